//! BVH tasks seen through rendered AO: the BLAS throttle, moving instances, refits,
//! compaction, and deferred destruction.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{
    BuildHint, BvhBuildTask, Error, GeometryInput, GeometryTask, IndexBufferInput, InitSettings, InstanceInput,
    InstanceOperation, InstanceTask, RayOffset, TaskOperation, VertexBufferInput,
};
use hybrid_rt_testkit::host::Host;
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const W: u32 = 96;
const H: u32 = 64;
const RAYS: u32 = 16;

/// Ground pixels in a ring around the base of a unit box centred at `c` (in XZ).
fn ring(g: &GBuffer, c: Vec3) -> Vec<bool> {
    (0..g.depth.len())
        .map(|i| {
            let p = g.position[i];
            let dx = (p.x - c.x).abs();
            let dz = (p.z - c.z).abs();
            g.hit[i] && p.y.abs() < 1e-3 && dx.max(dz) > 0.52 && dx.max(dz) < 0.85
        })
        .collect()
}

struct Boxes {
    ground: Scene,
    boxes: Scene,
    centres: Vec<Vec3>,
    camera: Camera,
}

/// Ten unit boxes on a 5x2 grid. The ground is only in the G-buffer (the engine's
/// rasterizer saw it); the SDK's TLAS holds the boxes, so AO on the ground shows exactly which
/// boxes are in the TLAS.
fn boxes(n: usize) -> Boxes {
    let mut boxes = Scene::default();
    let mut centres = Vec::new();
    for i in 0..n {
        let m = boxes.add_mesh(Mesh::cuboid(Vec3::splat(0.5)));
        let c = Vec3::new(-6.0 + 3.0 * (i % 5) as f32, 0.5, if i < 5 { -1.6 } else { 1.6 });
        boxes.add_instance(m, Affine3A::from_translation(c));
        centres.push(Vec3::new(c.x, 0.0, c.z));
    }
    let mut ground = boxes.clone();
    let plane = ground.add_mesh(Mesh::grid(40.0, 2));
    ground.add_instance(plane, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 12.0, 0.01), Vec3::ZERO);
    Boxes { ground, boxes, centres, camera }
}

fn params() -> AoParams {
    AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset: RayOffset::default() }
}

/// Checks, box by box, that the ring around each box is occluded exactly when `in_tlas(i)`.
fn check_rings(gpu: &[f32], g: &GBuffer, b: &Boxes, in_tlas: impl Fn(usize) -> bool, what: &str) {
    check_rings_moved(gpu, g, b, in_tlas, None, what)
}

/// `check_rings` where box `moved` has left its place: its old ring matches the reference
/// of where it is now, occluded or not.
fn check_rings_moved(gpu: &[f32], g: &GBuffer, b: &Boxes, in_tlas: impl Fn(usize) -> bool, moved: Option<usize>, what: &str) {
    let tracer = Tracer::with_instances(&b.boxes, &in_tlas);
    for (i, c) in b.centres.iter().enumerate() {
        let mask = ring(g, *c);
        let n = mask.iter().filter(|m| **m).count();
        assert!(n >= 20, "ring {i} has {n} pixels");
        let reference: Vec<f32> = (0..g.depth.len())
            .map(|p| {
                if mask[p] {
                    ao_at(&tracer, g.position[p], g.normal[p], b.camera.eye, &params(), 8, &mut Rng::new(p as u64))
                } else {
                    1.0
                }
            })
            .collect();
        let gpu_mean = stats::masked_mean(gpu, &mask);
        let ref_mean = stats::masked_mean(&reference, &mask);
        let tol = 4.0 * stats::sample_sigma(RAYS, 64) / (n as f32).sqrt() + 0.01;
        assert!(
            (gpu_mean - ref_mean).abs() <= tol,
            "{what}: box {i}: GPU ring AO {gpu_mean:.4} vs reference {ref_mean:.4} (tol {tol:.4})"
        );
        if moved == Some(i) {
            continue;
        }
        if in_tlas(i) {
            assert!(ref_mean < 0.9, "{what}: box {i} should occlude its ring ({ref_mean})");
        } else {
            assert!(gpu_mean > 0.9999, "{what}: box {i} is not in the TLAS yet, ring AO {gpu_mean}");
        }
    }
}

