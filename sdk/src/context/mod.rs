//! `ExecuteContext`: the SDK's state for one engine device.
//!
//! It never begins, ends, submits or waits on a command buffer and owns no queue: the engine
//! records our work into its own command buffer with `build_gpu_task`, submits it where it
//! likes and hands the ticket back when its fence says the GPU is done. Everything the GPU may
//! still use is freed only after the tickets that could use it have come back.
pub(crate) mod container;
pub(crate) mod validate;
use crate::cache::pool::{CachePool, CacheRange};
use crate::error::{Error, HandleProblem, Result};
use crate::gpu::deferred::{self, DeferredFrees, Garbage};
use crate::gpu::device::{Device, DeviceDesc};
use crate::gpu::memory::{self, Buffer, Memory, MemoryKind, ResourceAllocations};
use crate::gpu::sync::{self, Hazards};
use crate::gpu::timestamps::Timer;
use crate::gpu::upload::UploadRing;
use crate::passes::{self, ao::AoPass, Recording};
use crate::passes::{
    cache_ops::CacheOps,
    debug::DebugPass,
    diffuse::DiffusePass,
    inject::InjectPass,
    shadow::{MultiShadowPass, ShadowPass},
    specular::SpecularPass,
    transfer::TransferPass,
};
use crate::scene::blas::{self, BuildJob};
use crate::scene::geometry::{self, BlasState, GeometryLayout, GeometryRecord};
use crate::scene::instance::{self, InstanceRecord, Placement};
use crate::scene::tlas::{self, Tlas};
use crate::types::handles::Registry;
use crate::types::*;
use ash::vk;
use container::{Task, TaskContainer};
use gpu_allocator::MemoryLocation;
use parking_lot::Mutex;

mod cache;
mod denoise;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU16, Ordering};
use std::sync::Arc;

static NEXT_CONTEXT_ID: AtomicU16 = AtomicU16::new(1);

/// The SDK context. `Send + Sync`: containers may be filled on many threads; builds are
/// serialised by one mutex.
pub struct ExecuteContext {
    shared: Arc<Shared>,
}

pub(crate) struct Shared {
    pub id: u16,
    pub device: Device,
    pub memory: Memory,
    state: Mutex<State>,
    bench_floor: AtomicBool,
    warned_inline: AtomicBool,
}

struct WorkingSet {
    in_flight: Option<u64>,
    ring: UploadRing,
    scratch: Option<Buffer>,
    timer: Timer,
    compaction_pool: vk::QueryPool,
    compaction_slots: u32,
    compactions: Vec<(GeometryHandle, u64)>,
    /// Geometry copies read back for their surfel layouts: (geometry, build id, buffer).
    readbacks: Vec<(GeometryHandle, u64, Buffer)>,
    tlas: Tlas,
}

struct State {
    geometries: Registry<GeometryHandle, GeometryRecord>,
    instances: Registry<InstanceHandle, InstanceRecord>,
    /// Geometries waiting for a (re)build, oldest first. Entries of destroyed geometries are
    /// skipped when popped.
    build_queue: VecDeque<GeometryHandle>,
    /// Updated deformable geometries to refit at the next BVH build (not throttled: refits are
    /// cheap and a skinned mesh must follow its animation every frame).
    refit_queue: Vec<GeometryHandle>,
    /// Static BLASes whose compacted size came back; compacted at the next BVH build.
    compaction_ready: Vec<GeometryHandle>,
    /// TLAS records of every registered instance whose BLAS is ready.
    snapshot: Vec<vk::AccelerationStructureInstanceKHR>,
    snapshot_version: u64,
    snapshot_dirty: bool,
    working_sets: Vec<WorkingSet>,
    deferred: DeferredFrees,
    next_serial: u64,
    ao: Option<AoPass>,
    debug: Option<DebugPass>,
    inject: Option<InjectPass>,
    transfer: Option<TransferPass>,
    shadow: Option<ShadowPass>,
    diffuse: Option<DiffusePass>,
    specular: Option<SpecularPass>,
    multi_shadow: Option<MultiShadowPass>,
    denoise: Option<crate::passes::denoise::DenoisePass>,
    denoisers: Registry<DenoisingContextHandle, crate::passes::denoise::DenoiserState>,
    cache_ops: Option<CacheOps>,
    cache_pool: CachePool,
    /// Cache ranges of destroyed/changed instances: (newest serial issued then, range).
    cache_frees: Vec<(u64, CacheRange)>,
    /// Some instance may need a cache (new layout, new or moved instance).
    caches_dirty: bool,
    next_layout_id: u64,
    sampler: vk::Sampler,
}

impl State {
    fn in_flight(&self) -> impl Iterator<Item = u64> + '_ {
        self.working_sets.iter().filter_map(|w| w.in_flight)
    }
    fn last_issued(&self) -> u64 {
        self.next_serial - 1
    }
}

