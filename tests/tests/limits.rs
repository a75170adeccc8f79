//! Inputs that used to reach the driver unchecked (every case crashed the driver, panicked in a
//! debug build, or was accepted silently): each is now a typed error naming the field and the
//! limit, or is made safe on the GPU and reported — and the context keeps working. The suite
//! runs in debug builds, so an overflow panic in any of them fails here.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostBuffer};
use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;

fn buffer(host: &Host, bytes: &[u8]) -> HostBuffer {
    host.buffer_with_data(bytes, vk::BufferUsageFlags::TRANSFER_SRC).unwrap()
}

fn message(e: &Error) -> String {
    e.to_string()
}

#[test]
fn sizes_and_counts_past_the_device_limits_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let v = buffer(&host, bytemuck::cast_slice(&[Vec3::ZERO, Vec3::X, Vec3::Z]));
    let i = buffer(&host, bytemuck::cast_slice(&[0u32, 1, 2]));
    let h = ctx.create_geometry_handles(1)[0];
    let mut c = ctx.create_task_container();
    let good = GeometryInput {
        vertices: VertexBufferInput { buffer: v.buffer, count: 3, ..Default::default() },
        indices: IndexBufferInput { buffer: i.buffer, count: 3, ..Default::default() },
        ..Default::default()
    };
    let register = |input| GeometryTask { handle: h, operation: TaskOperation::Register, input };

    // A stride of 2^63: stride x (count - 1) once overflowed, the region check passed, and a
    // debug build panicked ("attempt to multiply with overflow"). Strides are now below 4 GiB.
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&register(GeometryInput {
            vertices: VertexBufferInput { stride: 1 << 63, ..good.vertices },
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(matches!(e, Error::InvalidInput { .. }) && message(&e).contains("stride"), "{e}");
    // An offset near 2^64 plus the vertex range's start overflows: refused, named.
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&register(GeometryInput {
            vertices: VertexBufferInput { offset: u64::MAX - 4, ..good.vertices },
            vertex_range: Some(hybrid_rt::VertexRange { first: 1, last: 2 }),
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(matches!(e, Error::InvalidInput { .. }) && message(&e).contains("overflow"), "{e}");

    // More triangles than any BLAS may hold (checked before the buffers' sizes).
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe {
        c.schedule_geometry(&register(GeometryInput {
            indices: IndexBufferInput { count: u32::MAX / 3 * 3, ..good.indices },
            ..good.clone()
        }))
    }
    .unwrap_err();
    assert!(message(&e).contains("maxPrimitiveCount"), "{e}");
    assert!(c.is_empty());

    // An upload ring larger than any buffer the device can make.
    let settings = InitSettings { upload_ring_bytes: u64::MAX / 2, ..Default::default() };
    let e = host.create_context(&settings).expect_err("refused");
    assert!(matches!(e, Error::InvalidInput { .. }) && message(&e).contains("maxBufferSize"), "{e}");

    // A launch past the ray-dispatch and compute-group limits (the images are checked after).
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(4.0, 1));
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 0.01), Vec3::ZERO);
    let images = GBufferImages::upload(&host, &GBuffer::render(&Tracer::new(&scene), &camera, 8, 8)).unwrap();
    let mut ao = images.ao_task(&camera, 1.0, 1);
    ao.common.viewport = Viewport::full(1 << 20, 1 << 20);
    let e = c.schedule_ambient_occlusion(&ao).unwrap_err();
    assert!(message(&e).contains("maxRayDispatchInvocationCount") || message(&e).contains("maxComputeWorkGroupCount"), "{e}");

    // A denoising context larger than the device's images.
    let e = ctx
        .create_denoising_context(&DenoisingContextInput { max_width: 16384, max_height: 16384, ..Default::default() })
        .map(|_| ())
        .err();
    if let Some(e) = e {
        assert!(matches!(e, Error::InvalidInput { .. } | Error::OutOfMemory { .. }), "{e}");
    }

    // Injection with a NaN depth range (trace tasks refused it; injection did not).
    let inject = DirectLightingInjectionTask {
        depth: DepthInput { image: images.depth.input(READ), depth_type: DepthType::ClipSpace },
        lit: images.normals.input(READ),
        viewport: Viewport { min_depth: f32::NAN, ..Viewport::full(8, 8) },
        camera: camera.sdk_camera(8, 8),
        ..Default::default()
    };
    let e = c.schedule_direct_lighting_injection(&inject).unwrap_err();
    assert!(message(&e).contains("depth range"), "{e}");

    // An output without STORAGE usage crashed at the descriptor write: Vulkan cannot report an
    // image's usage, so ImageInput declares it and the SDK checks it.
    let mut no_storage = images.ao_task(&camera, 1.0, 1);
    no_storage.output.usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
    let e = c.schedule_ambient_occlusion(&no_storage).unwrap_err();
    assert!(message(&e).contains("STORAGE"), "{e}");
    let mut undeclared = images.ao_task(&camera, 1.0, 1);
    undeclared.common.depth.image.usage = vk::ImageUsageFlags::empty();
    let e = c.schedule_ambient_occlusion(&undeclared).unwrap_err();
    assert!(message(&e).contains("usage is empty"), "{e}");
    assert!(c.is_empty(), "refused tasks are not scheduled");

    images.destroy(&host);
    ctx.destroy_geometry_handles(&[h]).unwrap();
    host.destroy_buffer(v);
    host.destroy_buffer(i);
    drop(ctx);
}