/// The boxes scene registered with a fresh context, its G-buffer uploaded, and the first
/// BVH build done when `build` is set.
struct Fixture {
    host: Host,
    ctx: hybrid_rt::ExecuteContext,
    b: Boxes,
    g: GBuffer,
    images: GBufferImages,
    frame: hybrid_rt::TaskContainer,
    gpu_scene: SceneOnGpu,
}

fn fixture(n: usize, build: bool) -> Fixture {
    let (host, ctx) = host_and_context(InitSettings::default());
    let b = boxes(n);
    let g = GBuffer::render(&Tracer::new(&b.ground), &b.camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &b.boxes).unwrap();
    if build {
        frame.schedule_bvh_build(&Default::default()).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
    }
    Fixture { host, ctx, b, g, images, frame, gpu_scene }
}

impl Fixture {
    fn ao(&self) -> hybrid_rt::TraceAmbientOcclusionTask {
        self.images.ao_task(&self.b.camera, 1.0, RAYS)
    }

    fn finish(self) {
        self.images.destroy(&self.host);
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
    }
}

#[test]
fn blas_throttle_brings_instances_in_over_frames() {
    let mut f = fixture(10, false);
    for (k, expected) in [3usize, 6, 9, 10].into_iter().enumerate() {
        f.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 3, ..Default::default() }).unwrap();
        f.frame.schedule_ambient_occlusion(&f.ao()).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        assert_eq!(f.ctx.tlas_instance_count(), expected, "build {k}");
        assert_eq!(f.ctx.pending_blas_builds(), 10 - expected);
        let gpu = f.images.read_output(&f.host).unwrap();
        check_rings(&gpu, &f.g, &f.b, |i| i < expected, &format!("build {k}"));
    }
    f.finish();
}

#[test]
fn moving_an_instance_moves_its_occlusion() {
    let mut f = fixture(2, false);
    f.frame.schedule_bvh_build(&Default::default()).unwrap();
    f.frame.schedule_ambient_occlusion(&f.ao()).unwrap();
    run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    check_rings(&f.images.read_output(&f.host).unwrap(), &f.g, &f.b, |_| true, "before the move");

    // Move box 0 far away (off the ground the camera sees); box 1 stays.
    let far = Affine3A::from_translation(Vec3::new(0.0, 50.0, 0.0));
    let moved = InstanceTask {
        handle: f.gpu_scene.instances[0],
        operation: InstanceOperation::Update,
        input: InstanceInput { geometry: f.gpu_scene.geometries[0], transform: far, ..Default::default() },
    };
    f.frame.schedule_instance(&moved).unwrap();
    f.frame.schedule_bvh_build(&Default::default()).unwrap();
    f.frame.schedule_ambient_occlusion(&f.ao()).unwrap();
    run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    f.b.boxes.instances[0].transform = far;
    check_rings(&f.images.read_output(&f.host).unwrap(), &f.g, &f.b, |i| i == 1, "after the move");
    f.finish();
}

