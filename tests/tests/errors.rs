//! Every public entry point refuses bad input with a typed error and leaves the context usable.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Mat4, Vec3};
use hybrid_rt::{
    BvhBuildTask, DenoiseDiffuseOcclusionTask, DenoisingCommon, DenoisingContextInput, Error, GeometryInput, GeometryTask,
    GpuTicket, HandleProblem, IndexBufferInput, InitSettings, InstanceHandle, InstanceInput, InstanceOperation, InstanceTask,
    SignalType, TaskOperation, TraceAmbientOcclusionTask, VertexBufferInput,
};
use hybrid_rt_testkit::sdk_scene::*;

fn triangle_buffers(
    host: &hybrid_rt_testkit::host::Host,
) -> (hybrid_rt_testkit::host::HostBuffer, hybrid_rt_testkit::host::HostBuffer) {
    let v = [Vec3::ZERO, Vec3::X, Vec3::Z];
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    (
        host.buffer_with_data(bytemuck::cast_slice(&v), usage).unwrap(),
        host.buffer_with_data(bytemuck::cast_slice(&[0u32, 1, 2]), usage).unwrap(),
    )
}

/// A small working scene rendered after every refusal: the context must still work.
fn render_ok(host: &hybrid_rt_testkit::host::Host, ctx: &hybrid_rt::ExecuteContext) {
    let (scene, camera, images) = ground_view(host);
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(host, ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, 1)).unwrap();
    run_frame(host, ctx, &mut frame).unwrap();
    assert!(images.read_output(host).unwrap().iter().all(|v| *v > 0.999));
    ctx.destroy_instance_handles(&s.instances).unwrap();
    ctx.destroy_geometry_handles(&s.geometries).unwrap();
    images.destroy(host);
    s.destroy(host);
}