/// An index past the vertex count (1,000,000 on a 3-vertex mesh) was copied and built as is:
/// undefined behaviour in the BLAS build. Now the index check makes such triangles degenerate
/// on the GPU and reports how many; 16-bit indices too, where two triangles share words.
#[test]
fn triangles_with_out_of_range_indices_are_dropped_and_reported() {
    let (host, ctx) = host_and_context(InitSettings::default());
    // A unit box (12 triangles): in 32 bits triangle 5 points far past its vertices; in 16
    // bits triangle 2 does too, and triangle 7 names the vertex count itself (the first index
    // past the end).
    let cube = Mesh::cuboid(Vec3::splat(0.5));
    let mut bad32: Vec<u32> = cube.indices.clone();
    bad32[5 * 3 + 1] = 1_000_000;
    let mut bad16: Vec<u16> = cube.indices.iter().map(|&i| i as u16).collect();
    bad16[2 * 3] = 60_000;
    bad16[7 * 3 + 2] = cube.positions.len() as u16;
    let v = buffer(&host, bytemuck::cast_slice(&cube.positions));
    let i32b = buffer(&host, bytemuck::cast_slice(&bad32));
    let i16b = buffer(&host, bytemuck::cast_slice(&bad16));
    let geometries = ctx.create_geometry_handles(2);
    let instances = ctx.create_instance_handles(2);
    let mut c = ctx.create_task_container();
    for (k, (ib, format, count)) in
        [(&i32b, vk::Format::R32_UINT, bad32.len()), (&i16b, vk::Format::R16_UINT, bad16.len())].into_iter().enumerate()
    {
        let input = GeometryInput {
            vertices: VertexBufferInput { buffer: v.buffer, count: cube.positions.len() as u32, ..Default::default() },
            indices: IndexBufferInput { buffer: ib.buffer, count: count as u32, format, ..Default::default() },
            ..Default::default()
        };
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { c.schedule_geometry(&GeometryTask { handle: geometries[k], operation: TaskOperation::Register, input }) }
            .unwrap();
        let transform = Affine3A::from_translation(Vec3::new(2.0 * k as f32 - 1.0, 0.5, 0.0));
        c.schedule_instance(&InstanceTask {
            handle: instances[k],
            operation: InstanceOperation::Register,
            input: InstanceInput { geometry: geometries[k], transform, ..Default::default() },
        })
        .unwrap();
    }
    // AO on a ground plane the boxes stand on: they must still occlude (11 and 10 good
    // triangles of 12), and nothing may crash or trip the validation layer.
    let mut ground = Scene::default();
    let g = ground.add_mesh(Mesh::grid(8.0, 1));
    ground.add_instance(g, Affine3A::IDENTITY);
    let b = ground.add_mesh(cube.clone());
    ground.add_instance(b, Affine3A::from_translation(Vec3::new(-1.0, 0.5, 0.0)));
    ground.add_instance(b, Affine3A::from_translation(Vec3::new(1.0, 0.5, 0.0)));
    let camera = Camera::look_at(Vec3::new(0.0, 6.0, 0.01), Vec3::ZERO);
    let gbuffer = GBuffer::render(&Tracer::new(&ground), &camera, 32, 32);
    let images = GBufferImages::upload(&host, &gbuffer).unwrap();
    c.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 8, ..Default::default() }).unwrap();
    c.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, 8)).unwrap();
    run_frame(&host, &ctx, &mut c).unwrap();
    assert_eq!(ctx.geometry_invalid_triangles(geometries[0]).unwrap(), 1, "one 32-bit triangle was bad");
    assert_eq!(ctx.geometry_invalid_triangles(geometries[1]).unwrap(), 2, "two 16-bit triangles were bad");
    let ao = images.read_output(&host).unwrap();
    let occluded = (0..ao.len()).filter(|&p| gbuffer.hit[p] && gbuffer.position[p].y.abs() < 1e-3 && ao[p] < 0.9).count();
    assert!(occluded > 10, "the boxes' good triangles still occlude the ground ({occluded} pixels)");
    images.destroy(&host);
    ctx.destroy_instance_handles(&instances).unwrap();
    ctx.destroy_geometry_handles(&geometries).unwrap();
    for b in [v, i32b, i16b] {
        host.destroy_buffer(b);
    }
    drop(ctx);
}

