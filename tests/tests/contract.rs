//! The integration contract: what an engine must be able to trust. Each test is a promise
//! that used to break — a device without the SDK's features or with a 1.2 instance accepted
//! (and an abort at the first build), no way to replay a frame's noise, scheduling stalled by
//! another thread's build, a context dropped under the GPU — now kept.
use ash::vk;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::Host;
use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;
use std::time::{Duration, Instant};

fn missing(e: Error) -> Vec<String> {
    match e {
        Error::MissingDeviceSupport { missing } => missing,
        other => panic!("expected MissingDeviceSupport, got {other}"),
    }
}

#[test]
fn a_device_without_what_the_sdk_needs_is_refused_naming_it() {
    let host = Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)");
    let settings = InitSettings::default();
    let make = |desc: DeviceDesc<'_>| unsafe { ExecuteContext::new(&desc, &settings) }.expect_err("refused");
    // The host's description with one thing changed (the fields are public; the struct is
    // non-exhaustive, so it is made by `DeviceDesc::new`).
    let with = |change: &dyn Fn(&mut DeviceDesc<'_>)| {
        let mut d = host.device_desc();
        change(&mut d);
        make(d)
    };

    // No feature chain at all: nothing can be checked, so nothing is assumed.
    let e = missing(with(&|d| d.enabled_features = std::ptr::null()));
    assert!(e.iter().any(|m| m.contains("enabled_features")), "{e:?}");

    // A chain without synchronization2 and rayTracingPipeline: both named, and only those.
    let mut off = DeviceFeatures::required(false);
    off.vulkan13.synchronization2 = vk::FALSE;
    off.ray_tracing_pipeline.ray_tracing_pipeline = vk::FALSE;
    let _ = off.push_to(vk::DeviceCreateInfo::default());
    let e = missing(with(&|d| d.enabled_features = off.chain()));
    assert_eq!(e.len(), 2, "{e:?}");
    assert!(e.iter().any(|m| m.contains("synchronization2")) && e.iter().any(|m| m.contains("rayTracingPipeline")), "{e:?}");

    // A Vulkan 1.2 instance: the SDK records 1.3 commands (it used to abort inside ash).
    let e = missing(with(&|d| d.instance_api_version = vk::API_VERSION_1_2));
    assert!(e.iter().any(|m| m.contains("apiVersion 1.3")), "{e:?}");

    // An extension left off.
    let fewer: Vec<&std::ffi::CStr> =
        host.enabled_extensions.iter().copied().filter(|e| *e != ash::khr::push_descriptor::NAME).collect();
    let mut d = host.device_desc();
    d.enabled_extensions = &fewer;
    let e = missing(make(d));
    assert!(e.iter().any(|m| m.contains("VK_KHR_push_descriptor")), "{e:?}");

    // The real chain (the host's own Vulkan13Features with the SDK's merged in) works.
    host.create_context(&settings).expect("the merged chain has everything");
}

/// The ground-plane AO used by the determinism tests: a box on a plane, `W` x `H`.
struct Frame {
    host: Host,
    images: GBufferImages,
    camera: Camera,
    scene: Scene,
}

const W: u32 = 32;
const H: u32 = 32;

impl Frame {
    fn new() -> Frame {
        let host = Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)");
        let mut scene = Scene::default();
        let g = scene.add_mesh(Mesh::grid(6.0, 1));
        scene.add_instance(g, Affine3A::IDENTITY);
        let b = scene.add_mesh(Mesh::cuboid(Vec3::splat(0.5)));
        scene.add_instance(b, Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)));
        let camera = Camera::look_at(Vec3::new(0.0, 4.0, 2.0), Vec3::ZERO);
        let images = GBufferImages::upload(&host, &GBuffer::render(&Tracer::new(&scene), &camera, W, H)).unwrap();
        Frame { host, images, camera, scene }
    }

    /// A context with the scene registered and built (`extra` unrelated builds first, so its
    /// ticket serials differ from another context's).
    fn context(&self, extra: usize) -> ExecuteContext {
        let ctx = self.host.create_context(&InitSettings::default()).unwrap();
        let mut c = ctx.create_task_container();
        let s = SceneOnGpu::register(&self.host, &ctx, &mut c, &self.scene).unwrap();
        c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
        run_frame(&self.host, &ctx, &mut c).unwrap();
        for _ in 0..extra {
            c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
            run_frame(&self.host, &ctx, &mut c).unwrap();
        }
        s.destroy(&self.host);
        ctx
    }

    /// AO with 2 rays per pixel (noisy), checkerboarded when `half`.
    fn ao(&self, ctx: &ExecuteContext, frame_index: Option<u64>, half: bool) -> Vec<f32> {
        let mode = if half { HalfResolutionMode::Checkerboard } else { HalfResolutionMode::Off };
        self.ao_in_mode(ctx, frame_index, mode)
    }

    fn ao_in_mode(&self, ctx: &ExecuteContext, frame_index: Option<u64>, mode: HalfResolutionMode) -> Vec<f32> {
        let mut c = ctx.create_task_container();
        if let Some(i) = frame_index {
            c.set_frame_index(i);
        }
        let mut task = self.images.ao_task(&self.camera, 1.0, 2);
        task.common.half_resolution_mode = mode;
        c.schedule_ambient_occlusion(&task).unwrap();
        run_frame(&self.host, ctx, &mut c).unwrap();
        self.images.read_output(&self.host).unwrap()
    }
}