/// With `tlas_max_refits`, frames that only move instances refit the TLAS in place; one that
/// removes an instance, or the refit budget running out, rebuilds it. Every frame's occlusion
/// matches the reference of that frame's placement.
#[test]
fn a_refit_tlas_follows_moving_instances() {
    let mut f = fixture(3, false);
    let build = BvhBuildTask { tlas_max_refits: 2, ..Default::default() };
    let place = |f: &mut Fixture, i: usize, t: Option<Affine3A>, op: InstanceOperation| {
        let task = InstanceTask {
            handle: f.gpu_scene.instances[i],
            operation: op,
            input: InstanceInput { geometry: f.gpu_scene.geometries[i], transform: t.unwrap_or_default(), ..Default::default() },
        };
        f.frame.schedule_instance(&task).unwrap();
    };
    let start: Vec<Affine3A> = f.b.boxes.instances.iter().map(|i| i.transform).collect();
    // Box 0 slides a little each frame, then far; box 2 leaves (a rebuild) and comes back.
    for step in 0..8usize {
        let mut present = [true; 3];
        if step > 0 {
            let shift =
                if step == 4 { Vec3::new(0.0, 50.0, 0.0) } else { Vec3::new(0.15 * step as f32, 0.0, -0.1 * step as f32) };
            let t = Affine3A::from_translation(shift) * start[0];
            place(&mut f, 0, Some(t), InstanceOperation::Update);
            f.b.boxes.instances[0].transform = t;
            present[2] = step != 5;
            let op = match step {
                5 => InstanceOperation::Remove,
                6 => InstanceOperation::Register,
                _ => InstanceOperation::Update,
            };
            place(&mut f, 2, present[2].then_some(start[2]), op);
        }
        f.frame.schedule_bvh_build(&build).unwrap();
        f.frame.schedule_ambient_occlusion(&f.ao()).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        let gpu = f.images.read_output(&f.host).unwrap();
        let moved = (step > 0).then_some(0);
        check_rings_moved(&gpu, &f.g, &f.b, |i| present[i], moved, &format!("step {step}"));
    }
    f.finish();
}

/// A deformable (allow_update) quad is refitted in place when its vertices change.
#[test]
fn updating_a_deformable_geometry_refits_its_blas() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut ground = Scene::default();
    let plane = ground.add_mesh(Mesh::grid(10.0, 2));
    ground.add_instance(plane, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 6.0, 0.01), Vec3::ZERO);
    let g = GBuffer::render(&Tracer::new(&ground), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();

    // A ceiling quad (facing down) that first hangs 0.15 above the ground, then is lifted
    // out of AO range: same vertex count, new positions.
    let ceiling = |h: f32| {
        let mut m = Mesh::grid(3.0, 1);
        m.positions.iter_mut().for_each(|p| p.y = h);
        m
    };
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    let low = ceiling(0.15);
    let vb_low = host.buffer_with_data(bytemuck::cast_slice(&low.positions), usage).unwrap();
    let ib = host.buffer_with_data(bytemuck::cast_slice(&low.indices), usage).unwrap();
    let input = |vb: vk::Buffer| GeometryInput {
        vertices: VertexBufferInput { buffer: vb, count: 4, ..Default::default() },
        indices: IndexBufferInput { buffer: ib.buffer, count: 6, ..Default::default() },
        allow_update: true,
        ..Default::default()
    };
    let geo = ctx.create_geometry_handles(1)[0];
    let inst = ctx.create_instance_handles(1)[0];
    let mut frame = ctx.create_task_container();
    // SAFETY: the engine's buffers the task names are alive.
    unsafe {
        frame.schedule_geometry(&GeometryTask { handle: geo, operation: TaskOperation::Register, input: input(vb_low.buffer) })
    }
    .unwrap();
    frame
        .schedule_instance(&InstanceTask {
            handle: inst,
            operation: InstanceOperation::Register,
            input: InstanceInput { geometry: geo, ..Default::default() },
        })
        .unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, RAYS)).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let under: Vec<bool> = g.position.iter().map(|p| p.x.abs() < 1.0 && p.z.abs() < 1.0).collect();
    let before = stats::masked_mean(&images.read_output(&host).unwrap(), &under);
    let tracer_low = {
        let mut s = Scene::default();
        let m = s.add_mesh(low.clone());
        s.add_instance(m, Affine3A::IDENTITY);
        Tracer::new(&s)
    };
    let ref_before = stats::masked_mean(&reference_ao(&tracer_low, &g, camera.eye, &params(), 8), &under);
    let n = under.iter().filter(|m| **m).count() as f32;
    let tol = 4.0 * stats::sample_sigma(RAYS, 64) / n.sqrt() + 0.01;
    assert!((before - ref_before).abs() < tol, "low ceiling: GPU {before} vs reference {ref_before}");
    assert!(before < 0.7, "low ceiling occludes: {before} (reference {ref_before})");

    let high = ceiling(3.0);
    let vb_high = host.buffer_with_data(bytemuck::cast_slice(&high.positions), usage).unwrap();
    // SAFETY: the engine's buffers the task names are alive.
    unsafe {
        frame.schedule_geometry(&GeometryTask { handle: geo, operation: TaskOperation::Update, input: input(vb_high.buffer) })
    }
    .unwrap();
    frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 0, ..Default::default() }).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, RAYS)).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let after = stats::masked_mean(&images.read_output(&host).unwrap(), &under);
    assert!(after > 0.9999, "the refitted ceiling is out of AO range: {after}");
    assert_eq!(ctx.pending_blas_builds(), 0, "a refit is not a queued rebuild");

    // Changing the triangle count of an updatable geometry is refused at build time.
    let tri = host.buffer_with_data(bytemuck::cast_slice(&high.positions[..3]), usage).unwrap();
    // SAFETY: the engine's buffers the task names are alive.
    unsafe {
        frame.schedule_geometry(&GeometryTask {
            handle: geo,
            operation: TaskOperation::Update,
            input: GeometryInput {
                vertices: VertexBufferInput { buffer: tri.buffer, count: 3, ..Default::default() },
                allow_update: true,
                ..Default::default()
            },
        })
    }
    .unwrap();
    assert!(matches!(run_frame(&host, &ctx, &mut frame), Err(e) if e.contains("refitted")));
    frame.clear();

    for b in [vb_low, vb_high, ib, tri] {
        host.destroy_buffer(b);
    }
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// `BuildHint::FastThenTrace`: the frame that registers a mesh builds it fast; later BVH
/// builds rebuild it for fast trace after their new registrations, within the same
/// `max_blas_build_count`, and tracing is right throughout.
#[test]
fn fast_first_builds_are_rebuilt_for_fast_trace_later() {
    let mut f = fixture(4, false);
    for (k, (vb, ib)) in f.gpu_scene.buffers.iter().enumerate() {
        let mesh = &f.b.boxes.meshes[k];
        let input = GeometryInput {
            vertices: VertexBufferInput { buffer: vb.buffer, count: mesh.positions.len() as u32, ..Default::default() },
            indices: IndexBufferInput { buffer: ib.buffer, count: mesh.indices.len() as u32, ..Default::default() },
            build_hint: BuildHint::FastThenTrace,
            ..Default::default()
        };
        let task = GeometryTask { handle: f.gpu_scene.geometries[k], operation: TaskOperation::Update, input };
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { f.frame.schedule_geometry(&task) }.unwrap();
    }
    // (in TLAS, pending builds: queued registrations + quality rebuilds) after each build.
    for (k, (in_tlas, pending)) in [(2usize, 4usize), (4, 4), (4, 2), (4, 0)].into_iter().enumerate() {
        f.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 2, ..Default::default() }).unwrap();
        f.frame.schedule_ambient_occlusion(&f.ao()).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        assert_eq!((f.ctx.tlas_instance_count(), f.ctx.pending_blas_builds()), (in_tlas, pending), "build {k}");
        let gpu = f.images.read_output(&f.host).unwrap();
        check_rings(&gpu, &f.g, &f.b, |i| i < in_tlas, &format!("build {k}"));
    }
    f.finish();
}