/// A cache over the sample budget was sized in u32 and wrapped (65,536 triangles x 256^2 tiles
/// made a 32-byte cache), and a cache of more than 65,535 x 256 samples was filled in one
/// dispatch past the group-count limit. 66,248 triangles at 16 x 16 tiles (17 M samples) now fill
/// in two dispatches, and a mesh asking for 256 x 256 tiles gets a coarser layout that fits.
#[test]
fn big_caches_fill_completely_and_oversized_ones_are_coarsened() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let grid = Mesh::grid(64.0, 182);
    assert!(grid.indices.len() / 3 * 256 > 65_535 * 256, "more samples than one dispatch covers");
    let v = buffer(&host, bytemuck::cast_slice(&grid.positions));
    let i = buffer(&host, bytemuck::cast_slice(&grid.indices));
    let geometries = ctx.create_geometry_handles(2);
    let instances = ctx.create_instance_handles(2);
    let magenta = [1.0, 0.0, 1.0];
    let mut c = ctx.create_task_container();
    // Edges are 64/182 = 0.35 long: a unit of 0.02 asks for 18 samples per edge, limited to 16
    // (256 per triangle); the second geometry asks for 256 x 256 tiles per triangle.
    for (k, limit) in [(0usize, 16u32), (1, 256)] {
        let input = GeometryInput {
            vertices: VertexBufferInput { buffer: v.buffer, count: grid.positions.len() as u32, ..Default::default() },
            indices: IndexBufferInput { buffer: i.buffer, count: grid.indices.len() as u32, ..Default::default() },
            surfels: SurfelSettings {
                surfel_type: SurfelType::Tiles,
                tile_unit_length: if k == 0 { 0.02 } else { 0.0001 },
                tile_resolution_limit: limit,
                ..Default::default()
            },
            ..Default::default()
        };
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { c.schedule_geometry(&GeometryTask { handle: geometries[k], operation: TaskOperation::Register, input }) }
            .unwrap();
        let input = InstanceInput {
            geometry: geometries[k],
            transform: Affine3A::from_translation(Vec3::new(0.0, -10.0 * k as f32, 0.0)),
            initial_tile_color: magenta,
            ..Default::default()
        };
        c.schedule_instance(&InstanceTask { handle: instances[k], operation: InstanceOperation::Register, input }).unwrap();
    }
    c.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 2, ..Default::default() }).unwrap();
    run_frame(&host, &ctx, &mut c).unwrap();
    // The layouts' sample counts come back with the ticket; the next recording allocates and
    // fills the caches. A count over the budget is laid out again at a smaller resolution
    // limit, one round trip per try.
    for _ in 0..4 {
        c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
        run_frame(&host, &ctx, &mut c).unwrap();
    }
    let bytes = ctx.instance_cache_bytes(instances[0]).unwrap();
    assert_eq!(bytes, (grid.indices.len() / 3 * 256 * 32) as u64, "16 x 16 tiles per triangle");
    let coarse = ctx.instance_cache_bytes(instances[1]).unwrap();
    assert!(coarse > 0 && coarse <= MAX_CACHE_SAMPLES * 32, "coarsened to the budget: {coarse} bytes");

    // The cache view of the whole first grid, from above: every pixel on it is the initial
    // colour, the last triangles (filled by the second dispatch) included.
    let mut scene = Scene::default();
    let m = scene.add_mesh(grid.clone());
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 60.0, 0.01), Vec3::ZERO);
    let (w, h) = (64, 64);
    let g = GBuffer::render(&Tracer::new(&scene), &camera, w, h);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let out = host
        .image_cleared(vk::Format::R32G32B32A32_SFLOAT, w, h, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)
        .unwrap();
    let mut view = images.ao_task(&camera, 1.0, 1);
    view.common.debug_output = DebugOutput::DirectLightingCache;
    view.output = out.input(vk::ImageLayout::GENERAL);
    c.schedule_ambient_occlusion(&view).unwrap();
    run_frame(&host, &ctx, &mut c).unwrap();
    let texels: Vec<[f32; 4]> = bytemuck::cast_slice(&host.read_image(&out, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    let on_grid: Vec<&[f32; 4]> = texels.iter().zip(&g.hit).filter(|(_, hit)| **hit).map(|(t, _)| t).collect();
    assert!(on_grid.len() > 1000);
    let wrong = on_grid.iter().filter(|t| (t[0] - 1.0).abs() > 1e-3 || t[1].abs() > 1e-3 || (t[2] - 1.0).abs() > 1e-3).count();
    assert_eq!(wrong, 0, "{wrong} of {} grid pixels are not the initial colour", on_grid.len());

    host.destroy_image(out);
    images.destroy(&host);
    ctx.destroy_instance_handles(&instances).unwrap();
    ctx.destroy_geometry_handles(&geometries).unwrap();
    host.destroy_buffer(v);
    host.destroy_buffer(i);
    drop(ctx);
}

/// A ticket handed back before its command buffer ran was accepted: its working set was
/// recycled and the unsubmitted commands then wrote to freed memory. Now it is refused, stays
/// in flight, and is accepted once the GPU is done.
#[test]
fn a_ticket_returned_before_its_commands_ran_is_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(4.0, 1));
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 0.01), Vec3::ZERO);
    let images = GBufferImages::upload(&host, &GBuffer::render(&Tracer::new(&scene), &camera, 8, 8)).unwrap();
    let mut c = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut c, &scene).unwrap();
    c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
    c.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, 1)).unwrap();
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(&mut c, cmd) }.unwrap();
    let serial = ticket.serial();
    // Recorded, not submitted.
    let raw = match ctx.mark_gpu_task_completed(ticket) {
        Err(Error::TicketNotComplete { serial: s, raw }) => {
            assert_eq!(s, serial);
            raw
        }
        other => panic!("an unsubmitted ticket must be refused: {other:?}"),
    };
    assert_eq!(ctx.tickets_in_flight(), vec![serial], "the ticket stays in flight");
    host.full_barrier(cmd);
    let fence = host.submit(cmd).unwrap();
    host.wait(fence).unwrap();
    ctx.mark_gpu_task_completed(GpuTicket::from_raw(raw)).expect("accepted once the GPU is done");
    assert!(ctx.tickets_in_flight().is_empty());
    assert!(images.read_output(&host).unwrap().iter().all(|v| *v > 0.999), "the frame rendered");
    images.destroy(&host);
    ctx.destroy_instance_handles(&s.instances).unwrap();
    ctx.destroy_geometry_handles(&s.geometries).unwrap();
    s.destroy(&host);
    drop(ctx);
}