/// The random sequences and the checkerboard phase follow the engine's frame index: the same
/// index and inputs give the same image on another context with other ticket serials, and two
/// containers of one frame trace the same checkerboard half.
#[test]
fn the_same_frame_index_gives_the_same_image() {
    let f = Frame::new();
    let (a, b) = (f.context(0), f.context(3));
    let first = f.ao(&a, Some(41), false);
    assert!(first.iter().any(|v| *v > 0.01 && *v < 0.99), "the image is noisy: a replay means something");
    assert_eq!(first, f.ao(&b, Some(41), false), "frame 41 replayed on another context");
    assert_ne!(first, f.ao(&b, Some(42), false), "another frame, other samples");
    let (x, y) = (f.ao(&a, None, false), f.ao(&a, None, false));
    assert_ne!(x, y, "without an index every build draws fresh samples");

    // Checkerboard: an odd and an even frame trace opposite halves; the same index the same.
    let odd = f.ao(&a, Some(7), true);
    assert_eq!(odd, f.ao(&b, Some(7), true));
    assert_ne!(odd, f.ao(&b, Some(8), true));
    drop(a);
    drop(b);
    f.images.destroy(&f.host);
}

/// The SDK's shaders write engine outputs without a format qualifier, which Vulkan 1.3 allows
/// per format (`VK_FORMAT_FEATURE_2_STORAGE_WRITE_WITHOUT_FORMAT_BIT`), so the device needs no
/// `shaderStorageImageWriteWithoutFormat` — which wgpu leaves off on the devices it creates.
/// `DeviceFeatures` does not ask for it (every test's device is made without it, under the
/// validation layer); an output in each format the device writes that way traces the frame's
/// AO, and one it does not is refused by name before anything is recorded.
#[test]
fn outputs_need_no_device_wide_formatless_writes() {
    let wanted = DeviceFeatures::required(true);
    assert_eq!(wanted.core.features.shader_storage_image_write_without_format, vk::FALSE);
    let f = Frame::new();
    let ctx = f.context(0);
    let reference = f.ao(&ctx, Some(5), false);
    assert!(reference.iter().any(|v| *v > 0.01 && *v < 0.99), "the image is noisy: equality means something");
    let formats = [
        vk::Format::R8_UNORM,
        vk::Format::R16_UNORM,
        vk::Format::R16_SFLOAT,
        vk::Format::R32_SFLOAT,
        vk::Format::R8G8B8A8_UNORM,
        vk::Format::R16G16B16A16_SFLOAT,
        vk::Format::R32G32B32A32_SFLOAT,
    ];
    let mut written = 0;
    for format in formats {
        let mut props3 = vk::FormatProperties3::default();
        let mut props2 = vk::FormatProperties2::default().push_next(&mut props3);
        // SAFETY: a plain query on the host's physical device.
        unsafe { f.host.instance.get_physical_device_format_properties2(f.host.physical_device, format, &mut props2) };
        let features = props3.optimal_tiling_features;
        if !features.contains(vk::FormatFeatureFlags2::STORAGE_IMAGE) {
            continue;
        }
        let out = f.host.image_cleared(format, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
        let mut task = f.images.ao_task(&f.camera, 1.0, 2);
        task.output = out.input(vk::ImageLayout::GENERAL);
        let mut c = ctx.create_task_container();
        c.set_frame_index(5);
        let scheduled = c.schedule_ambient_occlusion(&task);
        if features.contains(vk::FormatFeatureFlags2::STORAGE_WRITE_WITHOUT_FORMAT) {
            scheduled.unwrap_or_else(|e| panic!("{format:?}: {e}"));
            run_frame(&f.host, &ctx, &mut c).unwrap();
            if format == vk::Format::R32G32B32A32_SFLOAT {
                let got = f.host.read_image_f32(&out, vk::ImageLayout::GENERAL).unwrap();
                assert_eq!(got, reference, "frame 5's AO written to {format:?}");
            }
            written += 1;
        } else {
            match scheduled {
                Err(Error::UnsupportedFormat { format: refused, .. }) => assert_eq!(refused, format),
                other => panic!("{format:?} without formatless writes: expected UnsupportedFormat, got {other:?}"),
            }
        }
        f.host.destroy_image(out);
    }
    assert!(written >= 2, "the device writes R32F and RGBA32F outputs ({written} formats written)");
    drop(ctx);
    f.images.destroy(&f.host);
}

/// The two checkerboard modes of one frame trace complementary halves of the pixels — each
/// pixel exactly once between them, in a checker pattern — and the halves swap with the frame.
#[test]
fn checkerboard_and_inverted_checkerboard_trace_complementary_halves() {
    let f = Frame::new();
    let ctx = f.context(0);
    let (w, h) = (f.images.width as usize, f.images.height as usize);
    // Which pixels a mode traces in a frame: the output starts at -1 and keeps it where untouched.
    let traced = |mode, frame| -> Vec<bool> {
        let untouched: Vec<u8> = (0..w * h).flat_map(|_| (-1.0f32).to_ne_bytes()).collect();
        f.host.write_image(&f.images.output, &untouched, vk::ImageLayout::GENERAL).unwrap();
        f.ao_in_mode(&ctx, Some(frame), mode).iter().map(|v| *v >= 0.0).collect()
    };
    let all = traced(HalfResolutionMode::Off, 4);
    assert!(all.iter().all(|t| *t), "without checkerboard every pixel is traced");
    let even = traced(HalfResolutionMode::Checkerboard, 4);
    let odd = traced(HalfResolutionMode::CheckerboardInverted, 4);
    for (i, (e, o)) in even.iter().zip(&odd).enumerate() {
        let (x, y) = (i % w, i / w);
        assert_eq!(*e, (x + y + 4) % 2 == 0, "Checkerboard at ({x}, {y})");
        assert_ne!(e, o, "({x}, {y}): traced by exactly one of the two modes");
    }
    assert_eq!(traced(HalfResolutionMode::Checkerboard, 5), odd, "the next frame traces the other half");
    drop(ctx);
    f.images.destroy(&f.host);
}

/// Scheduling on eight threads while another thread holds the context for a long time (a
/// build that registers 60,000 instances: applying them, the TLAS snapshot, the instance
/// table): no schedule call waits for it.
#[test]
fn scheduling_does_not_wait_for_a_build_or_completion_in_progress() {
    let f = Frame::new();
    let ctx = f.host.create_context(&InitSettings::default()).unwrap();
    let quad = Mesh::grid(1.0, 1);
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    let vb = f.host.buffer_with_data(bytemuck::cast_slice(&quad.positions), usage).unwrap();
    let ib = f.host.buffer_with_data(bytemuck::cast_slice(&quad.indices), usage).unwrap();
    let g = ctx.create_geometry_handles(1)[0];
    let mut c = ctx.create_task_container();
    // SAFETY: the engine's buffers the task names are alive.
    unsafe {
        c.schedule_geometry(&GeometryTask {
            handle: g,
            operation: TaskOperation::Register,
            input: GeometryInput {
                vertices: VertexBufferInput { buffer: vb.buffer, count: quad.positions.len() as u32, ..Default::default() },
                indices: IndexBufferInput { buffer: ib.buffer, count: quad.indices.len() as u32, ..Default::default() },
                ..Default::default()
            },
        })
    }
    .unwrap();
    c.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&f.host, &ctx, &mut c).unwrap();
    let many = ctx.create_instance_handles(60_000);
    for (k, &handle) in many.iter().enumerate() {
        let transform = Affine3A::from_translation(Vec3::new((k % 300) as f32 * 2.0, 0.0, (k / 300) as f32 * 2.0));
        let input = InstanceInput { geometry: g, transform, ..Default::default() };
        c.schedule_instance(&InstanceTask { handle, operation: InstanceOperation::Register, input }).unwrap();
    }
    c.schedule_bvh_build(&Default::default()).unwrap();

    let task = f.images.ao_task(&f.camera, 1.0, 1);
    let instance = ctx.create_instance_handles(1)[0];
    let cmd = f.host.allocate_command_buffer().unwrap();
    f.host.begin(cmd).unwrap();
    let (slow, worst, ticket) = std::thread::scope(|s| {
        let ctx = &ctx;
        let c = &mut c;
        let slow = s.spawn(move || {
            let t = Instant::now();
            // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
            let ticket = unsafe { ctx.build_gpu_task(c, cmd) }.unwrap();
            (t.elapsed(), ticket)
        });
        let schedulers: Vec<_> = (0..8)
            .map(|_| {
                s.spawn(move || {
                    let mut c = ctx.create_task_container();
                    let mut worst = Duration::ZERO;
                    let until = Instant::now() + Duration::from_millis(150);
                    while Instant::now() < until {
                        let t = Instant::now();
                        c.schedule_ambient_occlusion(&task).unwrap();
                        c.schedule_clear_cache(&ClearCacheTask { instance }).unwrap();
                        worst = worst.max(t.elapsed());
                        c.clear();
                    }
                    worst
                })
            })
            .collect();
        let worst = schedulers.into_iter().map(|h| h.join().unwrap()).max().unwrap();
        let (slow, ticket) = slow.join().unwrap();
        (slow, worst, ticket)
    });
    f.host.full_barrier(cmd);
    let fence = f.host.submit(cmd).unwrap();
    f.host.wait(fence).unwrap();
    ctx.mark_gpu_task_completed(ticket).unwrap();
    eprintln!("a build registering 60,000 instances: {slow:?}; slowest schedule call on 8 threads: {worst:?}");
    assert!(slow > Duration::from_millis(100), "the held operation is long enough to tell ({slow:?})");
    assert!(worst < slow / 4, "a schedule call waited for it ({worst:?} vs {slow:?})");
    ctx.destroy_instance_handles(&[instance]).unwrap();
    ctx.destroy_instance_handles(&many).unwrap();
    ctx.destroy_geometry_handles(&[g]).unwrap();
    drop(ctx);
    f.host.destroy_buffer(vb);
    f.host.destroy_buffer(ib);
    f.images.destroy(&f.host);
}

