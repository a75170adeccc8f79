//! Denoisers on lavapipe: 1-ray-per-pixel traces denoised over frames against the converged
//! CPU reference (relative RMSE, raw and denoised), disocclusion without ghosts, sharp
//! mirrors and hard shadow edges, checkerboard resolve, history reset, and errors.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostImage};
use hybrid_rt_testkit::reference::{self as reference, AoParams, Camera, GBuffer, Mesh, Rng, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const FRAMES: u32 = 32;
const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

fn storage_image(host: &Host, format: vk::Format, w: u32, h: u32) -> HostImage {
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    host.image_cleared(format, w, h, usage, GENERAL).unwrap()
}

/// Channel `c` of an RGBA32F image.
fn read_channel(host: &Host, img: &HostImage, c: usize) -> Vec<f32> {
    let texels: Vec<[f32; 4]> = bytemuck::cast_slice(&host.read_image(img, GENERAL).unwrap()).to_vec();
    texels.iter().map(|t| t[c]).collect()
}

/// A sphere resting on a plane, seen from above and in front (AO and shadows).
fn sphere_on_plane() -> (Scene, Camera) {
    let mut scene = Scene::default();
    let plane = scene.add_mesh(Mesh::grid(8.0, 8));
    let sphere = scene.add_mesh(Mesh::sphere(0.5, 24, 12));
    scene.add_instance(plane, Affine3A::IDENTITY);
    scene.add_instance(sphere, Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)));
    (scene, Camera::look_at(Vec3::new(0.0, 1.6, 2.2), Vec3::new(0.0, 0.2, 0.0)))
}

fn context(ctx: &ExecuteContext, signal: SignalType, w: u32, h: u32) -> DenoisingContextHandle {
    ctx.create_denoising_context(&DenoisingContextInput { max_width: w, max_height: h, signal, ..Default::default() }).unwrap()
}

/// Relative RMSE of the last raw frame and of the denoised image.
struct Quality {
    raw: f32,
    denoised: f32,
}

/// 1-ray AO traced and denoised for FRAMES frames on a static camera.
fn ao_quality(half_resolution: bool) -> Quality {
    const W: u32 = 64;
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, W);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();

    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&ctx, SignalType::DiffuseOcclusion, W, W);
    let mut trace = images.ao_task(&camera, 1.0, 1);
    trace.output = noisy.input(GENERAL);
    trace.common.half_resolution_mode = half_resolution;
    let mut common = images.denoising_common(&camera);
    common.half_resolution_mode = half_resolution;
    let task = DenoiseDiffuseOcclusionTask { context: dn, common, input: noisy.input(GENERAL), output: denoised.input(GENERAL) };
    for _ in 0..FRAMES {
        frame.schedule_ambient_occlusion(&trace).unwrap();
        frame.schedule_denoise_diffuse_occlusion(&task).unwrap();
        let done = run_frame(&host, &ctx, &mut frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == TaskKind::DenoiseDiffuseOcclusion));
    }
    let raw = read_channel(&host, &noisy, 0);
    let out = read_channel(&host, &denoised, 0);
    assert!(out.iter().all(|v| v.is_finite() && (0.0..=1.001).contains(v)), "AO stays in [0, 1]");
    let strata = 24; // 576 samples: the reference's own noise is below 0.021 per pixel
    let reference = reference::reference_ao(&tracer, &g, camera.eye, &AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset: RayOffset::default() }, strata);
    let q = Quality { raw: stats::relative_rmse(&raw, &reference, &g.hit), denoised: stats::relative_rmse(&out, &reference, &g.hit) };
    // Where something occludes (reference < 0.9: the contact region), the harder part.
    let occluded: Vec<bool> = g.hit.iter().zip(&reference).map(|(h, r)| *h && *r < 0.9).collect();
    eprintln!(
        "  occluded region ({} px): raw {:.4}, denoised {:.4}",
        occluded.iter().filter(|m| **m).count(),
        stats::relative_rmse(&raw, &reference, &occluded),
        stats::relative_rmse(&out, &reference, &occluded)
    );
    ctx.destroy_denoising_context(dn).unwrap();
    for i in [noisy, denoised] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    q
}