/// Static BLASes are compacted a frame after their build (no stall), and tracing still works.
#[test]
fn static_blases_are_compacted() {
    let mut f = fixture(4, true);
    let built = f.ctx.resource_allocations().blas;
    assert_eq!(built.count, 4);
    // Next build: compaction copies; the originals are freed when that ticket is back.
    f.frame.schedule_bvh_build(&Default::default()).unwrap();
    f.frame.schedule_ambient_occlusion(&f.ao()).unwrap();
    run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    let compacted = f.ctx.resource_allocations().blas;
    eprintln!("BLAS bytes: built {} -> compacted {}", built.bytes, compacted.bytes);
    assert_eq!(compacted.count, 4, "originals freed once the compacting ticket is back");
    assert!(compacted.bytes <= built.bytes);
    check_rings(&f.images.read_output(&f.host).unwrap(), &f.g, &f.b, |_| true, "after compaction");
    f.finish();
}

/// Destroying handles while a ticket that uses them is in flight defers the frees.
#[test]
fn destruction_is_deferred_until_tickets_return() {
    let mut f = fixture(2, true);
    let (host, ctx) = (&f.host, &f.ctx);
    f.frame.schedule_ambient_occlusion(&f.images.ao_task(&f.b.camera, 1.0, RAYS)).unwrap();
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(&mut f.frame, cmd) }.unwrap();
    // The AO recorded above still reads both BLASes: destroying now must not free them.
    assert!(matches!(ctx.destroy_geometry_handles(&f.gpu_scene.geometries), Err(Error::GeometryInUse { .. })));
    ctx.destroy_instance_handles(&f.gpu_scene.instances).unwrap();
    ctx.destroy_geometry_handles(&f.gpu_scene.geometries).unwrap();
    let during = ctx.resource_allocations();
    assert_eq!(during.blas.count, 2, "BLASes live while the ticket is out");
    assert!(matches!(ctx.release_device_resources_immediately(), Err(Error::TicketsInFlight { .. })));
    let fence = host.submit(cmd).unwrap();
    host.wait(fence).unwrap();
    ctx.mark_gpu_task_completed(ticket).unwrap();
    let after = ctx.resource_allocations();
    assert_eq!(after.blas.count, 0);
    assert_eq!(after.geometry_copies.count, 0);
    // The frame's AO saw both boxes.
    check_rings(&f.images.read_output(host).unwrap(), &f.g, &f.b, |_| true, "in-flight frame");
    ctx.release_device_resources_immediately().unwrap();
    f.finish();
}

