//! A build's journal: what one recording changed, so that a build that fails halfway (an
//! allocation, a Vulkan call) leaves the context exactly as it was — registries, queues, the
//! TLAS snapshot, caches and GPU objects — and the same container can be built again.
//!
//! Metadata is saved on first touch (a record's fields before the build changed them); GPU
//! objects are never destroyed or retired during a build: an object a build replaces waits in
//! the journal, and is retired when the build commits or put back (and the new one destroyed at
//! once — only the never-submitted command buffer refers to it) when it fails.
use super::State;
use crate::cache::layout::SurfelLayout;
use crate::cache::pool::CacheRange;
use crate::gpu::deferred::{self, Garbage};
use crate::gpu::device::Device;
use crate::gpu::memory::{Buffer, Memory};
use crate::gpu::upload::UploadRing;
use crate::scene::geometry::{Blas, GeometryMeta, SurfelGpu};
use crate::scene::instance::Placement;
use crate::types::{GeometryHandle, InstanceHandle};
use ash::vk;
use std::collections::{HashSet, VecDeque};

/// Where a replaced GPU object lived.
#[derive(Clone, Copy)]
pub(super) enum Slot {
    Copy(GeometryHandle),
    Blas(GeometryHandle),
    Surfel(GeometryHandle),
    Scratch,
    IndexCounters,
    Usage,
    UsageReadback,
    Ring,
    Tlas,
}

/// A GPU object held by the journal.
pub(super) enum Held {
    Buffer(Buffer),
    Accel(Blas),
    Surfel(SurfelGpu),
    Ring(UploadRing),
}

impl Held {
    /// Puts `old` (a buffer, or nothing) into `slot`; returns what was there.
    fn swap_buffer(slot: &mut Option<Buffer>, old: Option<Held>) -> Option<Held> {
        let old = old.and_then(|o| if let Held::Buffer(b) = o { Some(b) } else { None });
        std::mem::replace(slot, old).map(Held::Buffer)
    }

    fn swap_accel(slot: &mut Option<Blas>, old: Option<Held>) -> Option<Held> {
        let old = old.and_then(|o| if let Held::Accel(a) = o { Some(a) } else { None });
        std::mem::replace(slot, old).map(Held::Accel)
    }

    fn into_garbage(self) -> Garbage {
        match self {
            Held::Buffer(b) => Garbage::Buffer(b),
            Held::Accel(a) => Garbage::AccelerationStructure(a.accel, a.buffer),
            Held::Surfel(s) => Garbage::Buffer(s.buffer),
            Held::Ring(r) => Garbage::Buffer(r.buffer),
        }
    }
}

/// Scene-wide fields, saved when the build starts (the queues are short next to the scene).
struct SceneMeta {
    build_queue: VecDeque<GeometryHandle>,
    refit_queue: Vec<GeometryHandle>,
    compaction_ready: Vec<GeometryHandle>,
    snapshot_version: u64,
    changed_at: u64,
    snapshot_dirty: bool,
    caches_dirty: bool,
    next_layout_id: u64,
    cache_stats: crate::scene::CacheStats,
    relayout: Vec<(GeometryHandle, u32)>,
    quality_queue: VecDeque<(GeometryHandle, u64)>,
}

pub(super) struct Journal {
    scene: SceneMeta,
    /// The TLAS snapshot before the build rebuilt it.
    old_snapshot: Option<Vec<vk::AccelerationStructureInstanceKHR>>,
    geometries: Vec<(GeometryHandle, GeometryMeta)>,
    instances: Vec<(InstanceHandle, Option<Placement>)>,
    /// Which records are saved already (a linear search made a build of 60,000 instance
    /// registrations take seconds).
    touched_geometries: HashSet<GeometryHandle>,
    touched_instances: HashSet<InstanceHandle>,
    /// GPU objects the build replaced (None: the slot was empty), in order.
    replaced: Vec<(Slot, Option<Held>)>,
    /// Objects the build made and retires itself (staging): retired at commit, destroyed on
    /// failure.
    made_to_retire: Vec<Garbage>,
    /// Surfel layouts the build took for upload.
    pending_layouts: Vec<(GeometryHandle, SurfelLayout)>,
    cache_allocations: Vec<CacheRange>,
    pool_retired_len: usize,
    tlas_version: u64,
    tlas_refit: Option<crate::scene::tlas::Refit>,
}

impl Journal {
    pub fn begin(st: &State, ws: usize) -> Journal {
        let s = &st.scene;
        Journal {
            scene: SceneMeta {
                build_queue: s.build_queue.clone(),
                refit_queue: s.refit_queue.clone(),
                compaction_ready: s.compaction_ready.clone(),
                snapshot_version: s.snapshot_version,
                changed_at: s.changed_at,
                snapshot_dirty: s.snapshot_dirty,
                caches_dirty: s.caches_dirty,
                next_layout_id: s.next_layout_id,
                cache_stats: s.cache_stats,
                relayout: s.relayout.clone(),
                quality_queue: s.quality_queue.clone(),
            },
            old_snapshot: None,
            geometries: Vec::new(),
            instances: Vec::new(),
            touched_geometries: HashSet::new(),
            touched_instances: HashSet::new(),
            replaced: Vec::new(),
            made_to_retire: Vec::new(),
            pending_layouts: Vec::new(),
            cache_allocations: Vec::new(),
            pool_retired_len: st.cache_pool.retired_len(),
            tlas_version: st.working_sets[ws].tlas.version,
            tlas_refit: st.working_sets[ws].tlas.refit,
        }
    }