#[test]
fn ao_denoised_over_32_frames_approaches_the_reference() {
    let q = ao_quality(false);
    eprintln!("AO, 1 ray/pixel, {FRAMES} frames: relative RMSE raw {:.4}, denoised {:.4}", q.raw, q.denoised);
    // A 1-ray AO pixel is one sample in [0, 1] (exactly 1 on the open plane, so the image-wide
    // raw error is ~0.12). The denoised mean of ~63 effective frames (window 32) with the
    // spatial filter leaves about a percent, near the reference's own noise (0.021 per pixel
    // at 576 samples, ~0.025 relative).
    assert!(q.denoised < 0.06, "denoised relative RMSE {}", q.denoised);
    assert!(q.denoised * 6.0 < q.raw, "denoising gains at least 6x: raw {} denoised {}", q.raw, q.denoised);
}

#[test]
fn checkerboard_ao_is_resolved_to_a_full_image() {
    let q = ao_quality(true);
    eprintln!("AO, checkerboard, {FRAMES} frames: relative RMSE raw {:.4}, denoised {:.4}", q.raw, q.denoised);
    // The raw image holds each pixel's last traced sample (half are a frame old); the
    // denoised one fills every pixel and is nearly as good as full-resolution tracing.
    assert!(q.denoised < 0.07, "denoised relative RMSE {}", q.denoised);
    assert!(q.denoised * 5.0 < q.raw);
}

#[test]
fn diffuse_gi_denoised_over_32_frames_approaches_the_reference() {
    const W: u32 = 48;
    const SKY: [f32; 3] = [0.1, 0.2, 0.3];
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, colours, camera) = reference::coloured_room(true);
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, W);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register_coloured(&host, &ctx, &mut frame, &scene, Default::default(), &colours).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();

    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&ctx, SignalType::Diffuse, W, W);
    let trace = TraceDiffuseTask { common: images.trace_common(&camera), output: noisy.input(GENERAL), ray_length: 100.0, miss_radiance: SKY, ..Default::default() };
    let task = DenoiseDiffuseTask { context: dn, common: images.denoising_common(&camera), input: noisy.input(GENERAL), output: denoised.input(GENERAL) };
    for _ in 0..FRAMES {
        frame.schedule_diffuse(&trace).unwrap();
        frame.schedule_denoise_diffuse(&task).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
    }
    let reference = reference::diffuse_reference(&tracer, &g, camera.eye, &colours, SKY, 100.0, 24);
    let (mut raw_e, mut den_e) = (0.0, 0.0);
    for k in 0..3 {
        let r: Vec<f32> = reference.iter().map(|c| c[k]).collect();
        let raw = stats::relative_rmse(&read_channel(&host, &noisy, k), &r, &g.hit);
        let den = stats::relative_rmse(&read_channel(&host, &denoised, k), &r, &g.hit);
        eprintln!("diffuse GI channel {k}, 1 ray/pixel, {FRAMES} frames: relative RMSE raw {raw:.4}, denoised {den:.4}");
        raw_e += raw / 3.0;
        den_e += den / 3.0;
    }
    // One cosine sample of radiances between 0.1 and 0.9 is ~0.6 relative; the reference's
    // 576 samples leave ~0.02.
    assert!(den_e < 0.08, "denoised relative RMSE {den_e}");
    assert!(den_e * 5.0 < raw_e, "raw {raw_e} denoised {den_e}");
    ctx.destroy_denoising_context(dn).unwrap();
    for i in [noisy, denoised] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// Shadows of a sphere on a plane under `light`, traced at 1 ray/pixel and denoised for