/// Level unload: every geometry at once (refused, changing nothing, while instances place
/// them), every denoising context at once.
#[test]
fn destroy_all_geometries_and_denoising_contexts() {
    let mut f = fixture(2, true);
    let ctx = &f.ctx;
    let geometries = f.gpu_scene.geometries.clone();
    assert!(matches!(ctx.destroy_all_geometry_handles(), Err(Error::GeometryInUse { .. })));
    for g in &geometries {
        ctx.geometry_invalid_triangles(*g).expect("a refused destroy-all keeps every geometry");
    }
    ctx.destroy_all_instance_handles();
    ctx.destroy_all_geometry_handles().unwrap();
    for g in &geometries {
        assert!(matches!(ctx.geometry_invalid_triangles(*g), Err(Error::InvalidHandle { .. })));
    }
    let input = |signal| hybrid_rt::DenoisingContextInput { max_width: W, max_height: H, signal, ..Default::default() };
    let contexts = [
        ctx.create_denoising_context(&input(hybrid_rt::SignalType::Shadow)).unwrap(),
        ctx.create_denoising_context(&input(hybrid_rt::SignalType::DiffuseOcclusion)).unwrap(),
    ];
    assert!(ctx.resource_allocations().denoiser.count > 0);
    ctx.destroy_all_denoising_context_handles();
    for c in contexts {
        assert!(matches!(ctx.destroy_denoising_context(c), Err(Error::InvalidHandle { .. })));
    }
    // Nothing in flight: everything deferred goes now.
    run_frame(&f.host, ctx, &mut f.frame).unwrap();
    ctx.release_device_resources_immediately().unwrap();
    let left = ctx.resource_allocations();
    assert_eq!((left.blas.count, left.denoiser.count), (0, 0), "{left:?}");
    f.finish();
}

