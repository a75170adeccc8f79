//! Ambient occlusion against the CPU reference.
mod common;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::InitSettings;
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const W: u32 = 64;
const H: u32 = 64;

fn ao_params(ray_length: f32) -> AoParams {
    AoParams { ray_length, falloff_power: 1.0, ray_offset: hybrid_rt::RayOffset::default() }
}

#[test]
fn open_plane_is_unoccluded() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(20.0, 4));
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 4.0, 1.0), Vec3::ZERO);
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    assert!(g.hit.iter().all(|h| *h), "the plane fills the view");

    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 2.0, 4)).unwrap();
    let done = run_frame(&host, &ctx, &mut frame).unwrap();
    let ao = images.read_output(&host).unwrap();
    let min = ao.iter().cloned().fold(f32::MAX, f32::min);
    assert!(min > 0.9999, "an open plane has AO 1 everywhere; min {min}");
    assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::AmbientOcclusion));
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// A sphere resting on a plane: contact darkening under the sphere, matching the reference.
#[test]
fn sphere_on_plane_matches_reference() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);

    let rays = 16;
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, rays)).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let gpu = images.read_output(&host).unwrap();

    let strata = 16; // 256 reference samples per pixel
    let reference = reference_ao(&tracer, &g, camera.eye, &ao_params(1.0), strata);
    let sigma = stats::sample_sigma(rays, strata * strata);
    let report = stats::compare_blocks(&gpu, &reference, W, H, 8, sigma, 0.01);
    eprintln!(
        "sphere on plane: worst 8x8 block error {:.4} at {:?} (tolerance {:.4}), mean abs error {:.4}",
        report.worst_block_error, report.worst_block, report.tolerance, report.mean_abs_error
    );
    assert!(report.worst_block_error <= report.tolerance);
    // The contact region under the sphere is really occluded (the test is not vacuous).
    assert!(reference.iter().cloned().fold(1.0, f32::min) < 0.5);
    assert!(gpu.iter().cloned().fold(1.0, f32::min) < 0.5);
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// Each ray-offset type against a reference that applies the same offset to the same origin.
/// `WorldPosition` moves a point by a few ULPs, less than a clip-depth reconstruction's error,
/// so it is tested on a world-position G-buffer (exact points, as the reference has them);
/// `Disabled` on world positions an engine has already lifted off the surface (1 mm along the
/// normal: nothing may move them further); `CameraDistance` on the usual clip depth.
#[test]
fn ray_offsets_match_the_reference() {
    use hybrid_rt::{DepthInput, DepthType, RayOffset, RayOffsetType};
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let tracer = Tracer::new(&scene);
    let exact = GBuffer::render(&tracer, &camera, W, H);
    let mut lifted = exact.clone();
    for (p, n) in lifted.position.iter_mut().zip(&exact.normal) {
        *p += *n * 1e-3;
    }
    let read = ash::vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let world = |g: &GBuffer| {
        host.image_with_data(
            ash::vk::Format::R32G32B32A32_SFLOAT,
            W,
            H,
            ash::vk::ImageUsageFlags::SAMPLED,
            &g.position_bytes_rgba32f(),
            read,
        )
        .unwrap()
    };
    let (exact_world, lifted_world) = (world(&exact), world(&lifted));
    let g = exact.clone();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let rays = 16;
    let strata = 16;
    let cases = [
        (RayOffsetType::Disabled, Some(&lifted_world), &lifted),
        (RayOffsetType::WorldPosition, Some(&exact_world), &exact),
        (RayOffsetType::CameraDistance, None, &exact),
    ];
    for (offset_type, positions, reference_g) in cases {
        let ray_offset = RayOffset { offset_type, ..Default::default() };
        let mut task = images.ao_task(&camera, 1.0, rays);
        task.common.ray_offset = ray_offset;
        if let Some(p) = positions {
            task.common.depth = DepthInput { image: p.input(read), depth_type: DepthType::WorldPosition };
        }
        frame.schedule_ambient_occlusion(&task).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        let gpu = images.read_output(&host).unwrap();
        let params = AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset };
        let reference = reference_ao(&tracer, reference_g, camera.eye, &params, strata);
        let sigma = stats::sample_sigma(rays, strata * strata);
        let report = stats::compare_blocks(&gpu, &reference, W, H, 8, sigma, 0.01);
        eprintln!("{offset_type:?}: worst block error {:.4} (tolerance {:.4})", report.worst_block_error, report.tolerance);
        assert!(report.worst_block_error <= report.tolerance, "{offset_type:?}");
    }
    host.destroy_image(exact_world);
    host.destroy_image(lifted_world);
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