impl ExecuteContext {
    /// Creates the context from the engine's device. Fails with
    /// `Error::MissingDeviceSupport` naming every missing extension or feature.
    pub fn new(desc: &DeviceDesc<'_>, settings: &InitSettings) -> Result<ExecuteContext> {
        if !(1..=16).contains(&settings.supported_working_sets) {
            return Err(Error::invalid("InitSettings.supported_working_sets", "must be in 1..=16"));
        }
        if settings.max_timed_tasks == 0 || settings.max_timed_tasks > 4096 {
            return Err(Error::invalid("InitSettings.max_timed_tasks", "must be in 1..=4096"));
        }
        let device = Device::new(desc)?;
        let memory = Memory::new(desc.instance, desc.device, desc.physical_device)?;
        let id = NEXT_CONTEXT_ID.fetch_add(1, Ordering::Relaxed).max(1);
        // From here on, partially created objects are released by State's Drop via Shared.
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        let sampler = unsafe { device.raw.create_sampler(&sampler_info, None) }.map_err(Error::vk("vkCreateSampler"))?;
        let shared = Arc::new(Shared {
            id,
            device,
            memory,
            state: Mutex::new(State {
                geometries: Registry::new(id),
                instances: Registry::new(id),
                build_queue: VecDeque::new(),
                refit_queue: Vec::new(),
                compaction_ready: Vec::new(),
                snapshot: Vec::new(),
                snapshot_version: 1,
                snapshot_dirty: false,
                working_sets: Vec::new(),
                deferred: DeferredFrees::default(),
                next_serial: 1,
                ao: None,
                debug: None,
                inject: None,
                transfer: None,
                shadow: None,
                diffuse: None,
                specular: None,
                multi_shadow: None,
                denoise: None,
                denoisers: Registry::new(id),
                cache_ops: None,
                cache_pool: CachePool::default(),
                cache_frees: Vec::new(),
                caches_dirty: false,
                next_layout_id: 0,
                sampler,
            }),
            bench_floor: AtomicBool::new(false),
            warned_inline: AtomicBool::new(false),
        });
        {
            let mut st = shared.state.lock();
            st.ao = Some(AoPass::new(&shared.device, &shared.memory, sampler)?);
            st.debug = Some(DebugPass::new(&shared.device, &shared.memory)?);
            st.inject = Some(InjectPass::new(&shared.device, &shared.memory, sampler)?);
            st.transfer = Some(TransferPass::new(&shared.device, &shared.memory)?);
            st.shadow = Some(ShadowPass::new(&shared.device, &shared.memory, sampler)?);
            st.diffuse = Some(DiffusePass::new(&shared.device, &shared.memory, sampler)?);
            st.specular = Some(SpecularPass::new(&shared.device, &shared.memory, sampler)?);
            st.multi_shadow = Some(MultiShadowPass::new(&shared.device, &shared.memory, sampler)?);
            st.cache_ops = Some(CacheOps::new(&shared.device)?);
            st.denoise = Some(crate::passes::denoise::DenoisePass::new(&shared.device, sampler)?);
            for _ in 0..settings.supported_working_sets {
                let ws = shared.new_working_set(settings)?;
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

    pub fn device_name(&self) -> &str {
        &self.shared.device.device_name
    }

    /// Whether `use_inline_rt` takes effect on this device (VK_KHR_ray_query enabled).
    pub fn supports_inline_rt(&self) -> bool {
        self.shared.device.ray_query
    }

    pub fn create_geometry_handles(&self, count: usize) -> Vec<GeometryHandle> {
        let mut st = self.shared.state.lock();
        (0..count).map(|_| st.geometries.insert(GeometryRecord::new())).collect()
    }

    pub fn create_instance_handles(&self, count: usize) -> Vec<InstanceHandle> {
        let mut st = self.shared.state.lock();
        (0..count).map(|_| st.instances.insert(InstanceRecord { placement: None })).collect()
    }

    /// Destroys geometries. All-or-nothing: if any handle is invalid or still used by a
    /// registered instance, nothing is destroyed. GPU memory is freed once the tickets in
    /// flight now have come back.
    pub fn destroy_geometry_handles(&self, handles: &[GeometryHandle]) -> Result<()> {
        let mut st = self.shared.state.lock();
        for (i, h) in handles.iter().enumerate() {
            let g = st.geometries.get(*h)?;
            if g.instance_refs > 0 {
                return Err(Error::GeometryInUse { raw: h.0, instances: g.instance_refs });
            }
            if handles[..i].contains(h) {
                return Err(Error::InvalidHandle { kind: GeometryHandle::KIND, raw: h.0, problem: HandleProblem::Destroyed });
            }
        }
        let serial = st.last_issued();
        for h in handles {
            let g = st.geometries.remove(*h)?;
            retire_geometry(&mut st.deferred, serial, g);
        }
        Ok(())
    }

    /// Destroys instances (all-or-nothing). They leave the TLAS at the next build.
    pub fn destroy_instance_handles(&self, handles: &[InstanceHandle]) -> Result<()> {
        let mut st = self.shared.state.lock();
        for (i, h) in handles.iter().enumerate() {
            st.instances.check(*h)?;
            if handles[..i].contains(h) {
                return Err(Error::InvalidHandle { kind: InstanceHandle::KIND, raw: h.0, problem: HandleProblem::Destroyed });
            }
        }
        for h in handles {
            let rec = st.instances.remove(*h)?;
            st.unplace(rec.placement);
        }
        Ok(())
    }

    /// Destroys every instance (level unload).
    pub fn destroy_all_instance_handles(&self) {
        let mut st = self.shared.state.lock();
        let all: Vec<InstanceHandle> = st.instances.iter().map(|(h, _)| h).collect();
        for h in all {
            if let Ok(rec) = st.instances.remove(h) {
                st.unplace(rec.placement);
            }
        }
    }

    pub fn create_task_container(&self) -> TaskContainer {
        TaskContainer { shared: Arc::downgrade(&self.shared), tasks: Vec::new() }
    }

    /// BLAS builds waiting for a `BvhBuildTask` (registered geometries not built yet, and
    /// rebuilds of updated static geometries).
    pub fn pending_blas_builds(&self) -> usize {
        let st = self.shared.state.lock();
        st.build_queue.iter().filter(|h| st.geometries.get(**h).is_ok()).count()
    }

    /// Instances in the TLAS as of the last build.
    pub fn tlas_instance_count(&self) -> usize {
        self.shared.state.lock().snapshot.len()
    }

    /// Bytes of the instance's direct-lighting cache (0 until its layout has come back and the
    /// cache is allocated: one recording after the ticket that registered its geometry).
    pub fn instance_cache_bytes(&self, instance: InstanceHandle) -> Result<u64> {
        let st = self.shared.state.lock();
        let rec = st.instances.get(instance)?;
        Ok(rec.placement.and_then(|p| p.cache).map_or(0, |(r, _)| r.count * crate::cache::pool::SAMPLE_BYTES))
    }

    pub fn resource_allocations(&self) -> ResourceAllocations {
        self.shared.memory.allocations()
    }

    /// Tickets built and not yet handed back.
    pub fn tickets_in_flight(&self) -> Vec<u64> {
        self.shared.state.lock().in_flight().collect()
    }

    /// Frees every deferred GPU resource now. Only when no ticket is in flight (a level load
    /// after the engine waited for its queue idle): otherwise `Error::TicketsInFlight`.
    pub fn release_device_resources_immediately(&self) -> Result<()> {
        let mut st = self.shared.state.lock();
        let serials: Vec<u64> = st.in_flight().collect();
        if !serials.is_empty() {
            return Err(Error::TicketsInFlight { serials });
        }
        let st = &mut *st;
        st.collect_garbage(&self.shared.device, &self.shared.memory);
        Ok(())
    }

    /// Bench only: trace with empty hit/miss shaders (the bare-ray floor) — AO, shadows,
    /// diffuse and specular. The floor pipelines are built on first use.
    #[doc(hidden)]
    pub fn set_bench_floor_mode(&self, on: bool) -> Result<()> {
        if on {
            let mut st = self.shared.state.lock();
            let (d, m) = (&self.shared.device, &self.shared.memory);
            if let Some(p) = st.shadow.as_mut() {
                p.program_mut().ensure_floor(d, m)?;
            }
            if let Some(p) = st.multi_shadow.as_mut() {
                p.program_mut().ensure_floor(d, m)?;
            }
            if let Some(p) = st.diffuse.as_mut() {
                p.program_mut().ensure_floor(d, m)?;
            }
            if let Some(p) = st.specular.as_mut() {
                p.program_mut().ensure_floor(d, m)?;
            }
        }
        self.shared.bench_floor.store(on, Ordering::Relaxed);
        Ok(())
    }

    /// Records every task of `container` into `cmd`, which the engine has begun and will end,
    /// submit and wait for itself. On success the container is emptied and a ticket returned.
    /// On error nothing usable was recorded, no state changed, and the container keeps its
    /// tasks. (A Vulkan error in the middle of recording leaves `cmd` partly recorded: reset
    /// it.)
    pub fn build_gpu_task(&self, container: &mut TaskContainer, cmd: vk::CommandBuffer) -> Result<GpuTicket> {
        if !std::ptr::eq(container.shared.as_ptr(), Arc::as_ptr(&self.shared)) {
            return Err(Error::ForeignContainer);
        }
        if cmd == vk::CommandBuffer::null() {
            return Err(Error::invalid("build_gpu_task command buffer", "is null"));
        }
        let mut guard = self.shared.state.lock();
        let st = &mut *guard;
        let ws_index = st
            .working_sets
            .iter()
            .position(|w| w.in_flight.is_none())
            .ok_or(Error::WorkingSetsExhausted { in_flight: st.working_sets.len() as u32 })?;
        validate_handles(st, &container.tasks)?;
        st.collect_garbage(&self.shared.device, &self.shared.memory);

        let serial = st.next_serial;
        self.shared.record(st, ws_index, serial, &container.tasks, cmd)?;
        st.next_serial += 1;
        st.working_sets[ws_index].in_flight = Some(serial);
        container.tasks.clear();
        Ok(GpuTicket { ctx: self.shared.id, serial })
    }

    /// Hands a ticket back once the GPU has finished its command buffer: returns its working
    /// set to the pool, frees what only it still used, and reports per-task GPU times.
    pub fn mark_gpu_task_completed(&self, ticket: GpuTicket) -> Result<CompletedTask> {
        let mut guard = self.shared.state.lock();
        let st = &mut *guard;
        let unknown = Error::UnknownTicket { serial: ticket.serial };
        if ticket.ctx != self.shared.id {
            return Err(unknown);
        }
        let ws_index = st.working_sets.iter().position(|w| w.in_flight == Some(ticket.serial)).ok_or(unknown)?;
        let d = &self.shared.device;
        let ws = &mut st.working_sets[ws_index];
        let mut done = CompletedTask { serial: ticket.serial, timings: Vec::new() };
        if let Some(period) = d.timestamp_period_ns {
            match ws.timer.read(&d.raw, period) {
                Ok(t) => done.timings = t,
                Err(e) => log::warn!("ticket {}: timestamps unavailable ({e:?}); was it really complete?", ticket.serial),
            }
        }
        if !ws.compactions.is_empty() {
            let mut sizes = vec![0u64; ws.compactions.len()];
            let r = unsafe { d.raw.get_query_pool_results(ws.compaction_pool, 0, &mut sizes, vk::QueryResultFlags::TYPE_64) };
            let compactions = std::mem::take(&mut ws.compactions);
            if r.is_ok() {
                for ((h, build_id), size) in compactions.into_iter().zip(sizes) {
                    if let Ok(g) = st.geometries.get_mut(h) {
                        if g.build_id == build_id && size > 0 {
                            g.compacted_size = Some(size);
                            st.compaction_ready.push(h);
                        }
                    }
                }
            }
        }
        self.shared.finish_readbacks(st, ws_index);
        st.working_sets[ws_index].in_flight = None;
        st.collect_garbage(d, &self.shared.memory);
        Ok(done)
    }
}

/// Checks handle states in task order (a register earlier in the container counts), before
/// anything is recorded.
fn validate_handles(st: &State, tasks: &[Task]) -> Result<()> {
    use std::collections::HashMap;
    let mut geometry_registered: HashMap<GeometryHandle, bool> = HashMap::new();
    let mut instance_registered: HashMap<InstanceHandle, bool> = HashMap::new();
    let problem = |kind, raw, problem| Err(Error::InvalidHandle { kind, raw, problem });
    for task in tasks {
        match task {
            Task::Geometry(t) => {
                let g = st.geometries.get(t.handle)?;
                let registered = *geometry_registered.entry(t.handle).or_insert(g.registered());
                match t.operation {
                    TaskOperation::Register if registered => {
                        return problem(GeometryHandle::KIND, t.handle.0, HandleProblem::AlreadyRegistered)
                    }
                    TaskOperation::Update if !registered => {
                        return problem(GeometryHandle::KIND, t.handle.0, HandleProblem::NotRegistered)
                    }
                    TaskOperation::Update => {
                        if let Some(old) = g.layout.filter(|l| l.allow_update) {
                            let new = GeometryLayout::of(&t.input);
                            if !t.input.allow_update
                                || new.primitive_count != old.primitive_count
                                || new.vertex_count != old.vertex_count
                                || new.index_type != old.index_type
                            {
                                return Err(Error::invalid(
                                    "GeometryTask.input",
                                    "an update of an allow_update geometry must keep allow_update and its vertex, index and triangle counts (the BLAS is refitted)",
                                ));
                            }
                        }
                    }
                    _ => {}
                }
                geometry_registered.insert(t.handle, true);
            }
            Task::Instance(t) => {
                let rec = st.instances.get(t.handle)?;
                let registered = *instance_registered.entry(t.handle).or_insert(rec.placement.is_some());
                match t.operation {
                    InstanceOperation::Register if registered => {
                        return problem(InstanceHandle::KIND, t.handle.0, HandleProblem::AlreadyRegistered)
                    }
                    InstanceOperation::Update | InstanceOperation::Remove if !registered => {
                        return problem(InstanceHandle::KIND, t.handle.0, HandleProblem::NotRegistered)
                    }
                    _ => {}
                }
                if t.operation != InstanceOperation::Remove {
                    let g = st.geometries.get(t.input.geometry)?;
                    if !*geometry_registered.get(&t.input.geometry).unwrap_or(&g.registered()) {
                        return problem(GeometryHandle::KIND, t.input.geometry.0, HandleProblem::NotRegistered);
                    }
                }
                instance_registered.insert(t.handle, t.operation != InstanceOperation::Remove);
            }
            Task::ClearCache(t) => {
                st.instances.get(t.instance)?;
            }
            Task::DirectLightTransfer(t) => {
                st.instances.get(t.source)?;
                st.instances.get(t.target)?;
            }
            Task::Denoise(j) => denoise::check_job(&st.denoisers, j)?,
            Task::BvhBuild(_)
            | Task::AmbientOcclusion(_)
            | Task::DirectLightingInjection(_)
            | Task::Shadow(_)
            | Task::Diffuse(_)
            | Task::Specular(_)
            | Task::MultiShadow(_) => {}
        }
    }
    Ok(())
}

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

impl State {
    /// Bookkeeping when an instance leaves the scene.
    fn unplace(&mut self, placement: Option<Placement>) {
        if let Some((range, _)) = placement.and_then(|p| p.cache) {
            self.free_cache(range);
        }
        if let Some(p) = placement {
            if let Ok(g) = self.geometries.get_mut(p.geometry) {
                g.instance_refs = g.instance_refs.saturating_sub(1);
            }
            self.snapshot_dirty = true;
        }
    }

    fn rebuild_snapshot(&mut self) {
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

impl Shared {
    pub(crate) fn check_geometry_alive(&self, h: GeometryHandle) -> Result<()> {
        self.state.lock().geometries.check(h).map(|_| ())
    }

    pub(crate) fn check_instance_alive(&self, h: InstanceHandle) -> Result<()> {
        self.state.lock().instances.check(h).map(|_| ())
    }

    fn new_working_set(&self, settings: &InitSettings) -> Result<WorkingSet> {
        let d = &self.device.raw;
        // Two slots per timed task plus the nested BLAS/TLAS intervals of the BVH work.
        let timer = Timer::new(d, settings.max_timed_tasks * 2 + 4, self.device.timestamp_period_ns.is_some())?;
        let ring = match UploadRing::new(&self.memory, settings.upload_ring_bytes.max(4096)) {
            Ok(r) => r,
            Err(e) => {
                timer.destroy(d);
                return Err(e);
            }
        };
        Ok(WorkingSet {
            in_flight: None,
            ring,
            scratch: None,
            timer,
            compaction_pool: vk::QueryPool::null(),
            compaction_slots: 0,
            compactions: Vec::new(),
            readbacks: Vec::new(),
            tlas: Tlas { accel: None, version: 0 },
        })
    }

    /// Records one container. Handles were validated; errors here are Vulkan/memory failures.
    fn record(&self, st: &mut State, ws_index: usize, serial: u64, tasks: &[Task], cmd: vk::CommandBuffer) -> Result<()> {
        let device = &self.device;
        let d = &device.raw;
        let mut hazards = Hazards::after_earlier_submissions();
        st.working_sets[ws_index].ring.reset();
        st.working_sets[ws_index].timer.reset(d, cmd);
        fn timer(st: &mut State, ws: usize) -> &mut Timer {
            &mut st.working_sets[ws].timer
        }

        // ---- BVH work: copies, builds, refits, compactions, TLAS.
        let first_bvh =
            tasks.iter().position(|t| matches!(t, Task::Geometry(_) | Task::Instance(_) | Task::BvhBuild(_))).map(|i| i as u32);
        let has_render = tasks.iter().any(|t| {
            matches!(
                t,
                Task::AmbientOcclusion(_)
                    | Task::DirectLightingInjection(_)
                    | Task::DirectLightTransfer(_)
                    | Task::Shadow(_)
                    | Task::Diffuse(_)
                    | Task::Specular(_)
                    | Task::MultiShadow(_)
                    | Task::Denoise(_)
            )
        });
        let bvh_span = first_bvh.map(|i| timer(st, ws_index).begin(d, cmd, TaskKind::Bvh, i));
        self.apply_scene_tasks(st, ws_index, tasks, cmd, serial, &mut hazards)?;
        let max_builds: Option<u32> = tasks
            .iter()
            .filter_map(|t| if let Task::BvhBuild(b) = t { Some(b.max_blas_build_count) } else { None })
            .reduce(|a, b| a.saturating_add(b));
        if let Some(max_builds) = max_builds {
            let span = timer(st, ws_index).begin(d, cmd, TaskKind::BlasBuild, first_bvh.unwrap_or(0));
            self.record_blas_work(st, ws_index, serial, max_builds, cmd, &mut hazards)?;
            timer(st, ws_index).end(d, cmd, span);
        }
        if max_builds.is_some() || has_render {
            if st.snapshot_dirty {
                st.rebuild_snapshot();
            }
            if st.working_sets[ws_index].tlas.version != st.snapshot_version {
                let span = timer(st, ws_index).begin(d, cmd, TaskKind::TlasBuild, first_bvh.unwrap_or(0));
                self.record_tlas(st, ws_index, cmd, &mut hazards)?;
                timer(st, ws_index).end(d, cmd, span);
            }
        }
        if let Some(span) = bvh_span {
            timer(st, ws_index).end(d, cmd, span);
        }

        // ---- Cache maintenance: new layouts, new caches, clears.
        if st.caches_dirty || tasks.iter().any(|t| matches!(t, Task::ClearCache(_))) {
            let span = timer(st, ws_index).begin(d, cmd, TaskKind::CacheUpdate, 0);
            self.update_caches(st, ws_index, cmd, &mut hazards, tasks, serial)?;
            timer(st, ws_index).end(d, cmd, span);
        }

        // ---- Render tasks, in scheduled order.
        if !has_render {
            return Ok(());
        }
        let floor = self.bench_floor.load(Ordering::Relaxed);
        let per_task = passes::ao::UPLOAD_BYTES
            .max(passes::debug::UPLOAD_BYTES)
            .max(passes::inject::UPLOAD_BYTES)
            .max(passes::transfer::UPLOAD_BYTES)
            .max(passes::shadow::UPLOAD_BYTES)
            .max(passes::diffuse::UPLOAD_BYTES)
            .max(passes::specular::UPLOAD_BYTES)
            .max(passes::shadow::MULTI_UPLOAD_BYTES)
            .max(passes::denoise::UPLOAD_BYTES)
            + device.ubo_alignment;
        self.ensure_ring(st, ws_index, Self::instance_table_bytes(st) + tasks.len() as u64 * per_task)?;
        let instance_table = self.push_instance_table(st, ws_index);
        for (i, task) in tasks.iter().enumerate() {
            let kind = match task {
                Task::AmbientOcclusion(_) => TaskKind::AmbientOcclusion,
                Task::DirectLightingInjection(_) => TaskKind::DirectLightingInjection,
                Task::DirectLightTransfer(_) => TaskKind::CacheTransfer,
                Task::Shadow(_) => TaskKind::Shadow,
                Task::Diffuse(_) => TaskKind::Diffuse,
                Task::Specular(_) => TaskKind::Specular,
                Task::MultiShadow(_) => TaskKind::MultiShadow,
                Task::Denoise(j) => match j.signal {
                    SignalType::Specular => TaskKind::DenoiseSpecular,
                    SignalType::Diffuse => TaskKind::DenoiseDiffuse,
                    SignalType::SpecularAndDiffuse => TaskKind::DenoiseSpecularAndDiffuse,
                    SignalType::DiffuseOcclusion => TaskKind::DenoiseDiffuseOcclusion,
                    SignalType::Shadow => TaskKind::DenoiseShadow,
                    SignalType::MultiShadow => TaskKind::DenoiseMultiShadow,
                },
                _ => continue,
            };
            let transfer_job = match task {
                Task::DirectLightTransfer(t) => match cache::transfer_job(st, t) {
                    Some(job) => Some(job),
                    None => {
                        log::debug!("cache transfer skipped: an instance has no cache yet");
                        continue;
                    }
                },
                _ => None,
            };
            let span = timer(st, ws_index).begin(d, cmd, kind, i as u32);
            let ws = &mut st.working_sets[ws_index];
            let tlas = ws.tlas.accel.as_ref().map(|a| a.accel).unwrap_or_default();
            let mut r = Recording {
                device,
                cmd,
                ring: &mut ws.ring,
                hazards: &mut hazards,
                tlas,
                seed: serial as u32,
                instance_table,
                floor,
            };
            // Inline ray queries where asked for and available; otherwise the pipeline (once
            // a warning says so).
            let wants_inline = task.trace_common().is_some_and(|c| c.use_inline_rt);
            if wants_inline && !device.ray_query && !self.warned_inline.swap(true, Ordering::Relaxed) {
                log::warn!("use_inline_rt: the device has no VK_KHR_ray_query enabled; using the ray-tracing pipeline");
            }
            let inline = wants_inline && device.ray_query;
            if let Some((common, output)) = task.debug_target() {
                // Any trace task with a debug mode records the visualisation instead.
                st.debug.as_ref().expect("created in new").record(&mut r, common, output);
                timer(st, ws_index).end(d, cmd, span);
                continue;
            }
            match task {
                Task::Shadow(t) => st.shadow.as_ref().expect("created in new").record(&mut r, inline, t),
                Task::Diffuse(t) => st.diffuse.as_ref().expect("created in new").record(&mut r, inline, t),
                Task::Specular(t) => st.specular.as_ref().expect("created in new").record(&mut r, inline, t),
                Task::MultiShadow(t) => st.multi_shadow.as_ref().expect("created in new").record(&mut r, inline, t),
                Task::Denoise(j) => {
                    if let Ok(state) = st.denoisers.get_mut(j.context) {
                        st.denoise.as_ref().expect("created in new").record(&mut r, state, j);
                    }
                }
                Task::AmbientOcclusion(t) => st.ao.as_ref().expect("created in new").record(&mut r, t, inline, floor),
                Task::DirectLightingInjection(t) => cache::record_injection(
                    &mut r,
                    st.inject.as_ref().expect("created in new"),
                    st.cache_ops.as_ref().expect("created in new"),
                    &st.cache_pool,
                    t,
                ),
                Task::DirectLightTransfer(_) => {
                    if let Some(job) = transfer_job.as_ref() {
                        st.transfer.as_ref().expect("created in new").record(&mut r, job);
                    }
                }
                _ => {}
            }
            timer(st, ws_index).end(d, cmd, span);
        }
        Ok(())
    }

    /// Applies geometry and instance tasks to the registries and records the geometry copies.
    fn apply_scene_tasks(
        &self,
        st: &mut State,
        ws_index: usize,
        tasks: &[Task],
        cmd: vk::CommandBuffer,
        serial: u64,
        hazards: &mut Hazards,
    ) -> Result<()> {
        let d = &self.device.raw;
        let mut copies_declared = false;
        let mut read_back: Vec<GeometryHandle> = Vec::new();
        for task in tasks {
            match task {
                Task::Geometry(t) => {
                    if !copies_declared {
                        hazards.write(d, cmd, sync::TRANSFER_WRITE);
                        copies_declared = true;
                    }
                    let layout = GeometryLayout::of(&t.input);
                    let copy = geometry::record_copy(d, &self.memory, cmd, &t.input, &layout)?;
                    let g = st.geometries.get_mut(t.handle)?;
                    if let Some(old) = g.copy.replace(copy) {
                        st.deferred.retire(serial, Garbage::Buffer(old));
                    }
                    let g = st.geometries.get_mut(t.handle)?;
                    g.layout = Some(layout);
                    g.input = t.input;
                    let refit = t.operation == TaskOperation::Update && layout.allow_update && g.blas.is_some();
                    if refit {
                        g.needs_refit = true;
                        st.refit_queue.push(t.handle);
                    } else {
                        read_back.retain(|h| *h != t.handle);
                        read_back.push(t.handle);
                        g.build_id += 1;
                        g.compacted_size = None;
                        if g.blas.is_none() {
                            g.state = BlasState::Queued;
                        }
                        if !st.build_queue.contains(&t.handle) {
                            st.build_queue.push_back(t.handle);
                        }
                    }
                }
                Task::Instance(t) => {
                    let mut old = st.instances.get(t.handle)?.placement;
                    // Moving an instance keeps its lighting; a new geometry needs a new cache.
                    let keep = old
                        .filter(|o| t.operation == InstanceOperation::Update && o.geometry == t.input.geometry)
                        .and_then(|o| o.cache);
                    if keep.is_some() {
                        if let Some(o) = old.as_mut() {
                            o.cache = None;
                        }
                    }
                    st.unplace(old);
                    let placement = (t.operation != InstanceOperation::Remove).then_some(Placement {
                        geometry: t.input.geometry,
                        transform: t.input.transform,
                        mask: t.input.mask.0,
                        initial_tile_color: t.input.initial_tile_color,
                        cache: keep,
                    });
                    st.caches_dirty = true;
                    if let Some(p) = placement {
                        st.geometries.get_mut(p.geometry)?.instance_refs += 1;
                    }
                    st.instances.get_mut(t.handle)?.placement = placement;
                    st.snapshot_dirty = true;
                }
                _ => {}
            }
        }
        self.record_readbacks(st, ws_index, &read_back, cmd, hazards)
    }

    /// Compactions, throttled BLAS builds and refits, in one batch where possible.
    fn record_blas_work(
        &self,
        st: &mut State,
        ws_index: usize,
        serial: u64,
        max_builds: u32,
        cmd: vk::CommandBuffer,
        hazards: &mut Hazards,
    ) -> Result<()> {
        let device = &self.device;
        let d = &device.raw;

        // Compactions of BLASes built in earlier tickets.
        let ready = std::mem::take(&mut st.compaction_ready);
        let mut declared = false;
        for h in ready {
            let Ok(g) = st.geometries.get_mut(h) else { continue };
            let (Some(size), Some(_)) = (g.compacted_size.take(), g.blas.as_ref()) else { continue };
            let compact =
                blas::create(device, &self.memory, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, size, MemoryKind::Blas)?;
            if !declared {
                hazards.read_write(d, cmd, sync::AS_COPY, sync::AS_COPY);
                declared = true;
            }
            let old = g.blas.replace(compact).expect("checked");
            let info = vk::CopyAccelerationStructureInfoKHR::default()
                .src(old.accel)
                .dst(g.blas.as_ref().expect("set").accel)
                .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
            unsafe { device.accel.cmd_copy_acceleration_structure(cmd, &info) };
            st.deferred.retire(serial, Garbage::AccelerationStructure(old.accel, old.buffer));
            st.snapshot_dirty = true;
        }

        // Plan the batch: refits first (not throttled), then up to max_builds queued builds.
        let mut jobs: Vec<BuildJob> = Vec::new();
        let mut compaction_candidates: Vec<(GeometryHandle, u64, vk::AccelerationStructureKHR)> = Vec::new();
        let mut scratch_total = 0u64;
        let align = device.scratch_alignment;
        let refits = std::mem::take(&mut st.refit_queue);
        for h in refits {
            let Ok(g) = st.geometries.get_mut(h) else { continue };
            if !g.needs_refit {
                continue;
            }
            g.needs_refit = false;
            let (Some(layout), Some(copy), Some(b)) = (g.layout, g.copy.as_ref(), g.blas.as_ref()) else { continue };
            let geometry = blas::triangles(copy.address, &layout);
            let flags = blas::flags(&layout);
            let sizes = blas::build_sizes(
                device,
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                flags,
                &geometry,
                layout.primitive_count,
            );
            jobs.push(BuildJob {
                geometry,
                flags,
                refit: true,
                dst: b.accel,
                primitive_count: layout.primitive_count,
                scratch_offset: scratch_total,
            });
            scratch_total += sizes.update_scratch_size.div_ceil(align) * align;
        }
        let mut built = 0;
        while built < max_builds {
            let Some(h) = st.build_queue.pop_front() else { break };
            let Ok(g) = st.geometries.get_mut(h) else { continue };
            let (Some(layout), Some(copy)) = (g.layout, g.copy.as_ref()) else { continue };
            let geometry = blas::triangles(copy.address, &layout);
            let flags = blas::flags(&layout);
            let sizes = blas::build_sizes(
                device,
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                flags,
                &geometry,
                layout.primitive_count,
            );
            let fresh = blas::create(
                device,
                &self.memory,
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                sizes.acceleration_structure_size,
                MemoryKind::Blas,
            )?;
            let dst = fresh.accel;
            if let Some(old) = g.blas.replace(fresh) {
                st.deferred.retire(serial, Garbage::AccelerationStructure(old.accel, old.buffer));
            }
            let g = st.geometries.get_mut(h)?;
            g.state = BlasState::Ready;
            g.needs_refit = false;
            if !layout.allow_update {
                compaction_candidates.push((h, g.build_id, dst));
            }
            jobs.push(BuildJob {
                geometry,
                flags,
                refit: false,
                dst,
                primitive_count: layout.primitive_count,
                scratch_offset: scratch_total,
            });
            scratch_total += sizes.build_scratch_size.div_ceil(align) * align;
            st.snapshot_dirty = true;
            built += 1;
        }
        if jobs.is_empty() {
            return Ok(());
        }
        self.ensure_scratch(st, ws_index, scratch_total)?;
        hazards.read_write(d, cmd, sync::AS_BUILD_READ, sync::AS_BUILD_WRITE);
        let ws = &mut st.working_sets[ws_index];
        blas::record_batch(device, cmd, ws.scratch.as_ref().expect("ensured"), &jobs);

        // Ask for compacted sizes; read back when this ticket completes.
        if !compaction_candidates.is_empty() {
            let n = compaction_candidates.len() as u32;
            if ws.compaction_slots < n {
                if ws.compaction_pool != vk::QueryPool::null() {
                    unsafe { d.destroy_query_pool(ws.compaction_pool, None) };
                }
                let slots = n.max(16).next_power_of_two();
                let info = vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                    .query_count(slots);
                ws.compaction_pool = unsafe { d.create_query_pool(&info, None) }.map_err(Error::vk("vkCreateQueryPool"))?;
                ws.compaction_slots = slots;
            }
            hazards.read(d, cmd, sync::AS_BUILD_READ);
            let accels: Vec<_> = compaction_candidates.iter().map(|c| c.2).collect();
            unsafe {
                d.cmd_reset_query_pool(cmd, ws.compaction_pool, 0, n);
                device.accel.cmd_write_acceleration_structures_properties(
                    cmd,
                    &accels,
                    vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                    ws.compaction_pool,
                    0,
                );
            }
            ws.compactions = compaction_candidates.iter().map(|c| (c.0, c.1)).collect();
        }
        Ok(())
    }

    /// Rebuilds this working set's TLAS when the snapshot changed since it last did.
    fn record_tlas(&self, st: &mut State, ws_index: usize, cmd: vk::CommandBuffer, hazards: &mut Hazards) -> Result<()> {
        let device = &self.device;
        let version = st.snapshot_version;
        if st.working_sets[ws_index].tlas.version == version {
            return Ok(());
        }
        let count = st.snapshot.len() as u32;
        let sizes = tlas::sizes(device, count);
        self.ensure_scratch(st, ws_index, sizes.build_scratch_size)?;
        self.ensure_ring(st, ws_index, st.snapshot.len() as u64 * 64 + 256)?;
        let ws = &mut st.working_sets[ws_index];
        ws.tlas.ensure_storage(device, &self.memory, sizes.acceleration_structure_size)?;
        let upload = ws.ring.push(instance::instance_bytes(&st.snapshot), 16);
        hazards.read_write(&device.raw, cmd, sync::AS_BUILD_READ, sync::AS_BUILD_WRITE);
        ws.tlas.record_build(device, cmd, upload, count, ws.scratch.as_ref().expect("ensured"));
        ws.tlas.version = version;
        Ok(())
    }

    /// The working set is idle (its ticket came back), so a too-small scratch buffer can be
    /// replaced at once. Within one recording, scratch is only reused after a barrier.
    fn ensure_scratch(&self, st: &mut State, ws_index: usize, bytes: u64) -> Result<()> {
        let ws = &mut st.working_sets[ws_index];
        // Scratch written earlier in this recording may still be in use by the GPU when a
        // larger one replaces it, so the old one goes through deferred destruction.
        let serial = st.next_serial;
        let deferred = &mut st.deferred;
        memory::ensure_capacity(
            &mut ws.scratch,
            bytes + self.device.scratch_alignment,
            |size| {
                self.memory.create_buffer(
                    "build scratch",
                    size,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryLocation::GpuOnly,
                    MemoryKind::BuildScratch,
                )
            },
            |old| deferred.retire(serial, Garbage::Buffer(old)),
        )
    }

    /// Grows the ring so `more` bytes fit after what this recording already wrote. Data
    /// already pushed stays valid: the old ring is retired, not freed, until this ticket is back.
    fn ensure_ring(&self, st: &mut State, ws_index: usize, more: u64) -> Result<()> {
        let ws = &mut st.working_sets[ws_index];
        if ws.ring.remaining() >= more {
            return Ok(());
        }
        let size = (ws.ring.capacity() + more).max(ws.ring.capacity() * 3 / 2);
        let fresh = UploadRing::new(&self.memory, size)?;
        let old = std::mem::replace(&mut ws.ring, fresh);
        st.deferred.retire(st.next_serial, Garbage::Buffer(old.buffer));
        Ok(())
    }
}

impl Drop for Shared {
    /// The engine drops the context after the GPU finished every ticket (as for any Vulkan
    /// object it destroys); nothing here waits.
    fn drop(&mut self) {
        let st = self.state.get_mut();
        let device = &self.device;
        let memory = &self.memory;
        st.deferred.collect(device, memory, None);
        let geometries: Vec<GeometryHandle> = st.geometries.iter().map(|(h, _)| h).collect();
        for h in geometries {
            if let Ok(g) = st.geometries.remove(h) {
                if let Some(c) = g.copy {
                    deferred::destroy(device, memory, Garbage::Buffer(c));
                }
                if let Some(b) = g.blas {
                    deferred::destroy(device, memory, Garbage::AccelerationStructure(b.accel, b.buffer));
                }
                if let Some(sf) = g.surfel {
                    memory.destroy_buffer(sf.buffer);
                }
            }
        }
        for mut ws in st.working_sets.drain(..) {
            ws.tlas.destroy(device, memory);
            for (_, _, b) in ws.readbacks.drain(..) {
                memory.destroy_buffer(b);
            }
            memory.destroy_buffer(ws.ring.buffer);
            if let Some(s) = ws.scratch.take() {
                memory.destroy_buffer(s);
            }
            ws.timer.destroy(&device.raw);
            unsafe {
                if ws.compaction_pool != vk::QueryPool::null() {
                    device.raw.destroy_query_pool(ws.compaction_pool, None);
                }
            }
        }
        if let Some(ao) = st.ao.take() {
            ao.destroy(device, memory);
        }
        if let Some(p) = st.debug.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.inject.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.transfer.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.shadow.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.diffuse.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.specular.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.multi_shadow.take() {
            p.destroy(device, memory);
        }
        if let Some(p) = st.cache_ops.take() {
            p.destroy(device);
        }
        if let Some(p) = st.denoise.take() {
            p.destroy(device);
        }
        let denoisers: Vec<DenoisingContextHandle> = st.denoisers.iter().map(|(h, _)| h).collect();
        for h in denoisers {
            if let Ok(state) = st.denoisers.remove(h) {
                for image in state.into_images() {
                    memory.destroy_image(image);
                }
            }
        }
        st.cache_pool.destroy(memory);
        unsafe { device.raw.destroy_sampler(st.sampler, None) };
        memory.shutdown();
    }
}