/// A `Write` into a buffer the test keeps.
#[derive(Clone, Default)]
struct SharedLog(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl std::io::Write for SharedLog {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The rows of `ResourceAllocations`, by the kind names the allocation log writes.
fn bytes_by_kind(a: &hybrid_rt::ResourceAllocations) -> Vec<(String, u64)> {
    a.by_kind().iter().map(|(kind, c)| (format!("{kind:?}"), c.bytes)).collect()
}

/// The allocation log accounts for every byte: over a frame with a new denoiser, then a level
/// unload, each kind's logged allocations minus frees equal the change in
/// `resource_allocations`, and each kind's last `kind_live_bytes` is its final count.
#[test]
fn the_allocation_log_accounts_for_every_byte() {
    let mut f = fixture(2, true);
    let log = SharedLog::default();
    f.ctx.begin_logging_resource_allocations(log.clone()).unwrap();
    assert!(matches!(f.ctx.begin_logging_resource_allocations(SharedLog::default()), Err(Error::InvalidInput { .. })));
    let before = f.ctx.resource_allocations();
    let input = hybrid_rt::DenoisingContextInput {
        max_width: W,
        max_height: H,
        signal: hybrid_rt::SignalType::DiffuseOcclusion,
        ..Default::default()
    };
    let denoiser = f.ctx.create_denoising_context(&input).unwrap();
    f.frame.schedule_ambient_occlusion(&f.images.ao_task(&f.b.camera, 1.0, RAYS)).unwrap();
    run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    f.ctx.destroy_denoising_context(denoiser).unwrap();
    f.ctx.destroy_all_instance_handles();
    f.ctx.destroy_all_geometry_handles().unwrap();
    run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    f.ctx.release_device_resources_immediately().unwrap();
    let after = f.ctx.resource_allocations();
    f.ctx.end_logging_resource_allocations().unwrap();
    assert!(matches!(f.ctx.end_logging_resource_allocations(), Err(Error::InvalidInput { .. })));

    let text = String::from_utf8(log.0.lock().unwrap().clone()).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time_ms,event,kind,name,bytes,kind_live_bytes"));
    let mut net: std::collections::HashMap<String, i128> = Default::default();
    let mut last_live: std::collections::HashMap<String, u64> = Default::default();
    let (mut allocs, mut frees) = (0, 0);
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), 6, "{line}");
        let bytes: i128 = fields[4].parse().unwrap();
        match fields[1] {
            "alloc" => (*net.entry(fields[2].into()).or_default() += bytes, allocs += 1).1,
            "free" => (*net.entry(fields[2].into()).or_default() -= bytes, frees += 1).1,
            other => panic!("event {other}"),
        };
        last_live.insert(fields[2].into(), fields[5].parse().unwrap());
    }
    eprintln!("{allocs} allocations, {frees} frees logged");
    assert!(net.contains_key("Denoiser") && net.contains_key("Blas"), "{net:?}");
    for ((kind, b), (_, a)) in bytes_by_kind(&before).into_iter().zip(bytes_by_kind(&after)) {
        let logged = net.get(&kind).copied().unwrap_or(0);
        assert_eq!(logged, a as i128 - b as i128, "{kind}: logged net bytes against the report");
        if let Some(live) = last_live.get(&kind) {
            assert_eq!(*live, a, "{kind}: the last live count");
        }
    }
    f.finish();
}

/// The single-handle helpers are the `Vec` ones for one handle: each call makes a new handle,
/// destroying it once works and twice is refused.
#[test]
fn single_handle_helpers_make_and_destroy_one_handle() {
    let f = fixture(1, false);
    let (g, i) = (f.ctx.create_geometry_handle(), f.ctx.create_instance_handle());
    assert_ne!(g, f.ctx.create_geometry_handle(), "each call makes a new handle");
    f.ctx.destroy_instance_handle(i).unwrap();
    assert!(matches!(f.ctx.destroy_instance_handle(i), Err(Error::InvalidHandle { .. })));
    f.ctx.destroy_geometry_handle(g).unwrap();
    assert!(matches!(f.ctx.destroy_geometry_handle(g), Err(Error::InvalidHandle { .. })));
    f.finish();
}

/// Every public type prints something useful with `{:?}`: the context its device and tickets,
/// a container its tasks, a device description its handles and features.
#[test]
fn public_handles_print_what_they_hold() {
    let f = fixture(1, false);
    let ctx = format!("{:?}", f.ctx);
    assert!(ctx.starts_with("ExecuteContext") && ctx.contains("tickets_in_flight: 0"), "{ctx}");
    let frame = format!("{:?}", f.frame);
    assert!(frame.contains("TaskContainer") && frame.contains("context_alive: true"), "{frame}");
    let desc = format!("{:?}", f.host.device_desc());
    assert!(desc.contains("instance_api_version") && desc.contains("VK_KHR_acceleration_structure"), "{desc}");
    let features = format!("{:?}", hybrid_rt::DeviceFeatures::required(false));
    assert!(features.contains("rayTracingPipeline"), "{features}");
    f.finish();
}