fn oct_encode(n: Vec3) -> glam::Vec2 {
    let p = n.truncate() / (n.x.abs() + n.y.abs() + n.z.abs());
    if n.z >= 0.0 {
        p
    } else {
        let s = glam::Vec2::new(if p.x >= 0.0 { 1.0 } else { -1.0 }, if p.y >= 0.0 { 1.0 } else { -1.0 });
        (glam::Vec2::ONE - glam::Vec2::new(p.y.abs(), p.x.abs())) * s
    }
}

/// Every depth and normal encoding (the six normal types, world and view space, D32 and R32
/// depth, world positions), reversed-Z and infinite-far projections, and the inline ray-query
/// path give the same AO as the baseline (R32 clip depth, world-space RGB normals). All variants run in one container, so
/// they use the same random numbers: differences come only from decoding round-off, which
/// can flip a ray that grazes an edge.
#[test]
fn encodings_and_inline_rt_give_the_same_image() {
    use ash::vk;
    use hybrid_rt::{DepthInput, DepthType, NormalInput, NormalSpace, NormalType, TraceAmbientOcclusionTask};
    use hybrid_rt_testkit::host::Host;
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let plane = scene.add_mesh(Mesh::grid(8.0, 8));
    let sphere = scene.add_mesh(Mesh::sphere(0.5, 24, 12));
    let cube = scene.add_mesh(Mesh::cuboid(Vec3::splat(0.3)));
    scene.add_instance(plane, Affine3A::IDENTITY);
    scene.add_instance(sphere, Affine3A::from_translation(Vec3::new(-0.4, 0.5, 0.0)));
    scene.add_instance(cube, Affine3A::from_rotation_translation(glam::Quat::from_rotation_y(0.6), Vec3::new(0.6, 0.3, 0.3)));
    let camera = Camera::look_at(Vec3::new(0.3, 1.8, 2.2), Vec3::new(0.0, 0.2, 0.0));
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    assert!(g.hit.iter().any(|h| !h), "some background pixels, to check they are skipped");
    let base = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();

    let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let sampled = vk::ImageUsageFlags::SAMPLED;
    let world_to_view = camera.world_to_view();
    let normals_as = |f: &dyn Fn(Vec3) -> [f32; 4]| -> Vec<u8> {
        let v: Vec<[f32; 4]> = g.normal.iter().map(|n| f(*n)).collect();
        bytemuck::cast_slice(&v).to_vec()
    };
    let rg: Vec<[f32; 2]> = g.normal.iter().map(|n| oct_encode(*n).to_array()).collect();
    let img = |format, bytes: &[u8]| host.image_with_data(format, W, H, sampled, bytes, read).unwrap();
    let d32 = img(vk::Format::D32_SFLOAT, &g.depth_bytes());
    let positions = img(vk::Format::R32G32B32A32_SFLOAT, &g.position_bytes_rgba32f());
    let n_normalized =
        img(vk::Format::R32G32B32A32_SFLOAT, &normals_as(&|n| [n.x * 0.5 + 0.5, n.y * 0.5 + 0.5, n.z * 0.5 + 0.5, 0.0]));
    let n_rg_oct = img(vk::Format::R32G32_SFLOAT, bytemuck::cast_slice(&rg));
    let n_ba_oct_view = img(
        vk::Format::R32G32B32A32_SFLOAT,
        &normals_as(&|n| {
            let v = world_to_view.transform_vector3(n);
            let e = oct_encode(v) * 0.5 + 0.5;
            [0.0, 0.0, e.x, e.y]
        }),
    );

    let n_ba_oct = img(
        vk::Format::R32G32B32A32_SFLOAT,
        &normals_as(&|n| {
            let e = oct_encode(n);
            [0.0, 0.0, e.x, e.y]
        }),
    );
    let n_rg_noct_view = img(vk::Format::R16G16_UNORM, &{
        let v: Vec<[u16; 2]> = g
            .normal
            .iter()
            .map(|n| {
                let e = oct_encode(world_to_view.transform_vector3(*n)) * 0.5 + 0.5;
                [(e.x * 65535.0).round() as u16, (e.y * 65535.0).round() as u16]
            })
            .collect();
        bytemuck::cast_slice(&v).to_vec()
    });
    // An engine's own basis (z-up, scaled by 2): stored = to_engine * world, undone by the
    // normal_to_world 3x3 (the SDK normalises, so the scale must not matter).
    let to_world = glam::Mat3::from_rotation_x(-std::f32::consts::FRAC_PI_2) * glam::Mat3::from_rotation_z(0.7) * 2.0;
    let to_engine = to_world.inverse();
    let n_custom = img(
        vk::Format::R32G32B32A32_SFLOAT,
        &normals_as(&|n| {
            let v = to_engine * n;
            [v.x, v.y, v.z, 0.0]
        }),
    );
    let aspect = W as f32 / H as f32;
    let reversed = glam::camera::rh::proj::vulkan::perspective_infinite_reverse(camera.fov_y_radians, aspect, camera.near);
    let infinite = glam::camera::rh::proj::vulkan::perspective_infinite(camera.fov_y_radians, aspect, camera.near);
    let depth_under = |view_to_clip: glam::Mat4, background: f32| -> Vec<u8> {
        let to_clip = view_to_clip * world_to_view;
        let d: Vec<f32> =
            g.position.iter().zip(&g.hit).map(|(p, &hit)| if hit { to_clip.project_point3(*p).z } else { background }).collect();
        bytemuck::cast_slice(&d).to_vec()
    };
    let d_reversed = img(vk::Format::R32_SFLOAT, &depth_under(reversed, 0.0));
    let d_infinite = img(vk::Format::R32_SFLOAT, &depth_under(infinite, 1.0));

    let rays = 4;
    let baseline = base.ao_task(&camera, 1.0, rays);
    let mut variants: Vec<(&str, TraceAmbientOcclusionTask)> = Vec::new();
    let mut v = baseline;
    v.common.depth.image = d32.input(read);
    v.common.normals = NormalInput {
        image: n_normalized.input(read),
        normal_type: NormalType::RgbNormalizedVector,
        space: NormalSpace::World,
        ..Default::default()
    };
    variants.push(("D32 depth, normalized RGB normals", v));
    let mut v = baseline;
    v.common.depth = DepthInput { image: positions.input(read), depth_type: DepthType::WorldPosition };
    v.common.normals = NormalInput {
        image: n_rg_oct.input(read),
        normal_type: NormalType::RgOctahedron,
        space: NormalSpace::World,
        ..Default::default()
    };
    variants.push(("world positions, RG octahedral normals", v));
    let mut v = baseline;
    v.common.normals = NormalInput {
        image: n_ba_oct_view.input(read),
        normal_type: NormalType::BaNormalizedOctahedron,
        space: NormalSpace::View,
        ..Default::default()
    };
    variants.push(("view-space BA normalized octahedral normals", v));
    let mut v = baseline;
    v.common.normals = NormalInput {
        image: n_ba_oct.input(read),
        normal_type: NormalType::BaOctahedron,
        space: NormalSpace::World,
        ..Default::default()
    };
    variants.push(("BA octahedral normals", v));
    let mut v = baseline;
    v.common.normals = NormalInput {
        image: n_rg_noct_view.input(read),
        normal_type: NormalType::RgNormalizedOctahedron,
        space: NormalSpace::View,
        ..Default::default()
    };
    variants.push(("view-space RG normalized octahedral normals", v));
    let mut v = baseline;
    v.common.normals = NormalInput {
        image: n_custom.input(read),
        normal_type: NormalType::RgbVector,
        space: NormalSpace::Custom,
        normal_to_world: to_world,
    };
    variants.push(("custom-space normals (normal_to_world)", v));
    // Projections engines use: reversed Z with an infinite far plane (background depth 0) and
    // an infinite far plane (background 1). The depth images are the same surfaces' clip depth
    // under those projections.
    for (name, view_to_clip, image) in
        [("reversed-Z infinite projection", reversed, &d_reversed), ("infinite far plane", infinite, &d_infinite)]
    {
        let mut v = baseline;
        v.common.camera.view_to_clip = view_to_clip;
        v.common.depth.image = image.input(read);
        variants.push((name, v));
    }
    let mut v = baseline;
    v.common.use_inline_rt = true;
    variants.push(("inline ray query", v));

    frame.schedule_ambient_occlusion(&baseline).unwrap();
    let mut outputs = Vec::new();
    for (_, task) in variants.iter_mut() {
        let out =
            host.image_cleared(vk::Format::R32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
        task.output = out.input(vk::ImageLayout::GENERAL);
        frame.schedule_ambient_occlusion(task).unwrap();
        outputs.push(out);
    }
    run_frame(&host, &ctx, &mut frame).unwrap();
    let reference = base.read_output(&host).unwrap();
    for (i, &h) in g.hit.iter().enumerate() {
        if !h {
            assert_eq!(reference[i], 1.0, "background pixel {i} is skipped (AO 1)");
        }
    }
    for ((what, _), out) in variants.iter().zip(&outputs) {
        let ao = host.read_image_f32(out, vk::ImageLayout::GENERAL).unwrap();
        let diffs: Vec<f32> = ao.iter().zip(&reference).map(|(a, b)| (a - b).abs()).collect();
        let mean = stats::mean(&diffs);
        let off = diffs.iter().filter(|d| **d > 1e-3).count() as f32 / diffs.len() as f32;
        eprintln!("{what}: mean |diff| {mean:.2e}, pixels off by > 1e-3: {:.2}%", off * 100.0);
        assert!(mean < 2e-3 && off < 0.02, "{what}: mean {mean}, fraction off {off}");
    }
    if !ctx.supports_inline_rt() {
        eprintln!("(inline ray query not available: that variant ran the pipeline)");
    }
    for img in outputs.into_iter().chain([
        d32,
        positions,
        n_normalized,
        n_rg_oct,
        n_ba_oct_view,
        n_ba_oct,
        n_rg_noct_view,
        n_custom,
        d_reversed,
        d_infinite,
    ]) {
        host.destroy_image(img);
    }
    base.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    let _ = Host::validation_errors;
    assert_no_validation_errors();
}

/// Instances without the AO bit in their mask are invisible to AO rays.
#[test]
fn instance_mask_hides_instances_from_ao() {
    use hybrid_rt::{InstanceInclusionMask, InstanceInput, InstanceOperation, InstanceTask};
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    // The G-buffer holds only the plane: AO on the plane shows whether the sphere is seen.
    let mut ground = Scene::default();
    let p = ground.add_mesh(Mesh::grid(8.0, 8));
    ground.add_instance(p, Affine3A::IDENTITY);
    let g = GBuffer::render(&Tracer::new(&ground), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame
        .schedule_instance(&InstanceTask {
            handle: s.instances[1],
            operation: InstanceOperation::Update,
            input: InstanceInput {
                geometry: s.geometries[1],
                transform: scene.instances[1].transform,
                mask: InstanceInclusionMask::REFLECTIONS | InstanceInclusionMask::SHADOWS,
                ..Default::default()
            },
        })
        .unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, 4)).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let ao = images.read_output(&host).unwrap();
    assert!(ao.iter().all(|v| *v > 0.9999), "the masked sphere occludes nothing");
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// A viewport inside larger images: only its pixels are written, and they match the reference
/// rendered for that viewport.
#[test]
fn viewport_offsets_are_honoured() {
    use ash::vk;
    use hybrid_rt::{
        DepthInput, DepthType, NormalInput, NormalSpace, NormalType, TraceAmbientOcclusionTask, TraceCommon, Viewport,
    };
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let tracer = Tracer::new(&scene);
    let (vw, vh, ox, oy) = (32u32, 32u32, 24u32, 8u32);
    let g = GBuffer::render(&tracer, &camera, vw, vh);
    // Place the viewport's G-buffer at (ox, oy) of W x H images.
    let mut depth = vec![1.0f32; (W * H) as usize];
    let mut normals = vec![[0.0f32; 4]; (W * H) as usize];
    for y in 0..vh {
        for x in 0..vw {
            let s = (y * vw + x) as usize;
            let d = ((y + oy) * W + x + ox) as usize;
            depth[d] = g.depth[s];
            let n = g.normal[s];
            normals[d] = [n.x, n.y, n.z, 0.0];
        }
    }
    let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let sampled = vk::ImageUsageFlags::SAMPLED;
    let depth_img = host.image_with_data(vk::Format::R32_SFLOAT, W, H, sampled, bytemuck::cast_slice(&depth), read).unwrap();
    let normal_img =
        host.image_with_data(vk::Format::R32G32B32A32_SFLOAT, W, H, sampled, bytemuck::cast_slice(&normals), read).unwrap();
    let out = host.image_cleared(vk::Format::R32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
    let rays = 16;
    let task = TraceAmbientOcclusionTask {
        common: TraceCommon {
            depth: DepthInput { image: depth_img.input(read), depth_type: DepthType::ClipSpace },
            normals: NormalInput {
                image: normal_img.input(read),
                normal_type: NormalType::RgbVector,
                space: NormalSpace::World,
                ..Default::default()
            },
            viewport: Viewport { x: ox, y: oy, width: vw, height: vh, min_depth: 0.0, max_depth: 1.0 },
            camera: camera.sdk_camera(vw, vh),
            ..Default::default()
        },
        output: out.input(vk::ImageLayout::GENERAL),
        ray_length: 1.0,
        rays_per_pixel: rays,
        ..Default::default()
    };
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame.schedule_ambient_occlusion(&task).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let full = host.read_image_f32(&out, vk::ImageLayout::GENERAL).unwrap();
    let mut inside = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let v = full[(y * W + x) as usize];
            if (ox..ox + vw).contains(&x) && (oy..oy + vh).contains(&y) {
                inside.push(v);
            } else {
                assert_eq!(v, 0.0, "pixel ({x}, {y}) outside the viewport was written");
            }
        }
    }
    let reference = reference_ao(&tracer, &g, camera.eye, &ao_params(1.0), 16);
    let report = stats::compare_blocks(&inside, &reference, vw, vh, 8, stats::sample_sigma(rays, 256), 0.01);
    assert!(report.worst_block_error <= report.tolerance, "worst block {}", report.worst_block_error);
    for i in [depth_img, normal_img, out] {
        host.destroy_image(i);
    }
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// Half-resolution mode traces only its checkerboard, alternating between tickets.
#[test]
fn half_resolution_traces_only_its_checkerboard() {
    use ash::vk;
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let sentinel = -7.0f32;
    let mut parities = Vec::new();
    for _ in 0..2 {
        let fill = vec![sentinel; (W * H) as usize];
        let out = host
            .image_with_data(
                vk::Format::R32_SFLOAT,
                W,
                H,
                vk::ImageUsageFlags::STORAGE,
                bytemuck::cast_slice(&fill),
                vk::ImageLayout::GENERAL,
            )
            .unwrap();
        let mut task = images.ao_task(&camera, 1.0, 1);
        task.common.half_resolution_mode = hybrid_rt::HalfResolutionMode::Checkerboard;
        task.output = out.input(vk::ImageLayout::GENERAL);
        frame.schedule_ambient_occlusion(&task).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        let ao = host.read_image_f32(&out, vk::ImageLayout::GENERAL).unwrap();
        // Written pixels form one colour of a checkerboard.
        let parity = ((0..W * H).find(|&i| ao[i as usize] != sentinel).unwrap() / W
            + (0..W * H).find(|&i| ao[i as usize] != sentinel).unwrap() % W)
            % 2;
        for y in 0..H {
            for x in 0..W {
                let written = ao[(y * W + x) as usize] != sentinel;
                assert_eq!(written, (x + y) % 2 == parity, "pixel ({x}, {y})");
            }
        }
        parities.push(parity);
        host.destroy_image(out);
    }
    assert_ne!(parities[0], parities[1], "successive tickets trace the other half");
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
