//! Creating, destroying and querying geometry and instance handles, and the context-wide
//! reports (memory, tickets in flight).
use super::{retire_geometry, ExecuteContext, Shared};
use crate::error::{Error, HandleProblem, Result};
use crate::gpu::memory::ResourceAllocations;
use crate::scene::geometry::GeometryRecord;
use crate::scene::instance::InstanceRecord;
use crate::types::{GeometryHandle, InstanceHandle};
use std::collections::HashSet;

/// The raw values of every live handle, by kind (see `Shared::live`).
#[derive(Default)]
pub(crate) struct Live {
    pub geometries: HashSet<u64>,
    pub instances: HashSet<u64>,
    pub denoisers: HashSet<u64>,
    pub many_lights: HashSet<u64>,
}

/// Why `raw` is not a live handle of context `ctx`: null, foreign, or destroyed.
pub(crate) fn not_live(field: &'static str, kind: &'static str, raw: u64, ctx: u16) -> Error {
    let problem = if raw == 0 {
        HandleProblem::Null
    } else if crate::types::handles::context_of(raw) != ctx {
        HandleProblem::Foreign
    } else {
        HandleProblem::Destroyed
    };
    Error::InvalidHandle { field, kind, raw, problem, name: None }
}

impl ExecuteContext {
    /// `count` new geometry handles (not registered yet: schedule a `GeometryTask`).
    pub fn create_geometry_handles(&self, count: usize) -> Vec<GeometryHandle> {
        let mut st = self.shared.state.lock();
        let handles: Vec<GeometryHandle> = (0..count).map(|_| st.scene.geometries.insert(GeometryRecord::new())).collect();
        self.shared.live.write().geometries.extend(handles.iter().map(|h| h.0));
        handles
    }

    /// `count` new instance handles (not registered yet: schedule an `InstanceTask`).
    pub fn create_instance_handles(&self, count: usize) -> Vec<InstanceHandle> {
        let mut st = self.shared.state.lock();
        let handles: Vec<InstanceHandle> =
            (0..count).map(|_| st.scene.instances.insert(InstanceRecord { placement: None, name: None, last_used: 0 })).collect();
        self.shared.live.write().instances.extend(handles.iter().map(|h| h.0));
        handles
    }

    /// One new geometry handle (`create_geometry_handles(1)`'s).
    pub fn create_geometry_handle(&self) -> GeometryHandle {
        self.create_geometry_handles(1)[0]
    }

    /// One new instance handle (`create_instance_handles(1)`'s).
    pub fn create_instance_handle(&self) -> InstanceHandle {
        self.create_instance_handles(1)[0]
    }

    /// Destroys one geometry (`destroy_geometry_handles(&[handle])`).
    pub fn destroy_geometry_handle(&self, handle: GeometryHandle) -> Result<()> {
        self.destroy_geometry_handles(&[handle])
    }

    /// Destroys one instance (`destroy_instance_handles(&[handle])`).
    pub fn destroy_instance_handle(&self, handle: InstanceHandle) -> Result<()> {
        self.destroy_instance_handles(&[handle])
    }

    /// Destroys geometries. All-or-nothing: if any handle is invalid or still used by a
    /// registered instance, nothing is destroyed. GPU memory is freed once the tickets in
    /// flight now have come back.
    pub fn destroy_geometry_handles(&self, handles: &[GeometryHandle]) -> Result<()> {
        let mut guard = self.shared.state.lock();
        self.destroy_geometries(&mut guard, handles)
    }

    /// Destroys every geometry (level unload), all-or-nothing: `Error::GeometryInUse` while an
    /// instance still places one (destroy the instances first, e.g. with
    /// `destroy_all_instance_handles`). Kickstart RT's `DestroyAllGeometryHandles`.
    pub fn destroy_all_geometry_handles(&self) -> Result<()> {
        let mut guard = self.shared.state.lock();
        let all: Vec<GeometryHandle> = guard.scene.geometries.iter().map(|(h, _)| h).collect();
        self.destroy_geometries(&mut guard, &all)
    }