/// Destroying the context while the GPU may still run a ticket is refused (the context comes
/// back, usable); once the ticket's commands ran it goes. Before, dropping it freed memory
/// the GPU could still be using — from safe code.
#[test]
fn the_context_is_not_destroyed_under_the_gpu() {
    let f = Frame::new();
    let ctx = f.context(0);
    let mut c = ctx.create_task_container();
    c.schedule_ambient_occlusion(&f.images.ao_task(&f.camera, 1.0, 1)).unwrap();
    let cmd = f.host.allocate_command_buffer().unwrap();
    f.host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(&mut c, cmd) }.unwrap();
    let (ctx, e) = ctx.destroy().expect_err("refused: the ticket has not run");
    assert!(matches!(&e, Error::TicketsInFlight { serials } if serials == &[ticket.serial()]), "{e}");
    assert_eq!(ctx.unfinished_tickets(), vec![ticket.serial()]);
    f.host.full_barrier(cmd);
    let fence = f.host.submit(cmd).unwrap();
    f.host.wait(fence).unwrap();
    assert!(ctx.unfinished_tickets().is_empty(), "the GPU ran it (the engine has not handed it back)");
    ctx.mark_gpu_task_completed(ticket).unwrap();
    ctx.destroy().map_err(|(_, e)| e).expect("nothing in flight");
    f.images.destroy(&f.host);
}

