//! `ExecuteContext`: the SDK's state for one engine device, and the engine that records task
//! containers. This layer is the only one that knows every other; nothing imports it.
//!
//! It never begins, ends, submits or waits on a command buffer and owns no queue: the engine
//! records our work into its own command buffer with `build_gpu_task`, submits it where it
//! likes and hands the ticket back when its fence says the GPU is done. Everything the GPU may
//! still use is freed only after the tickets that could use it have come back.
//!
//! The files split it by concern: `handles` (creating, destroying and querying handles),
//! `tickets` (build and completion), `record` (the order of one recording), `scene` (scene tasks
//! applied to the registries, and their handle checks), `bvh` (BLAS and TLAS work), `cache`
//! (surfel layouts and instance caches), `working_set` (what one ticket in flight owns),
//! `denoise` (denoising contexts), `container` and `validate` (scheduling).
pub(crate) mod container;
pub(crate) mod validate;

mod budget;
mod bvh;
mod cache;
mod denoise;
mod handles;
mod journal;
mod many_lights;
mod record;
mod scene;
mod tickets;
mod working_set;

use crate::cache::pool::CachePool;
use crate::error::{Error, Result};
use crate::gpu::deferred::{DeferredFrees, Garbage};
use crate::gpu::device::{Device, DeviceDesc};
use crate::gpu::memory::Memory;
use crate::passes::denoise::{DenoiserState, TempPool};
use crate::passes::denoise_guide::{Guide, GuideKey};
use crate::passes::Passes;
use crate::scene::geometry::GeometryRecord;
use crate::scene::instance::Placement;
use crate::scene::Scene;
use crate::types::handles::Registry;
use crate::types::*;
pub use container::TaskContainer;
use parking_lot::{Mutex, RwLock};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU16, Ordering};
use std::sync::Arc;
use working_set::WorkingSet;

static NEXT_CONTEXT_ID: AtomicU16 = AtomicU16::new(1);

/// The SDK context. `Send + Sync`: containers may be filled on many threads; builds are
/// serialised by one mutex.
pub struct ExecuteContext {
    shared: Arc<Shared>,
}

/// The context's id, device and tickets in flight (without waiting for a recording that holds
/// the state: then "busy").
impl std::fmt::Debug for ExecuteContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.shared;
        let mut d = f.debug_struct("ExecuteContext");
        d.field("id", &s.id).field("device", &s.device.device_name);
        match s.state.try_lock() {
            Some(st) => d.field("tickets_in_flight", &st.in_flight().count()),
            None => d.field("tickets_in_flight", &"busy"),
        };
        d.finish_non_exhaustive()
    }
}

/// What the context and its containers share (containers hold it weakly).
pub(crate) struct Shared {
    pub id: u16,
    pub device: Device,
    pub memory: Memory,
    state: Mutex<State>,
    /// The live handles, apart from `state`: scheduling checks them here and so never waits
    /// for a recording (or a ticket's completion) that holds the state lock. Written only
    /// where handles are created and destroyed, inside the state lock.
    live: RwLock<handles::Live>,
    warned_inline: AtomicBool,
    /// Set by `destroy_after_device_lost`: tickets still out will never finish, and nothing of
    /// theirs runs any more, so dropping frees everything instead of leaking it.
    device_lost: AtomicBool,
}

struct State {
    scene: Scene,
    cache_pool: CachePool,
    denoisers: Registry<DenoisingContextHandle, DenoiserState>,
    many_lights: Registry<ManyLightsContextHandle, crate::passes::many_lights::ManyLightsState>,
    /// The intermediates every denoising context shares (as large as the largest).
    denoise_temps: TempPool,
    /// The denoisers' guides: one per view, and one per context without a view.
    denoise_guides: HashMap<GuideKey, Guide>,
    /// Where `RelightCacheTask`'s walk over the caches goes on next build.
    relight_cursor: crate::passes::relight::RelightCursor,
    /// `InitSettings::cache_budget_bytes` (0: none).
    cache_budget: u64,
    working_sets: Vec<WorkingSet>,
    deferred: DeferredFrees,
    next_serial: u64,
    passes: Passes,
}