#[test]
fn bad_geometry_inputs_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (vb, ib) = triangle_buffers(&host);
    let h = ctx.create_geometry_handles(1)[0];
    let good = GeometryInput {
        vertices: VertexBufferInput { buffer: vb.buffer, count: 3, ..Default::default() },
        indices: IndexBufferInput { buffer: ib.buffer, count: 3, ..Default::default() },
        ..Default::default()
    };
    let mut c = ctx.create_task_container();
    let task = |input| GeometryTask { handle: h, operation: TaskOperation::Register, input };
    let cases: Vec<(&str, GeometryInput)> = vec![
        (
            "null vertex buffer",
            GeometryInput { vertices: VertexBufferInput { buffer: vk::Buffer::null(), ..good.vertices }, ..good.clone() },
        ),
        ("zero vertices", GeometryInput { vertices: VertexBufferInput { count: 0, ..good.vertices }, ..good.clone() }),
        ("stride 8", GeometryInput { vertices: VertexBufferInput { stride: 8, ..good.vertices }, ..good.clone() }),
        ("index count 4", GeometryInput { indices: IndexBufferInput { count: 4, ..good.indices }, ..good.clone() }),
        (
            "zero tile unit",
            GeometryInput { surfels: hybrid_rt::SurfelSettings { tile_unit_length: 0.0, ..Default::default() }, ..good.clone() },
        ),
    ];
    for (what, input) in cases {
        // SAFETY: the engine's buffers the task names are alive.
        let e = unsafe { c.schedule_geometry(&task(input)) }.unwrap_err();
        assert!(matches!(e, Error::InvalidInput { .. }), "{what}: {e}");
    }
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&task(GeometryInput {
            vertices: VertexBufferInput { format: vk::Format::R16G16B16A16_SFLOAT, ..good.vertices },
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(matches!(e, Error::UnsupportedFormat { .. }), "{e}");
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&task(GeometryInput {
            indices: IndexBufferInput { format: vk::Format::R8_UINT, ..good.indices },
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(matches!(e, Error::UnsupportedFormat { .. }), "{e}");
    // 3 vertices of 12 bytes fit; a million do not.
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&task(GeometryInput {
            vertices: VertexBufferInput { count: 999_999, ..good.vertices },
            indices: IndexBufferInput { buffer: vk::Buffer::null(), ..good.indices },
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(matches!(e, Error::BufferTooSmall { .. }), "{e}");
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&task(GeometryInput {
            indices: IndexBufferInput { offset: 1 << 20, ..good.indices },
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(matches!(e, Error::BufferTooSmall { .. }), "{e}");
    assert!(c.is_empty(), "refused tasks are not scheduled");

    // Registering twice: the second register is refused when the container is built, and
    // the failed build leaves the container (and the context) as they were.
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { c.schedule_geometry(&task(good.clone())) }.unwrap();
    run_frame(&host, &ctx, &mut c).unwrap();
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { c.schedule_geometry(&task(good.clone())) }.unwrap();
    let e = run_frame(&host, &ctx, &mut c).unwrap_err();
    assert!(e.contains("already registered"), "{e}");
    assert_eq!(c.len(), 1, "a failed build keeps the tasks");
    c.clear();
    // An update of a never-registered handle.
    let fresh = ctx.create_geometry_handles(1)[0];
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { c.schedule_geometry(&GeometryTask { handle: fresh, operation: TaskOperation::Update, input: good.clone() }) }
        .unwrap();
    assert!(run_frame(&host, &ctx, &mut c).unwrap_err().contains("not registered"));
    c.clear();

    ctx.destroy_geometry_handles(&[h, fresh]).unwrap();
    host.destroy_buffer(vb);
    host.destroy_buffer(ib);
    render_ok(&host, &ctx);
    drop(ctx);
    assert_no_validation_errors();
}

#[test]
fn stale_foreign_and_null_handles_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let other = host.create_context(&InitSettings::default()).unwrap();
    let (vb, _ib) = triangle_buffers(&host);
    let input =
        GeometryInput { vertices: VertexBufferInput { buffer: vb.buffer, count: 3, ..Default::default() }, ..Default::default() };
    let mut c = ctx.create_task_container();

    let stale = ctx.create_geometry_handles(1)[0];
    ctx.destroy_geometry_handles(&[stale]).unwrap();
    let problem = |e: Error| match e {
        Error::InvalidHandle { problem, .. } => problem,
        e => panic!("expected InvalidHandle, got {e}"),
    };
    let t = |handle| GeometryTask { handle, operation: TaskOperation::Register, input: input.clone() };
    // SAFETY: the engine's buffers the task names are alive.
    assert_eq!(problem(unsafe { c.schedule_geometry(&t(stale)) }.unwrap_err()), HandleProblem::Destroyed);
    // SAFETY: the engine's buffers the task names are alive.
    assert_eq!(problem(unsafe { c.schedule_geometry(&t(hybrid_rt::GeometryHandle::NULL)) }.unwrap_err()), HandleProblem::Null);
    let foreign = other.create_geometry_handles(1)[0];
    // SAFETY: the engine's buffers the task names are alive.
    assert_eq!(problem(unsafe { c.schedule_geometry(&t(foreign)) }.unwrap_err()), HandleProblem::Foreign);
    assert_eq!(problem(ctx.destroy_geometry_handles(&[stale]).unwrap_err()), HandleProblem::Destroyed);
    // Destroying a handle twice in one call is refused, and destroys nothing.
    let a = ctx.create_geometry_handles(1)[0];
    assert!(ctx.destroy_geometry_handles(&[a, a]).is_err());
    ctx.destroy_geometry_handles(&[a]).unwrap();

    // A handle destroyed after scheduling is caught when the container is built.
    let late = ctx.create_geometry_handles(1)[0];
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { c.schedule_geometry(&t(late)) }.unwrap();
    ctx.destroy_geometry_handles(&[late]).unwrap();
    assert!(run_frame(&host, &ctx, &mut c).unwrap_err().contains("destroyed"));
    c.clear();

    // An instance of an unregistered geometry.
    let g = ctx.create_geometry_handles(1)[0];
    let i = ctx.create_instance_handles(1)[0];
    c.schedule_instance(&InstanceTask {
        handle: i,
        operation: InstanceOperation::Register,
        input: InstanceInput { geometry: g, ..Default::default() },
    })
    .unwrap();
    assert!(run_frame(&host, &ctx, &mut c).unwrap_err().contains("not registered"));
    c.clear();
    // Removing an instance that was never registered.
    c.schedule_instance(&InstanceTask { handle: i, operation: InstanceOperation::Remove, ..Default::default() }).unwrap();
    assert!(run_frame(&host, &ctx, &mut c).unwrap_err().contains("not registered"));
    c.clear();

    // A container of another context.
    let mut foreign_container = other.create_task_container();
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    assert!(matches!(unsafe { ctx.build_gpu_task(&mut foreign_container, cmd) }, Err(Error::ForeignContainer)));
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    assert!(matches!(unsafe { ctx.build_gpu_task(&mut c, vk::CommandBuffer::null()) }, Err(Error::InvalidInput { .. })));
    unsafe { host.device.end_command_buffer(cmd).unwrap() };

    ctx.destroy_instance_handles(&[i]).unwrap();
    ctx.destroy_geometry_handles(&[g]).unwrap();
    host.destroy_buffer(vb);
    host.destroy_buffer(_ib);
    render_ok(&host, &ctx);
    drop(other);
    // A container that outlives its context: the context's GPU objects are gone at once (the
    // engine may destroy its device next), and the container refuses politely.
    drop(ctx);
    assert!(matches!(foreign_container.schedule_bvh_build(&BvhBuildTask::default()), Err(Error::ContextDestroyed)));
    drop(host);
    drop(foreign_container);
    drop(c);
    assert_no_validation_errors();
}

#[test]
fn non_finite_transforms_and_cameras_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let g = ctx.create_geometry_handles(1)[0];
    let i = ctx.create_instance_handles(1)[0];
    let mut c = ctx.create_task_container();
    for t in [
        Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
        Affine3A::from_scale(Vec3::new(1.0, f32::INFINITY, 1.0)),
        Affine3A::from_scale(Vec3::ZERO),
    ] {
        let e = c
            .schedule_instance(&InstanceTask {
                handle: i,
                operation: InstanceOperation::Register,
                input: InstanceInput { geometry: g, transform: t, ..Default::default() },
            })
            .unwrap_err();
        assert!(matches!(e, Error::InvalidTransform { .. }), "{e}");
    }

    // AO task validation: camera, viewport, formats, layouts, parameters.
    let (_, camera, images) = ground_view(&host);
    let good = images.ao_task(&camera, 1.0, 1);
    let mut bad = good;
    bad.common.camera.world_to_view = Mat4::from_cols_array(&[f32::NAN; 16]);
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidTransform { .. }));
    bad = good;
    bad.common.camera.view_to_clip = Mat4::ZERO;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidTransform { .. }));
    bad = good;
    bad.common.viewport.width = 17;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }));
    bad = good;
    bad.common.viewport.height = 0;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }));
    bad = good;
    bad.output.format = vk::Format::R32G32_SFLOAT;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::UnsupportedFormat { .. }));
    bad = good;
    bad.output.layout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }));
    bad = good;
    bad.common.depth.image.format = vk::Format::R8G8B8A8_UNORM;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::UnsupportedFormat { .. }));
    bad = good;
    bad.common.normals.image.format = vk::Format::R32G32_SFLOAT; // RGB vector needs 3 channels
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::UnsupportedFormat { .. }));
    bad = good;
    bad.common.depth.image.view = vk::ImageView::null();
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }));
    // Roughness remap: 0 <= min <= max <= 1, no NaN.
    for (min, max) in [(0.5, 0.4), (-0.1, 1.0), (0.0, 1.5), (f32::NAN, 1.0), (0.0, f32::NAN)] {
        bad = good;
        bad.common.roughness.min_roughness = min;
        bad.common.roughness.max_roughness = max;
        assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }), "{min} {max}");
    }
    // A custom normal basis must be finite and invertible.
    for m in [glam::Mat3::ZERO, glam::Mat3::from_cols_array(&[f32::NAN; 9])] {
        bad = good;
        bad.common.normals.space = hybrid_rt::NormalSpace::Custom;
        bad.common.normals.normal_to_world = m;
        assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidTransform { .. }));
    }
    // Input mask: a sampled colour format with R, covering the viewport.
    bad = good;
    bad.common.input_mask = good.common.depth.image;
    bad.common.input_mask.format = vk::Format::R32_UINT;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::UnsupportedFormat { .. }));
    bad.common.input_mask.format = vk::Format::R32_SFLOAT;
    bad.common.input_mask.width = 8;
    assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }));
    for (rays, len, power) in [(0, 1.0, 1.0), (65, 1.0, 1.0), (1, -1.0, 1.0), (1, f32::NAN, 1.0), (1, 1.0, 0.0)] {
        bad = good;
        bad.rays_per_pixel = rays;
        bad.ray_length = len;
        bad.falloff_power = power;
        assert!(matches!(c.schedule_ambient_occlusion(&bad).unwrap_err(), Error::InvalidInput { .. }), "{rays} {len} {power}");
    }
    // A denoise task's G-buffer errors name `DenoisingCommon`, the struct the engine filled
    // (the checks are the trace tasks').
    let dn = ctx
        .create_denoising_context(&DenoisingContextInput {
            max_width: 16,
            max_height: 16,
            signal: SignalType::DiffuseOcclusion,
            ..Default::default()
        })
        .unwrap();
    let task = |common| DenoiseDiffuseOcclusionTask { context: dn, common, input: good.output, output: good.output };
    // Each spoils one field of a good `DenoisingCommon`; the field the error must name.
    type Spoiler = (fn(&mut DenoisingCommon), &'static str);
    let spoilers: [Spoiler; 4] = [
        (
            |d| {
                d.input_mask = d.depth.image;
                d.input_mask.format = vk::Format::R32_UINT;
            },
            "DenoisingCommon.input_mask.format",
        ),
        (
            |d| {
                d.roughness.min_roughness = 0.5;
                d.roughness.max_roughness = 0.4;
            },
            "DenoisingCommon.roughness",
        ),
        (
            |d| {
                d.normals.space = hybrid_rt::NormalSpace::Custom;
                d.normals.normal_to_world = glam::Mat3::ZERO;
            },
            "DenoisingCommon.normals.normal_to_world",
        ),
        (|d| d.depth.image.view = vk::ImageView::null(), "DenoisingCommon.depth.image"),
    ];
    for (spoil, field) in spoilers {
        let mut common = images.denoising_common(&camera);
        spoil(&mut common);
        let e = c.schedule_denoise_diffuse_occlusion(&task(common)).unwrap_err().to_string();
        assert!(e.contains(field) && !e.contains("TraceCommon"), "{field}: {e}");
    }
    ctx.destroy_denoising_context(dn).unwrap();
    assert!(c.is_empty());
    c.schedule_ambient_occlusion(&good).unwrap();
    c.clear();
    images.destroy(&host);
    render_ok(&host, &ctx);
    drop(ctx);
    assert_no_validation_errors();
}