    fn destroy_geometries(&self, st: &mut super::State, handles: &[GeometryHandle]) -> Result<()> {
        for (i, h) in handles.iter().enumerate() {
            let g = st.scene.geometries.get(*h).map_err(|e| e.for_field("destroy_geometry_handles handles"))?;
            if g.instance_refs > 0 {
                return Err(Error::GeometryInUse { raw: h.0, instances: g.instance_refs });
            }
            if handles[..i].contains(h) {
                return Err(Error::InvalidHandle {
                    field: "destroy_geometry_handles handles (listed twice)",
                    kind: GeometryHandle::KIND,
                    raw: h.0,
                    problem: HandleProblem::Destroyed,
                    name: None,
                });
            }
        }
        let serial = st.last_issued();
        let mut live = self.shared.live.write();
        for h in handles {
            let g = st.scene.geometries.remove(*h)?;
            live.geometries.remove(&h.0);
            retire_geometry(&mut st.deferred, serial, g);
        }
        Ok(())
    }

    /// Destroys instances (all-or-nothing). They leave the TLAS at the next build.
    pub fn destroy_instance_handles(&self, handles: &[InstanceHandle]) -> Result<()> {
        let mut st = self.shared.state.lock();
        for (i, h) in handles.iter().enumerate() {
            st.scene.instances.check(*h).map_err(|e| e.for_field("destroy_instance_handles handles"))?;
            if handles[..i].contains(h) {
                return Err(Error::InvalidHandle {
                    field: "destroy_instance_handles handles (listed twice)",
                    kind: InstanceHandle::KIND,
                    raw: h.0,
                    problem: HandleProblem::Destroyed,
                    name: None,
                });
            }
        }
        let mut live = self.shared.live.write();
        for h in handles {
            let rec = st.scene.instances.remove(*h)?;
            live.instances.remove(&h.0);
            st.unplace(rec.placement);
        }
        Ok(())
    }

    /// Destroys every instance (level unload).
    pub fn destroy_all_instance_handles(&self) {
        let mut st = self.shared.state.lock();
        let all: Vec<InstanceHandle> = st.scene.instances.iter().map(|(h, _)| h).collect();
        self.shared.live.write().instances.clear();
        for h in all {
            if let Ok(rec) = st.scene.instances.remove(h) {
                st.unplace(rec.placement);
            }
        }
    }

    /// BLAS builds waiting for a `BvhBuildTask` (registered geometries not built yet, and
    /// rebuilds of updated static geometries).
    pub fn pending_blas_builds(&self) -> usize {
        self.shared.state.lock().scene.pending_blas_builds()
    }

    /// Triangles of the geometry's last registered or updated data whose indices went past its
    /// vertex count. The SDK makes them degenerate (they are in no BLAS and no cache), so the
    /// driver never sees the bad index, and logs a warning; 0 until the ticket that copied the
    /// data has come back.
    pub fn geometry_invalid_triangles(&self, geometry: GeometryHandle) -> Result<u32> {
        Ok(self
            .shared
            .state
            .lock()
            .scene
            .geometries
            .get(geometry)
            .map_err(|e| e.for_field("geometry_invalid_triangles geometry"))?
            .invalid_triangles)
    }

    /// Gives a geometry a debug name: errors about it and the SDK's log messages quote it, and
    /// with VK_EXT_debug_utils its BLAS and copy are named after it (`hybrid-rt BLAS <name>`)
    /// in RenderDoc, Nsight and validation messages. Kickstart RT's `GeometryInput::name`.
    pub fn set_geometry_name(&self, geometry: GeometryHandle, name: &str) -> Result<()> {
        let mut st = self.shared.state.lock();
        let g = st.scene.geometries.get_mut(geometry).map_err(|e| e.for_field("set_geometry_name geometry"))?;
        g.name = Some(name.to_string());
        let d = &self.shared.device;
        if let Some(b) = &g.blas {
            d.name(b.accel, &format!("BLAS {name}"));
        }
        if let Some(c) = &g.copy {
            d.name(c.raw, &format!("geometry copy {name}"));
        }
        Ok(())
    }

    /// Gives an instance a debug name, quoted in errors and log messages about it.
    pub fn set_instance_name(&self, instance: InstanceHandle, name: &str) -> Result<()> {
        self.shared.state.lock().scene.instances.get_mut(instance).map_err(|e| e.for_field("set_instance_name instance"))?.name =
            Some(name.to_string());
        Ok(())
    }

    /// Instances in the TLAS as of the last build.
    pub fn tlas_instance_count(&self) -> usize {
        self.shared.state.lock().scene.snapshot.len()
    }

    /// Bytes of the instance's direct-lighting cache (0 until its layout has come back and the
    /// cache is allocated: one recording after the ticket that registered its geometry).
    pub fn instance_cache_bytes(&self, instance: InstanceHandle) -> Result<u64> {
        let st = self.shared.state.lock();
        let rec = st.scene.instances.get(instance).map_err(|e| e.for_field("instance_cache_bytes instance"))?;
        Ok(rec.placement.and_then(|p| p.cache).map_or(0, |(r, _)| r.count * crate::cache::pool::SAMPLE_BYTES))
    }