    pub fn touch_geometry(&mut self, h: GeometryHandle, meta: GeometryMeta) {
        if self.touched_geometries.insert(h) {
            self.geometries.push((h, meta));
        }
    }

    pub fn touch_instance(&mut self, h: InstanceHandle, placement: Option<Placement>) {
        if self.touched_instances.insert(h) {
            self.instances.push((h, placement));
        }
    }

    pub fn replaced(&mut self, slot: Slot, old: Option<Held>) {
        self.replaced.push((slot, old));
    }

    pub fn retire_at_commit(&mut self, g: Garbage) {
        self.made_to_retire.push(g);
    }

    pub fn took_layout(&mut self, h: GeometryHandle, layout: SurfelLayout) {
        self.pending_layouts.push((h, layout));
    }

    pub fn allocated_cache(&mut self, r: CacheRange) {
        self.cache_allocations.push(r);
    }

    pub fn saved_snapshot(&mut self, old: Vec<vk::AccelerationStructureInstanceKHR>) {
        self.old_snapshot.get_or_insert(old);
    }

    /// The build succeeded: what it replaced is retired after this ticket (`serial`).
    pub fn commit(self, st: &mut State, serial: u64) {
        for (_, old) in self.replaced {
            if let Some(old) = old {
                st.deferred.retire(serial, old.into_garbage());
            }
        }
        for g in self.made_to_retire {
            st.deferred.retire(serial, g);
        }
    }

    /// The build failed: everything goes back as it was before it began.
    pub fn roll_back(self, st: &mut State, ws: usize, device: &Device, memory: &Memory) {
        let destroy = |g: Garbage| deferred::destroy(device, memory, g);
        for (slot, old) in self.replaced.into_iter().rev() {
            let w = &mut st.working_sets[ws];
            let geometries = &mut st.scene.geometries;
            // Put the old object back; what the build had put there goes.
            let new = match slot {
                Slot::Copy(h) => geometries.get_mut(h).ok().and_then(|g| Held::swap_buffer(&mut g.copy, old)),
                Slot::Blas(h) => geometries.get_mut(h).ok().and_then(|g| Held::swap_accel(&mut g.blas, old)),
                Slot::Surfel(h) => geometries.get_mut(h).ok().and_then(|g| {
                    let old = old.and_then(|o| if let Held::Surfel(s) = o { Some(s) } else { None });
                    std::mem::replace(&mut g.surfel, old).map(Held::Surfel)
                }),
                Slot::Scratch => Held::swap_buffer(&mut w.scratch, old),
                Slot::IndexCounters => Held::swap_buffer(&mut w.index_counters, old),
                Slot::Usage => Held::swap_buffer(&mut w.usage, old),
                Slot::UsageReadback => Held::swap_buffer(&mut w.usage_readback, old),
                Slot::Tlas => Held::swap_accel(&mut w.tlas.accel, old),
                Slot::Ring => match old {
                    Some(Held::Ring(old)) => Some(Held::Ring(std::mem::replace(&mut w.ring, old))),
                    _ => None,
                },
            };
            if let Some(new) = new {
                destroy(new.into_garbage());
            }
        }
        for g in self.made_to_retire {
            destroy(g);
        }
        for (h, layout) in self.pending_layouts {
            if let Ok(g) = st.scene.geometries.get_mut(h) {
                g.pending_layout = Some(layout);
            }
        }
        for r in self.cache_allocations {
            st.cache_pool.free(r);
        }
        st.cache_pool.truncate_retired(self.pool_retired_len);
        for (h, meta) in self.geometries {
            if let Ok(g) = st.scene.geometries.get_mut(h) {
                g.restore(meta);
            }
        }
        for (h, placement) in self.instances {
            if let Ok(i) = st.scene.instances.get_mut(h) {
                i.placement = placement;
            }
        }
        let s = &mut st.scene;
        let m = self.scene;
        (s.build_queue, s.refit_queue, s.compaction_ready) = (m.build_queue, m.refit_queue, m.compaction_ready);
        (s.snapshot_version, s.snapshot_dirty, s.caches_dirty, s.next_layout_id, s.cache_stats) =
            (m.snapshot_version, m.snapshot_dirty, m.caches_dirty, m.next_layout_id, m.cache_stats);
        (s.relayout, s.quality_queue, s.changed_at) = (m.relayout, m.quality_queue, m.changed_at);
        if let Some(old) = self.old_snapshot {
            s.snapshot = old;
        }
        let w = &mut st.working_sets[ws];
        (w.tlas.version, w.tlas.refit) = (self.tlas_version, self.tlas_refit);
        // A working set is recorded only when idle, so these started empty.
        w.compactions.clear();
        w.index_checks.clear();
        w.usage_slots = 0;
        for r in w.readbacks.drain(..) {
            r.destroy(memory);
        }
    }
}