impl State {
    fn in_flight(&self) -> impl Iterator<Item = u64> + '_ {
        self.working_sets.iter().filter_map(|w| w.in_flight)
    }

    fn last_issued(&self) -> u64 {
        self.next_serial - 1
    }

    /// Frees deferred GPU objects and cache ranges that no in-flight ticket can still use.
    fn collect_garbage(&mut self, device: &Device, memory: &Memory) {
        let oldest = self.in_flight().min();
        self.deferred.collect(device, memory, oldest);
        self.cache_pool.collect(oldest);
    }

    /// An instance leaves the scene: its cache range is freed once the tickets that may touch
    /// it are back (the one being recorded, if any, included).
    fn unplace(&mut self, placement: Option<Placement>) {
        if let Some(range) = self.scene.unplace(placement) {
            self.cache_pool.free_after(self.next_serial, range);
        }
    }
}

impl ExecuteContext {
    /// Creates the context from the engine's device. Fails with
    /// `Error::MissingDeviceSupport` naming every missing extension, feature, device function
    /// and API version.
    ///
    /// # Safety
    /// The SDK cannot check what raw Vulkan handles are; as with ash, the caller guarantees:
    /// - `desc.instance`, `physical_device` and `device` are valid and belong together, and the
    ///   device was created with `desc.enabled_extensions` and the `desc.enabled_features`
    ///   chain (null, or valid for this call);
    /// - the device outlives the context, and is not destroyed while a ticket is in flight;
    /// - command buffers given to `build_gpu_task` belong to this device.
    pub unsafe fn new(desc: &DeviceDesc<'_>, settings: &InitSettings) -> Result<ExecuteContext> {
        if !(1..=16).contains(&settings.supported_working_sets) {
            return Err(Error::invalid("InitSettings.supported_working_sets", "must be in 1..=16"));
        }
        if settings.max_timed_tasks == 0 || settings.max_timed_tasks > 4096 {
            return Err(Error::invalid("InitSettings.max_timed_tasks", "must be in 1..=4096"));
        }
        // SAFETY: this function's contract is `Device::new`'s.
        let device = unsafe { Device::new(desc) }?;
        let max_buffer = device.limits.max_buffer_size;
        if settings.upload_ring_bytes > max_buffer {
            return Err(Error::invalid(
                "InitSettings.upload_ring_bytes",
                format!("{} exceeds the device's maxBufferSize {max_buffer}", settings.upload_ring_bytes),
            ));
        }
        let families = queue_families(desc, settings)?;
        let memory = Memory::new(desc.instance, desc.device, desc.physical_device, max_buffer, device.debug.clone(), families)?;
        let passes = match Passes::new(&device, &memory, settings.pipeline_cache) {
            Ok(p) => p,
            Err(e) => {
                memory.shutdown();
                return Err(e);
            }
        };
        let id = NEXT_CONTEXT_ID.fetch_add(1, Ordering::Relaxed).max(1);
        // From here on, partially created objects are released by Shared's Drop.
        let shared = Arc::new(Shared {
            id,
            device,
            memory,
            state: Mutex::new(State {
                scene: Scene::new(id),
                cache_pool: CachePool::default(),
                denoisers: Registry::new(id),
                many_lights: Registry::new(id),
                denoise_temps: TempPool::default(),
                denoise_guides: HashMap::new(),
                relight_cursor: Default::default(),
                cache_budget: settings.cache_budget_bytes,
                working_sets: Vec::new(),
                deferred: DeferredFrees::default(),
                next_serial: 1,
                passes,
            }),
            live: RwLock::new(handles::Live::default()),
            warned_inline: AtomicBool::new(false),
            device_lost: AtomicBool::new(false),
        });
        {
            let mut st = shared.state.lock();
            for _ in 0..settings.supported_working_sets {
                let ws = WorkingSet::new(&shared.device, &shared.memory, settings)?;
                st.working_sets.push(ws);
            }
        }
        log::info!(
            "hybrid-rt context on {} ({} working sets, ray queries {})",
            shared.device.device_name,
            settings.supported_working_sets,
            if shared.device.ray_query { "on" } else { "off" }
        );
        Ok(ExecuteContext { shared })
    }

    /// The device's name (`VkPhysicalDeviceProperties::deviceName`).
    pub fn device_name(&self) -> &str {
        &self.shared.device.device_name
    }

    /// Whether `use_inline_rt` takes effect on this device (VK_KHR_ray_query enabled).
    pub fn supports_inline_rt(&self) -> bool {
        self.shared.device.ray_query
    }

    /// Tickets in flight whose command buffers the GPU has not run to their end (by their
    /// completion markers): what must finish before the context may be destroyed.
    pub fn unfinished_tickets(&self) -> Vec<u64> {
        self.shared.unfinished_tickets()
    }

