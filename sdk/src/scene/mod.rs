//! Scene state: geometry and instance registries, the BLAS build queue with its throttle,
//! BLAS compaction, the TLAS snapshot that working sets build from, and the instance table
//! shaders read per hit. It knows the cache only as the ranges its instances own.
pub(crate) mod blas;
pub(crate) mod geometry;
pub(crate) mod instance;
pub(crate) mod table;
pub(crate) mod tlas;

use crate::cache::pool::CacheRange;
use crate::types::handles::Registry;
use crate::types::{GeometryHandle, InstanceHandle};
use ash::vk;
use geometry::{BlasState, GeometryRecord};
use instance::{InstanceRecord, Placement};
use std::collections::VecDeque;

pub(crate) struct Scene {
    pub geometries: Registry<GeometryHandle, GeometryRecord>,
    pub instances: Registry<InstanceHandle, InstanceRecord>,
    /// Geometries waiting for a (re)build, oldest first. Entries of destroyed geometries are
    /// skipped when popped.
    pub build_queue: VecDeque<GeometryHandle>,
    /// Updated deformable geometries to refit at the next BVH build (not throttled: refits are
    /// cheap and a skinned mesh must follow its animation every frame).
    pub refit_queue: Vec<GeometryHandle>,
    /// Static BLASes whose compacted size came back; compacted at the next BVH build.
    pub compaction_ready: Vec<GeometryHandle>,
    /// TLAS records of every registered instance whose BLAS is ready.
    pub snapshot: Vec<vk::AccelerationStructureInstanceKHR>,
    pub snapshot_version: u64,
    /// The serial of the last recording whose TLAS or BLASes show the scene changed (instances
    /// moved, added or removed; geometry refit or rebuilt): the denoisers look for moving
    /// objects only shortly after it. 0: never.
    pub changed_at: u64,
    /// Something changed that the snapshot must follow (rebuilt before the next TLAS).
    pub snapshot_dirty: bool,
    /// Some instance may need a cache (new layout, new or moved instance).
    pub caches_dirty: bool,
    /// Source of surfel layout ids (an instance cache is made for one layout id).
    pub next_layout_id: u64,
    /// What the cache budget has evicted and what layouts read back, so far.
    pub cache_stats: CacheStats,
    /// Geometries whose GPU-built layout had too many samples: built again at the next
    /// recording with this (halved) resolution limit.
    pub relayout: Vec<(GeometryHandle, u32)>,
    /// `BuildHint::FastThenTrace` geometries built fast, to rebuild for fast trace after the
    /// build queue: (geometry, build id of the fast build; a newer one skips the entry).
    pub quality_queue: VecDeque<(GeometryHandle, u64)>,
}

/// Totals since the context was made (`CacheReport`): caches the budget evicted, and geometry
/// bytes copied to the host for the CPU layout builders.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct CacheStats {
    pub evictions: u64,
    pub evicted_bytes: u64,
    pub readback_bytes: u64,
}

impl Scene {
    pub fn new(context_id: u16) -> Scene {
        Scene {
            geometries: Registry::new(context_id),
            instances: Registry::new(context_id),
            build_queue: VecDeque::new(),
            refit_queue: Vec::new(),
            compaction_ready: Vec::new(),
            snapshot: Vec::new(),
            snapshot_version: 1,
            changed_at: 0,
            snapshot_dirty: false,
            caches_dirty: false,
            next_layout_id: 0,
            cache_stats: CacheStats::default(),
            relayout: Vec::new(),
            quality_queue: VecDeque::new(),
        }
    }

    /// Bookkeeping when an instance leaves the scene; returns the cache range it held, for the
    /// caller to free once the tickets that may use it are back.
    pub fn unplace(&mut self, placement: Option<Placement>) -> Option<CacheRange> {
        let p = placement?;
        if let Ok(g) = self.geometries.get_mut(p.geometry) {
            g.instance_refs = g.instance_refs.saturating_sub(1);
        }
        self.snapshot_dirty = true;
        p.cache.map(|(range, _)| range)
    }

    /// BLAS builds still queued (registered geometries not built yet, and rebuilds).
    pub fn pending_blas_builds(&self) -> usize {
        let quality = self.quality_queue.iter().filter(|(h, id)| self.geometries.get(*h).is_ok_and(|g| g.build_id == *id));
        self.build_queue.iter().filter(|h| self.geometries.get(**h).is_ok()).count() + quality.count()
    }

    pub fn rebuild_snapshot(&mut self) {
        let mut records = Vec::with_capacity(self.instances.len());
        for (h, rec) in self.instances.iter() {
            let Some(p) = rec.placement else { continue };
            let Ok(g) = self.geometries.get(p.geometry) else { continue };
            if let (BlasState::Ready, Some(b)) = (g.state, g.blas.as_ref()) {
                let index = self.instances.index_of(h).unwrap_or(0);
                records.push(instance::tlas_record(&p, index, b.address));
            }
        }
        self.snapshot = records;
        self.snapshot_version += 1;
        self.snapshot_dirty = false;
    }
}