#[test]
fn tickets_working_sets_and_settings() {
    assert!(matches!(
        hybrid_rt_testkit::host::Host::new()
            .unwrap()
            .create_context(&InitSettings { supported_working_sets: 0, ..Default::default() }),
        Err(Error::InvalidInput { .. })
    ));
    let (host, ctx) = host_and_context(InitSettings { supported_working_sets: 1, ..Default::default() });
    let mut c = ctx.create_task_container();
    c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(&mut c, cmd) }.unwrap();
    assert!(c.is_empty());

    // The only working set is in flight: the next build is refused and records nothing.
    c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
    let cmd2 = host.allocate_command_buffer().unwrap();
    host.begin(cmd2).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    assert!(matches!(unsafe { ctx.build_gpu_task(&mut c, cmd2) }, Err(Error::WorkingSetsExhausted { in_flight: 1 })));
    assert_eq!(c.len(), 1, "the refused container keeps its tasks for the next try");
    assert_eq!(ctx.tickets_in_flight(), vec![ticket.serial()]);

    let fence = host.submit(cmd).unwrap();
    host.wait(fence).unwrap();
    let raw = ticket.into_raw();
    let done = ctx.mark_gpu_task_completed(GpuTicket::from_raw(raw)).unwrap();
    assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::Bvh));
    // The same ticket again, and a forged one.
    assert!(matches!(ctx.mark_gpu_task_completed(GpuTicket::from_raw(raw)), Err(Error::UnknownTicket { .. })));
    assert!(matches!(ctx.mark_gpu_task_completed(GpuTicket::from_raw(raw + 7)), Err(Error::UnknownTicket { .. })));

    // Now the retry goes through.
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(&mut c, cmd2) }.unwrap();
    let fence = host.submit(cmd2).unwrap();
    host.wait(fence).unwrap();
    ctx.mark_gpu_task_completed(ticket).unwrap();
    render_ok(&host, &ctx);
    drop(ctx);
    assert_no_validation_errors();
}