    /// Destroys the context, or refuses with `Error::TicketsInFlight` (and gives the context
    /// back) while the GPU may still run a ticket's commands. A ticket the GPU has finished but
    /// the engine never handed back does not hold it up.
    pub fn destroy(self) -> std::result::Result<(), (ExecuteContext, Error)> {
        let serials = self.unfinished_tickets();
        if !serials.is_empty() {
            return Err((self, Error::TicketsInFlight { serials }));
        }
        drop(self);
        Ok(())
    }

    /// Destroys the context after the engine's device was lost (`VK_ERROR_DEVICE_LOST`), when
    /// the tickets still out can never be handed back: every GPU object and all host memory
    /// of the SDK are freed at once, and nothing waits. (A lost device's command buffers are
    /// no longer pending, so destroying what they use is valid.) Destroy the context this way
    /// before the device; tickets the engine still holds are then meaningless.
    ///
    /// # Safety
    /// The device must be lost, or every command buffer holding one of this context's tickets
    /// must have finished or never be submitted: on a working device this frees memory that a
    /// running command buffer may still use.
    pub unsafe fn destroy_after_device_lost(self) {
        self.shared.device_lost.store(true, Ordering::Relaxed);
        drop(self);
    }

    /// A new, empty task container (`Send`: fill it on any thread).
    pub fn create_task_container(&self) -> TaskContainer {
        TaskContainer { shared: Arc::downgrade(&self.shared), tasks: Vec::new(), labels: Vec::new(), frame_index: None }
    }

    /// Bench only (cargo feature `bench-floor`): trace with empty hit/miss shaders (the
    /// bare-ray floor) — AO, shadows, diffuse and specular. The floor pipelines are built on
    /// first use.
    #[cfg(feature = "bench-floor")]
    pub fn set_bench_floor_mode(&self, on: bool) -> Result<()> {
        let mut st = self.shared.state.lock();
        if on {
            st.passes.ensure_floor(&self.shared.device, &self.shared.memory)?;
        }
        st.passes.floor = on;
        Ok(())
    }
}

/// Test hooks (cargo feature `fault-injection`): make an allocation fail, and print the state a
/// failed build must leave untouched.
#[cfg(feature = "fault-injection")]
impl ExecuteContext {
    /// The allocation after `after` more succeed fails with `Error::OutOfMemory` (None: none).
    #[doc(hidden)]
    pub fn inject_allocation_failure(&self, after: Option<u64>) {
        self.shared.memory.inject_failure(after);
    }

    /// Every piece of state a build may change — registries, queues, the TLAS snapshot, caches,
    /// GPU object handles, deferred frees, working sets, denoisers, memory counts — as text.
    #[doc(hidden)]
    pub fn debug_state_digest(&self) -> String {
        use std::fmt::Write;
        let st = self.shared.state.lock();
        let s = &st.scene;
        let mut out = String::new();
        for (h, g) in s.geometries.iter() {
            let _ = writeln!(
                out,
                "geometry {h:?} {:?} copy {:?} blas {:?} surfel {:?} pending {:?}",
                g.meta(),
                g.copy.as_ref().map(|b| b.raw),
                g.blas.as_ref().map(|b| b.accel),
                g.surfel.as_ref().map(|l| (l.buffer.raw, l.id, l.sample_count)),
                g.pending_layout.as_ref().map(|l| l.words.len()),
            );
        }
        for (h, i) in s.instances.iter() {
            let _ = writeln!(out, "instance {h:?} {:?}", i.placement);
        }
        let snapshot = crate::scene::instance::instance_bytes(&s.snapshot);
        let _ = writeln!(
            out,
            "queues {:?} {:?} {:?} snapshot {:?} v{} dirty {} caches {} layouts {}",
            s.build_queue,
            s.refit_queue,
            s.compaction_ready,
            snapshot,
            s.snapshot_version,
            s.snapshot_dirty,
            s.caches_dirty,
            s.next_layout_id
        );
        let _ = writeln!(out, "cache {}", st.cache_pool.digest());
        let _ = writeln!(out, "deferred {:?} next serial {}", st.deferred.serials(), st.next_serial);
        for w in &st.working_sets {
            let _ = writeln!(
                out,
                "working set {:?} ring {:?}/{} scratch {:?} tlas {:?} v{} {:?} compactions {} readbacks {}",
                w.in_flight,
                w.ring.buffer.raw,
                w.ring.capacity(),
                w.scratch.as_ref().map(|b| (b.raw, b.size)),
                w.tlas.accel.as_ref().map(|a| a.accel),
                w.tlas.version,
                w.tlas.refit,
                w.compactions.len(),
                w.readbacks.len()
            );
        }
        for (h, d) in st.denoisers.iter() {
            let _ = writeln!(out, "denoiser {h:?} {}", d.digest());
        }
        let mut guides: Vec<_> = st.denoise_guides.iter().map(|(k, g)| format!("guide {k:?} {}", g.digest())).collect();
        guides.sort();
        for g in guides {
            let _ = writeln!(out, "{g}");
        }
        let _ = writeln!(out, "memory {:?}", self.shared.memory.allocations());
        out
    }
}