/// Destroying a denoising context while a ticket that uses it is in flight frees its history
/// only after that ticket is back (checked by synchronization validation and the memory report).
#[test]
fn a_denoising_context_destroyed_in_flight_outlives_its_ticket() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(4.0, 1));
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 0.01), Vec3::ZERO);
    let images = GBufferImages::upload(&host, &GBuffer::render(&Tracer::new(&scene), &camera, 8, 8)).unwrap();
    let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let noisy = host.image_cleared(vk::Format::R32_SFLOAT, 8, 8, storage, vk::ImageLayout::GENERAL).unwrap();
    let mut c = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut c, &scene).unwrap();
    let before = ctx.resource_allocations().denoiser;
    let dn = ctx
        .create_denoising_context(&DenoisingContextInput {
            max_width: 8,
            max_height: 8,
            signal: SignalType::DiffuseOcclusion,
            ..Default::default()
        })
        .unwrap();
    c.schedule_bvh_build(&BvhBuildTask::default()).unwrap();
    c.schedule_ambient_occlusion(&TraceAmbientOcclusionTask {
        output: noisy.input(vk::ImageLayout::GENERAL),
        ..images.ao_task(&camera, 1.0, 1)
    })
    .unwrap();
    c.schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask {
        context: dn,
        common: images.denoising_common(&camera),
        input: noisy.input(vk::ImageLayout::GENERAL),
        output: images.output.input(vk::ImageLayout::GENERAL),
    })
    .unwrap();
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(&mut c, cmd) }.unwrap();
    ctx.destroy_denoising_context(dn).unwrap();
    assert!(ctx.resource_allocations().denoiser.bytes > before.bytes, "history waits for the ticket");
    host.full_barrier(cmd);
    let fence = host.submit(cmd).unwrap();
    host.wait(fence).unwrap();
    ctx.mark_gpu_task_completed(ticket).unwrap();
    assert_eq!(ctx.resource_allocations().denoiser.bytes, before.bytes, "freed once the ticket is back");
    host.destroy_image(noisy);
    images.destroy(&host);
    ctx.destroy_instance_handles(&s.instances).unwrap();
    ctx.destroy_geometry_handles(&s.geometries).unwrap();
    s.destroy(&host);
    drop(ctx);
}