    /// The direct-lighting caches' memory: what is resident, what waits for room and what the
    /// budget (`InitSettings::cache_budget_bytes`) has evicted.
    pub fn cache_report(&self) -> crate::types::CacheReport {
        let st = self.shared.state.lock();
        let r = st.residency();
        crate::types::CacheReport {
            resident_bytes: r.resident_bytes,
            budget_bytes: st.cache_budget,
            waiting_instances: r.waiting,
            evictions: st.scene.cache_stats.evictions,
            evicted_bytes: st.scene.cache_stats.evicted_bytes,
            geometry_readback_bytes: st.scene.cache_stats.readback_bytes,
        }
    }

    /// Device memory the SDK holds now, per kind.
    pub fn resource_allocations(&self) -> ResourceAllocations {
        self.shared.memory.allocations()
    }

    /// Starts a log of every device-memory allocation and free the SDK makes, as CSV lines
    /// written to `out` (buffered):
    ///
    /// `time_ms,event,kind,name,bytes,kind_live_bytes` — milliseconds since the log began,
    /// `alloc` or `free`, the [`MemoryKind`](crate::MemoryKind), what the memory holds, its
    /// bytes, and the bytes of that kind live afterwards (`resource_allocations`' numbers).
    ///
    /// One log at a time: a second begin is `InvalidInput`. A write error stops the log, and
    /// `end_logging_resource_allocations` reports it.
    ///
    /// ```no_run
    /// # fn f(ctx: &hybrid_rt::ExecuteContext) -> Result<(), Box<dyn std::error::Error>> {
    /// ctx.begin_logging_resource_allocations(std::fs::File::create("allocations.csv")?)?;
    /// // ... load a level ...
    /// ctx.end_logging_resource_allocations()?;
    /// # Ok(()) }
    /// ```
    pub fn begin_logging_resource_allocations(&self, out: impl std::io::Write + Send + 'static) -> Result<()> {
        if self.shared.memory.begin_log(Box::new(out)) {
            Ok(())
        } else {
            Err(Error::invalid("begin_logging_resource_allocations", "a log is open already: end it first"))
        }
    }

    /// Ends the allocation log: flushes it and hands its writer back. With no log open, or
    /// when writing it failed (the error says how), `InvalidInput`.
    pub fn end_logging_resource_allocations(&self) -> Result<Box<dyn std::io::Write + Send>> {
        let what = "end_logging_resource_allocations";
        match self.shared.memory.end_log() {
            None => Err(Error::invalid(what, "no log is open")),
            Some(Err(e)) => Err(Error::invalid(what, format!("writing the log failed: {e}"))),
            Some(Ok(out)) => Ok(out),
        }
    }

    /// Tickets built and not yet handed back.
    pub fn tickets_in_flight(&self) -> Vec<u64> {
        self.shared.state.lock().in_flight().collect()
    }

    /// Frees every deferred GPU resource now, and gives back cache pages no instance uses. Only
    /// when no ticket is in flight (a level load after the engine waited for its queue idle):
    /// otherwise `Error::TicketsInFlight`.
    pub fn release_device_resources_immediately(&self) -> Result<()> {
        let mut st = self.shared.state.lock();
        let serials: Vec<u64> = st.in_flight().collect();
        if !serials.is_empty() {
            return Err(Error::TicketsInFlight { serials });
        }
        st.collect_garbage(&self.shared.device, &self.shared.memory);
        st.cache_pool.trim(&self.shared.memory);
        Ok(())
    }
}

impl Shared {
    /// `h` is a live geometry; `field` names where the engine put it.
    pub(crate) fn check_geometry_alive(&self, h: GeometryHandle, field: &'static str) -> Result<()> {
        if self.live.read().geometries.contains(&h.0) {
            return Ok(());
        }
        Err(not_live(field, GeometryHandle::KIND, h.0, self.id))
    }

    /// `h` is a live instance; `field` names where the engine put it.
    pub(crate) fn check_instance_alive(&self, h: InstanceHandle, field: &'static str) -> Result<()> {
        if self.live.read().instances.contains(&h.0) {
            return Ok(());
        }
        Err(not_live(field, InstanceHandle::KIND, h.0, self.id))
    }
}