/// The distinct queue families of `InitSettings::queue_family_indices`, each checked against
/// the device.
fn queue_families(desc: &DeviceDesc<'_>, settings: &InitSettings) -> Result<Vec<u32>> {
    let n = settings.queue_family_count as usize;
    if n > settings.queue_family_indices.len() {
        return Err(Error::invalid("InitSettings.queue_family_count", format!("{n} is not in 0..=4")));
    }
    // SAFETY: a plain query on the engine's physical device.
    let available = unsafe { desc.instance.get_physical_device_queue_family_properties(desc.physical_device) }.len() as u32;
    let mut families = Vec::new();
    for &f in &settings.queue_family_indices[..n] {
        if f >= available {
            return Err(Error::invalid(
                "InitSettings.queue_family_indices",
                format!("family {f}: the device has {available} queue families"),
            ));
        }
        if !families.contains(&f) {
            families.push(f);
        }
    }
    Ok(families)
}

/// Every GPU object of a geometry, retired after the tickets issued up to `serial`.
fn retire_geometry(deferred: &mut DeferredFrees, serial: u64, g: GeometryRecord) {
    if let Some(s) = g.surfel {
        deferred.retire(serial, Garbage::Buffer(s.buffer));
    }
    if let Some(c) = g.copy {
        deferred.retire(serial, Garbage::Buffer(c));
    }
    if let Some(b) = g.blas {
        deferred.retire(serial, Garbage::AccelerationStructure(b.accel, b.buffer));
    }
}

impl Shared {
    fn unfinished_tickets(&self) -> Vec<u64> {
        let st = self.state.lock();
        st.working_sets.iter().filter_map(|w| w.in_flight.filter(|&serial| !w.completed(serial))).collect()
    }
}

impl Drop for Shared {
    /// Frees everything — unless a ticket the GPU may still be running is out (dropped without
    /// `destroy`'s check): then the SDK's GPU objects and memory are leaked, with an error in
    /// the log, rather than freed under the GPU. Nothing here waits: the SDK owns no queue.
    fn drop(&mut self) {
        // After a declared device loss the tickets' completion markers are not read: the
        // device will never write them, and everything is freed either way.
        let unfinished = if self.device_lost.load(Ordering::Relaxed) { Vec::new() } else { self.unfinished_tickets() };
        if !unfinished.is_empty() {
            log::error!(
                "hybrid-rt context dropped with tickets {unfinished:?} still running on the GPU: leaking its GPU objects \
                 (wait for the tickets' fences and hand them back, or use ExecuteContext::destroy)"
            );
            self.memory.leak();
            return;
        }
        let st = self.state.get_mut();
        let (device, memory) = (&self.device, &self.memory);
        let geometries: Vec<GeometryHandle> = st.scene.geometries.iter().map(|(h, _)| h).collect();
        for h in geometries {
            if let Ok(g) = st.scene.geometries.remove(h) {
                retire_geometry(&mut st.deferred, 0, g);
            }
        }
        let denoisers: Vec<DenoisingContextHandle> = st.denoisers.iter().map(|(h, _)| h).collect();
        for h in denoisers {
            if let Ok(state) = st.denoisers.remove(h) {
                for image in state.into_images() {
                    st.deferred.retire(0, Garbage::Image(image));
                }
            }
        }
        for image in std::mem::take(&mut st.denoise_temps).into_images() {
            st.deferred.retire(0, Garbage::Image(image));
        }
        let many_lights: Vec<ManyLightsContextHandle> = st.many_lights.iter().map(|(h, _)| h).collect();
        for h in many_lights {
            if let Ok(state) = st.many_lights.remove(h) {
                for buffer in state.into_buffers() {
                    st.deferred.retire(0, Garbage::Buffer(buffer));
                }
            }
        }
        for (_, guide) in st.denoise_guides.drain() {
            for image in guide.into_images() {
                st.deferred.retire(0, Garbage::Image(image));
            }
        }
        st.deferred.collect(device, memory, None);
        for ws in st.working_sets.drain(..) {
            ws.destroy(device, memory);
        }
        st.passes.destroy(device, memory);
        st.cache_pool.destroy(memory);
        memory.shutdown();
    }
}