/// `frames` frames: (raw, denoised, reference visibility, G-buffer).
fn denoised_shadow(light: LightInfo, frames: u32) -> (Vec<f32>, Vec<f32>, Vec<f32>, GBuffer) {
    const W: u32 = 64;
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, W);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();

    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&ctx, SignalType::Shadow, W, W);
    let trace = TraceShadowTask { common: images.trace_common(&camera), light, output: noisy.input(GENERAL), rays_per_pixel: 1 };
    let task = DenoiseShadowTask { context: dn, common: images.denoising_common(&camera), light, input: noisy.input(GENERAL), output: denoised.input(GENERAL) };
    for _ in 0..frames {
        frame.schedule_shadow(&trace).unwrap();
        frame.schedule_denoise_shadow(&task).unwrap();
        let done = run_frame(&host, &ctx, &mut frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == TaskKind::DenoiseShadow));
    }
    let raw = read_channel(&host, &noisy, 1);
    let out = read_channel(&host, &denoised, 0);
    let mut rng = Rng::new(9);
    let reference = (0..g.depth.len())
        .map(|i| {
            if !g.hit[i] {
                return 1.0;
            }
            reference::shadow_visibility(&tracer, g.position[i], g.normal[i], camera.eye, &light, &RayOffset::default(), 24, &mut rng).0
        })
        .collect();
    ctx.destroy_denoising_context(dn).unwrap();
    for i in [noisy, denoised] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    (raw, out, reference, g)
}

fn sun(angular_extent: f32) -> LightInfo {
    LightInfo { light_type: LightType::Directional, direction: Vec3::new(-0.5, -1.0, -0.3), angular_extent, ..Default::default() }
}

#[test]
fn soft_shadow_denoised_over_32_frames_approaches_the_reference() {
    let (raw, out, reference, g) = denoised_shadow(sun(0.2), FRAMES);
    let raw_e = stats::relative_rmse(&raw, &reference, &g.hit);
    let den_e = stats::relative_rmse(&out, &reference, &g.hit);
    let penumbra: Vec<bool> = g.hit.iter().zip(&reference).map(|(h, r)| *h && *r > 0.02 && *r < 0.98).collect();
    let (raw_p, den_p) = (stats::relative_rmse(&raw, &reference, &penumbra), stats::relative_rmse(&out, &reference, &penumbra));
    eprintln!("soft sun shadow (0.2 rad), 1 ray/pixel, {FRAMES} frames: relative RMSE raw {raw_e:.4}, denoised {den_e:.4}; penumbra ({} px) raw {raw_p:.4}, denoised {den_p:.4}", penumbra.iter().filter(|m| **m).count());
    // Most of the image is lit (exact at 1 ray); the penumbra is where the noise is. There a
    // 1-ray pixel is one Bernoulli sample (~0.76 relative); the blur is only as wide as the
    // penumbra (2-4 px here) and the reference has ~0.04 relative noise of its own.
    assert!(den_e < 0.03, "denoised relative RMSE {den_e}");
    assert!(den_e * 3.0 < raw_e);
    assert!(den_p * 3.0 < raw_p);
}

#[test]
fn hard_shadow_edges_stay_within_one_pixel() {
    const W: usize = 64;
    let (raw, out, _, g) = denoised_shadow(sun(0.0), 8);
    // A hard light: the raw image is exact (binary). The denoised edge may move at most one
    // pixel: every pixel that changed has a neighbour of the other raw value.
    let mut changed = 0;
    for y in 0..W {
        for x in 0..W {
            let i = y * W + x;
            if !g.hit[i] || (out[i] - raw[i]).abs() < 0.5 {
                continue;
            }
            changed += 1;
            let near_edge = (y.saturating_sub(1)..(y + 2).min(W))
                .flat_map(|yy| (x.saturating_sub(1)..(x + 2).min(W)).map(move |xx| yy * W + xx))
                .any(|j| (raw[j] - raw[i]).abs() > 0.5);
            assert!(near_edge, "pixel ({x}, {y}) changed from {} to {} away from any edge", raw[i], out[i]);
        }
    }
    let shadowed = raw.iter().zip(&g.hit).filter(|(v, h)| **h && **v < 0.5).count();
    eprintln!("hard shadow: {shadowed} shadowed pixels, {changed} changed by more than 0.5 (all beside an edge)");
    assert!(shadowed > 100, "the scene has a real shadow");
}