/// Contexts made through an engine-owned pipeline cache: the second finds every pipeline in it.
#[test]
fn pipelines_come_from_the_engines_cache() {
    let host = Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)");
    let cache = unsafe { host.device.create_pipeline_cache(&vk::PipelineCacheCreateInfo::default(), None) }.unwrap();
    let settings = InitSettings { pipeline_cache: cache, ..Default::default() };
    let t = Instant::now();
    drop(host.create_context(&settings).unwrap());
    let cold = t.elapsed();
    let data = unsafe { host.device.get_pipeline_cache_data(cache) }.unwrap();
    // A cache header is 32 bytes; lavapipe (LLVM) keeps no pipelines in caches, drivers do.
    assert!(data.len() >= 32, "a valid cache ({} bytes)", data.len());
    if !host.is_lavapipe() {
        assert!(data.len() > 1024, "the SDK's pipelines went into the engine's cache ({} bytes)", data.len());
    }
    // A new cache from the saved data, as on the next run of the engine.
    let warm_cache =
        unsafe { host.device.create_pipeline_cache(&vk::PipelineCacheCreateInfo::default().initial_data(&data), None) }.unwrap();
    let t = Instant::now();
    let ctx = host.create_context(&InitSettings { pipeline_cache: warm_cache, ..Default::default() }).unwrap();
    let warm = t.elapsed();
    eprintln!("context creation on {}: cold {cold:?}, warm {warm:?} ({} bytes of cache)", host.device_name, data.len());
    drop(ctx);
    unsafe {
        host.device.destroy_pipeline_cache(cache, None);
        host.device.destroy_pipeline_cache(warm_cache, None);
    }
}