/// After a device loss the engine's tickets never come back: `destroy` refuses (the GPU might
/// still run them, as far as the SDK can tell), and `destroy_after_device_lost` frees every
/// object at once without waiting. The validation layer, which checks at the device's
/// destruction that every object made on it was destroyed, sees nothing left behind (a plain
/// drop with tickets out leaks them on purpose).
#[test]
fn a_lost_device_tears_the_context_down_without_its_tickets() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera, images) = ground_view(&host);
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, 1)).unwrap();
    // The device is lost before the engine submits (or while the GPU runs it): the ticket's
    // command buffer never finishes.
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let _ticket = unsafe { ctx.build_gpu_task(&mut frame, cmd) }.unwrap();
    unsafe { host.device.end_command_buffer(cmd) }.unwrap();
    let (ctx, e) = ctx.destroy().unwrap_err();
    assert!(matches!(e, Error::TicketsInFlight { .. }), "{e}");
    assert_eq!(ctx.unfinished_tickets().len(), 1);
    // SAFETY: the ticket's command buffer is never submitted.
    unsafe { ctx.destroy_after_device_lost() };
    images.destroy(&host);
    s.destroy(&host);
    drop(host);
    assert_no_validation_errors();
}

/// A name given with `set_instance_name` is quoted in the errors about that instance.
#[test]
fn an_instance_name_is_quoted_in_its_errors() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let i = ctx.create_instance_handles(1)[0];
    let g = ctx.create_geometry_handles(1)[0];
    ctx.set_instance_name(i, "left wall").unwrap();
    let mut frame = ctx.create_task_container();
    // Updating an instance that was never registered: refused when the container is built.
    let input = InstanceInput { geometry: g, ..Default::default() };
    frame.schedule_instance(&InstanceTask { handle: i, operation: InstanceOperation::Update, input }).unwrap();
    let e = run_frame(&host, &ctx, &mut frame).unwrap_err();
    assert!(e.contains("\"left wall\"") && e.contains("not registered"), "{e}");
    assert!(matches!(ctx.set_instance_name(InstanceHandle::NULL, "x"), Err(Error::InvalidHandle { .. })));
    render_ok(&host, &ctx);
    drop(ctx);
    drop(host);
    assert_no_validation_errors();
}

/// `InitSettings::max_timed_tasks` bounds a ticket's timed intervals (two more go to the BVH
/// and cache work); the tasks past it run untimed, their images made all the same.
#[test]
fn tasks_past_max_timed_tasks_run_untimed() {
    let (host, ctx) = host_and_context(InitSettings { max_timed_tasks: 2, ..Default::default() });
    let (scene, camera, images) = ground_view(&host);
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let outputs: Vec<_> = (0..4)
        .map(|_| {
            host.image_cleared(vk::Format::R32_SFLOAT, 16, 16, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap()
        })
        .collect();
    for out in &outputs {
        let task = TraceAmbientOcclusionTask { output: out.input(vk::ImageLayout::GENERAL), ..images.ao_task(&camera, 1.0, 1) };
        frame.schedule_ambient_occlusion(&task).unwrap();
    }
    let done = run_frame(&host, &ctx, &mut frame).unwrap();
    let timed = done.timings.iter().filter(|t| t.kind == hybrid_rt::TaskKind::AmbientOcclusion).count();
    assert_eq!(done.timings.len(), 2 + 2, "{:?}", done.timings);
    assert!(timed < 4, "the fourth AO task runs untimed: {:?}", done.timings);
    for out in outputs {
        let ao: Vec<f32> = bytemuck::cast_slice(&host.read_image(&out, vk::ImageLayout::GENERAL).unwrap()).to_vec();
        assert!(ao.iter().all(|v| *v > 0.999), "every AO task ran, timed or not");
        host.destroy_image(out);
    }
    ctx.destroy_instance_handles(&s.instances).unwrap();
    ctx.destroy_geometry_handles(&s.geometries).unwrap();
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    drop(host);
    assert_no_validation_errors();
}