/// BVH work recorded into a command buffer of an async-compute queue (where the device has a
/// second compute family; lavapipe has one, so there the two command buffers share the queue)
/// and tracing into the graphics queue's, ordered by a semaphore: the same image as one
/// container on one queue. With two families, SDK memory is CONCURRENT over both (no ownership
/// transfers); synchronization validation checks the rest.
#[test]
fn bvh_work_on_an_async_compute_queue_then_tracing_on_graphics() {
    let f = Frame::new();
    let host = &f.host;
    let mut families = [host.queue_family, 0, 0, 0];
    let count = match &host.async_compute {
        Some(a) => {
            families[1] = a.family;
            2
        }
        None => 1,
    };
    let settings = InitSettings { queue_family_indices: families, queue_family_count: count, ..Default::default() };
    let ctx = host.create_context(&settings).unwrap();
    let d = &host.device;

    // Frame 1 on two queues: BVH (async compute) -> semaphore -> AO (graphics).
    let mut bvh = ctx.create_task_container();
    let s = SceneOnGpu::register(host, &ctx, &mut bvh, &f.scene).unwrap();
    bvh.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
    bvh.set_frame_index(1);
    let (queue, pool) = host.async_compute.as_ref().map_or((host.queue, None), |a| (a.queue, Some(a.pool)));
    let cmd_bvh = match pool {
        Some(pool) => unsafe {
            d.allocate_command_buffers(&vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1))
        }
        .unwrap()[0],
        None => host.allocate_command_buffer().unwrap(),
    };
    host.begin(cmd_bvh).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let t_bvh = unsafe { ctx.build_gpu_task(&mut bvh, cmd_bvh) }.unwrap();
    let semaphore = unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.unwrap();
    unsafe {
        d.end_command_buffer(cmd_bvh).unwrap();
        let (cmds, signals) = ([cmd_bvh], [semaphore]);
        d.queue_submit(queue, &[vk::SubmitInfo::default().command_buffers(&cmds).signal_semaphores(&signals)], vk::Fence::null())
            .unwrap();
    }
    let mut trace = ctx.create_task_container();
    trace.set_frame_index(1);
    trace.schedule_ambient_occlusion(&f.images.ao_task(&f.camera, 1.0, 2)).unwrap();
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let t_trace = unsafe { ctx.build_gpu_task(&mut trace, cmd) }.unwrap();
    host.full_barrier(cmd);
    unsafe {
        d.end_command_buffer(cmd).unwrap();
        let (cmds, waits, stages) = ([cmd], [semaphore], [vk::PipelineStageFlags::ALL_COMMANDS]);
        let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
        d.queue_submit(
            host.queue,
            &[vk::SubmitInfo::default().command_buffers(&cmds).wait_semaphores(&waits).wait_dst_stage_mask(&stages)],
            fence,
        )
        .unwrap();
        d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
        d.destroy_fence(fence, None);
        d.device_wait_idle().unwrap();
    }
    ctx.mark_gpu_task_completed(t_bvh).unwrap();
    ctx.mark_gpu_task_completed(t_trace).unwrap();
    let two_queues = f.images.read_output(host).unwrap();

    // The same frame in one container on one queue, on another context.
    let one = f.context(0);
    let expected = f.ao(&one, Some(1), false);
    assert_eq!(two_queues, expected, "BVH on {} queue(s) then tracing: the same image", count);
    unsafe {
        d.destroy_semaphore(semaphore, None);
        if let Some(pool) = pool {
            d.free_command_buffers(pool, &[cmd_bvh]);
        }
    }
    drop(one);
    drop(ctx);
    s.destroy(host);
    f.images.destroy(host);
}
