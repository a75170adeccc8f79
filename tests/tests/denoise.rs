//! Denoisers on lavapipe: 1-ray-per-pixel traces denoised over frames against the converged
//! CPU reference (relative RMSE, raw and denoised), disocclusion without ghosts, sharp
//! mirrors and hard shadow edges, checkerboard resolve, history reset, and errors.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostImage};
use hybrid_rt_testkit::reference::{self as reference, sphere_on_plane, AoParams, Camera, GBuffer, Mesh, Rng, Scene, Tracer};
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

/// A scene registered and built, its G-buffer uploaded: what every traced test starts from.
struct Fixture {
    host: Host,
    ctx: ExecuteContext,
    tracer: Tracer,
    g: GBuffer,
    images: GBufferImages,
    gpu_scene: SceneOnGpu,
    frame: TaskContainer,
}

impl Fixture {
    /// `colours`: each instance's cache colour (None: black).
    fn new(scene: &Scene, colours: Option<&[[f32; 3]]>, camera: &Camera, w: u32) -> Fixture {
        let (host, ctx) = host_and_context(InitSettings::default());
        let tracer = Tracer::new(scene);
        let g = GBuffer::render(&tracer, camera, w, w);
        let images = GBufferImages::upload(&host, &g).unwrap();
        let mut frame = ctx.create_task_container();
        let black = vec![[0.0; 3]; scene.instances.len()];
        let gpu_scene =
            SceneOnGpu::register_coloured(&host, &ctx, &mut frame, scene, Default::default(), colours.unwrap_or(&black)).unwrap();
        frame.schedule_bvh_build(&Default::default()).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        Fixture { host, ctx, tracer, g, images, gpu_scene, frame }
    }

    /// Frees everything (with the test's own images), checks the validation layer, and hands
    /// back the G-buffer.
    fn finish(self, images: impl IntoIterator<Item = HostImage>) -> GBuffer {
        for i in images {
            self.host.destroy_image(i);
        }
        self.images.destroy(&self.host);
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
        self.g
    }
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
    let (scene, camera) = sphere_on_plane();
    let mut f = Fixture::new(&scene, None, &camera, W);
    let noisy = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&f.ctx, SignalType::DiffuseOcclusion, W, W);
    let mut trace = f.images.ao_task(&camera, 1.0, 1);
    trace.output = noisy.input(GENERAL);
    let half_resolution = if half_resolution { HalfResolutionMode::Checkerboard } else { HalfResolutionMode::Off };
    trace.common.half_resolution_mode = half_resolution;
    let mut common = f.images.denoising_common(&camera);
    common.half_resolution_mode = half_resolution;
    let task = DenoiseDiffuseOcclusionTask { context: dn, common, input: noisy.input(GENERAL), output: denoised.input(GENERAL) };
    for _ in 0..FRAMES {
        f.frame.schedule_ambient_occlusion(&trace).unwrap();
        f.frame.schedule_denoise_diffuse_occlusion(&task).unwrap();
        let done = run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == TaskKind::DenoiseDiffuseOcclusion));
    }
    let raw = read_channel(&f.host, &noisy, 0);
    let out = read_channel(&f.host, &denoised, 0);
    assert!(out.iter().all(|v| v.is_finite() && (0.0..=1.001).contains(v)), "AO stays in [0, 1]");
    let strata = 24; // 576 samples: the reference's own noise is below 0.021 per pixel
    let params = AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset: RayOffset::default() };
    let reference = reference::reference_ao(&f.tracer, &f.g, camera.eye, &params, strata);
    let q = Quality {
        raw: stats::relative_rmse(&raw, &reference, &f.g.hit),
        denoised: stats::relative_rmse(&out, &reference, &f.g.hit),
    };
    // Where something occludes (reference < 0.9: the contact region), the harder part.
    let occluded: Vec<bool> = f.g.hit.iter().zip(&reference).map(|(h, r)| *h && *r < 0.9).collect();
    eprintln!(
        "  occluded region ({} px): raw {:.4}, denoised {:.4}",
        occluded.iter().filter(|m| **m).count(),
        stats::relative_rmse(&raw, &reference, &occluded),
        stats::relative_rmse(&out, &reference, &occluded)
    );
    f.ctx.destroy_denoising_context(dn).unwrap();
    f.finish([noisy, denoised]);
    q
}

/// `g` in the top-left corner of a `w` x `h` G-buffer whose other pixels see nothing: what an
/// engine rendering at a lower resolution leaves in its full-size targets.
fn padded(g: &GBuffer, w: u32, h: u32) -> GBuffer {
    let n = (w * h) as usize;
    let mut out = GBuffer {
        width: w,
        height: h,
        depth: vec![1.0; n],
        normal: vec![Vec3::ZERO; n],
        position: vec![Vec3::ZERO; n],
        hit: vec![false; n],
        instance: vec![0; n],
    };
    for y in 0..g.height as usize {
        for x in 0..g.width as usize {
            let (from, to) = (y * g.width as usize + x, y * w as usize + x);
            out.depth[to] = g.depth[from];
            out.normal[to] = g.normal[from];
            out.position[to] = g.position[from];
            out.hit[to] = g.hit[from];
            out.instance[to] = g.instance[from];
        }
    }
    out
}

/// 1-ray AO (`light` None) or a light's shadow denoised for `frames` frames on a static camera
/// whose render resolution follows `size_of(frame)` (a viewport of that many pixels square in
/// the top-left corner of the 64x64 targets, as dynamic resolution renders). Relative RMSE of
/// the last frame's raw and denoised signal within its viewport, against the reference at
/// that resolution.
fn quality_at_resolutions(light: Option<LightInfo>, frames: u32, size_of: impl Fn(u32) -> u32) -> Quality {
    const W: u32 = 64;
    let (scene, camera) = sphere_on_plane();
    let mut f = Fixture::new(&scene, None, &camera, W);
    let noisy = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let signal = if light.is_some() { SignalType::Shadow } else { SignalType::DiffuseOcclusion };
    let dn = context(&f.ctx, signal, W, W);
    let mut last = None;
    for frame in 0..frames {
        let size = size_of(frame);
        let g = GBuffer::render(&f.tracer, &camera, size, size);
        upload_gbuffer(&f.host, &f.images, &padded(&g, W, W));
        let viewport = Viewport::full(size, size);
        let mut common = f.images.trace_common(&camera);
        common.viewport = viewport;
        let mut denoising = f.images.denoising_common(&camera);
        denoising.viewport = viewport;
        let (input, output) = (noisy.input(GENERAL), denoised.input(GENERAL));
        match light {
            Some(light) => {
                f.frame
                    .schedule_shadow(&TraceShadowTask { common, light, output: input, rays_per_pixel: 1, ..Default::default() })
                    .unwrap();
                f.frame
                    .schedule_denoise_shadow(&DenoiseShadowTask { context: dn, common: denoising, light, input, output })
                    .unwrap();
            }
            None => {
                let trace = TraceAmbientOcclusionTask { common, output: input, ..f.images.ao_task(&camera, 1.0, 1) };
                f.frame.schedule_ambient_occlusion(&trace).unwrap();
                f.frame
                    .schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask {
                        context: dn,
                        common: denoising,
                        input,
                        output,
                    })
                    .unwrap();
            }
        }
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        last = Some(g);
    }
    let g = last.expect("at least one frame");
    let size = g.width as usize;
    let inside = |img: Vec<f32>| -> Vec<f32> { (0..size * size).map(|i| img[(i / size) * W as usize + i % size]).collect() };
    // The shadow trace writes visibility to G (R holds the occluder distance).
    let raw = inside(read_channel(&f.host, &noisy, if light.is_some() { 1 } else { 0 }));
    let out = inside(read_channel(&f.host, &denoised, 0));
    let reference = match light {
        Some(light) => {
            f.g = g.clone();
            reference_visibility(&f, &camera, &[light], 24)
        }
        None => {
            let params = AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset: RayOffset::default() };
            reference::reference_ao(&f.tracer, &g, camera.eye, &params, 24)
        }
    };
    let q =
        Quality { raw: stats::relative_rmse(&raw, &reference, &g.hit), denoised: stats::relative_rmse(&out, &reference, &g.hit) };
    f.ctx.destroy_denoising_context(dn).unwrap();
    f.finish([noisy, denoised]);
    q
}

/// Dynamic resolution: the render resolution changes every frame (64 and 48 pixels square,
/// alternating) and the history survives it — reprojection lands in the viewport the history
/// was made in. AO after 32 frames: within 1.5x of a run that stays at 48 pixels, and far
/// below a single frame's (restarting the history at every change, as the denoisers did,
/// measured 0.067: worse than one frame). A sun shadow fares as in a moving view, its hard
/// edges resampled every frame (each change keeps sharp penumbrae to two frames, as a move
/// does): better than one frame, not as good as a steady resolution.
#[test]
fn history_survives_a_resolution_that_changes_every_frame() {
    for (name, light, within_steady, of_single) in [("AO", None, 1.5, 0.6), ("sun shadow", Some(sun(0.2)), 6.0, 0.85)] {
        let steady = quality_at_resolutions(light, FRAMES, |_| 48);
        let alternating = quality_at_resolutions(light, FRAMES, |f| if f % 2 == 0 { 64 } else { 48 });
        let single = quality_at_resolutions(light, 1, |_| 48);
        eprintln!(
            "{name} at 48 px: steady {:.4}, alternating with 64 px {:.4}, one frame {:.4} (raw {:.4})",
            steady.denoised, alternating.denoised, single.denoised, alternating.raw
        );
        assert!(
            alternating.denoised < within_steady * steady.denoised,
            "{name}: alternating {} steady {}",
            alternating.denoised,
            steady.denoised
        );
        assert!(
            alternating.denoised < of_single * single.denoised,
            "{name}: alternating {} one frame {}",
            alternating.denoised,
            single.denoised
        );
    }
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

/// Diffuse GI in the coloured room at 48x48, 1 ray a pixel, denoised for `frames` frames with
/// `spatial_passes` blur passes: the relative RMSE (mean of the channels) of the last raw and
/// denoised frames against the reference, and the largest difference between the last frame's
/// raw and denoised images.
fn diffuse_gi_errors(frames: u32, spatial_passes: u32) -> (f32, f32, f32) {
    const W: u32 = 48;
    const SKY: [f32; 3] = [0.1, 0.2, 0.3];
    let (scene, colours, camera) = reference::coloured_room(true);
    let mut f = Fixture::new(&scene, Some(&colours), &camera, W);
    let noisy = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&f.ctx, SignalType::Diffuse, W, W);
    let trace = TraceDiffuseTask {
        common: f.images.trace_common(&camera),
        output: noisy.input(GENERAL),
        ray_length: 100.0,
        miss_radiance: SKY,
        ..Default::default()
    };
    let mut common = f.images.denoising_common(&camera);
    common.settings.spatial_passes = spatial_passes;
    let task = DenoiseDiffuseTask { context: dn, common, input: noisy.input(GENERAL), output: denoised.input(GENERAL) };
    for _ in 0..frames {
        f.frame.schedule_diffuse(&trace).unwrap();
        f.frame.schedule_denoise_diffuse(&task).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    }
    let reference = reference::diffuse_reference(&f.tracer, &f.g, camera.eye, &colours, SKY, 100.0, 24, |_, _, _| 1.0);
    let (mut raw_e, mut den_e, mut largest) = (0.0, 0.0, 0.0f32);
    for k in 0..3 {
        let r: Vec<f32> = reference.iter().map(|c| c[k]).collect();
        let (raw_k, den_k) = (read_channel(&f.host, &noisy, k), read_channel(&f.host, &denoised, k));
        let raw = stats::relative_rmse(&raw_k, &r, &f.g.hit);
        let den = stats::relative_rmse(&den_k, &r, &f.g.hit);
        eprintln!(
            "diffuse GI channel {k}, 1 ray/pixel, {frames} frames, {spatial_passes} spatial passes: relative RMSE raw {raw:.4}, denoised {den:.4}"
        );
        raw_e += raw / 3.0;
        den_e += den / 3.0;
        let hits = raw_k.iter().zip(&den_k).zip(&f.g.hit).filter(|(_, &hit)| hit);
        largest = hits.fold(largest, |m, ((a, b), _)| m.max((a - b).abs() / a.abs().max(1e-3)));
    }
    f.ctx.destroy_denoising_context(dn).unwrap();
    f.finish([noisy, denoised]);
    (raw_e, den_e, largest)
}

#[test]
fn diffuse_gi_denoised_over_32_frames_approaches_the_reference() {
    let (raw_e, den_e, _) = diffuse_gi_errors(FRAMES, DenoiserSettings::default().spatial_passes);
    // One cosine sample of radiances between 0.1 and 0.9 is ~0.6 relative; the reference's
    // 576 samples leave ~0.02. Measured 0.030 (0.036 while each frame's rays were independent
    // of the last's: a pixel's sequence now runs on across frames).
    assert!(den_e < 0.045, "denoised relative RMSE {den_e}");
    assert!(den_e * 5.0 < raw_e, "raw {raw_e} denoised {den_e}");
}

/// Without spatial passes the output is the clamped temporal mean (and the histories are still
/// kept): a first frame's output is its sample (to a half's rounding), and 32 frames' is at
/// least as close to the reference as the mean of 32 independent samples.
#[test]
fn without_spatial_passes_the_output_is_the_temporal_mean() {
    let (_, _, largest) = diffuse_gi_errors(1, 0);
    assert!(largest <= 1e-3, "a first frame's output differs from its sample by {largest} (relative)");
    let (raw_e, den_e, _) = diffuse_gi_errors(FRAMES, 0);
    // 32 independent one-sample frames: raw / sqrt(32), with the reference's own noise (~0.02)
    // beside it. A pixel's ray sequence runs on across frames (stratified), so the mean does
    // better: measured 0.078 against 0.138. Histories that were not kept would leave the raw
    // frame's 0.77.
    let expected = (raw_e * raw_e / FRAMES as f32 + 0.02 * 0.02).sqrt();
    eprintln!("spatial_passes 0: raw {raw_e:.4}, denoised {den_e:.4}, 32 samples' mean {expected:.4}");
    assert!(den_e < expected, "raw {raw_e} denoised {den_e}");
}

/// Shadows of a sphere on a plane under `light`, traced at 1 ray/pixel and denoised for
/// `frames` frames whose indices start at `seed`: (raw, denoised, reference visibility,
/// G-buffer).
fn denoised_shadow(light: LightInfo, frames: u32, seed: u64) -> (Vec<f32>, Vec<f32>, Vec<f32>, GBuffer) {
    const W: u32 = 64;
    let (scene, camera) = sphere_on_plane();
    let mut f = Fixture::new(&scene, None, &camera, W);
    let noisy = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let denoised = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&f.ctx, SignalType::Shadow, W, W);
    let trace = TraceShadowTask {
        common: f.images.trace_common(&camera),
        light,
        output: noisy.input(GENERAL),
        rays_per_pixel: 1,
        ..Default::default()
    };
    let task = DenoiseShadowTask {
        context: dn,
        common: f.images.denoising_common(&camera),
        light,
        input: noisy.input(GENERAL),
        output: denoised.input(GENERAL),
    };
    for k in 0..frames as u64 {
        f.frame.set_frame_index(seed + k);
        f.frame.schedule_shadow(&trace).unwrap();
        f.frame.schedule_denoise_shadow(&task).unwrap();
        let done = run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == TaskKind::DenoiseShadow));
    }
    let raw = read_channel(&f.host, &noisy, 1);
    let out = read_channel(&f.host, &denoised, 0);
    let reference = reference_visibility(&f, &camera, &[light], 24);
    f.ctx.destroy_denoising_context(dn).unwrap();
    let g = f.finish([noisy, denoised]);
    (raw, out, reference, g)
}

/// Visible fraction of `lights` per pixel, weighted by each light's irradiance as the
/// multi-light trace weighs them (`reference::light_weight`), `strata`² reference samples per
/// light.
fn reference_visibility(f: &Fixture, camera: &Camera, lights: &[LightInfo], strata: u32) -> Vec<f32> {
    let mut rng = Rng::new(9);
    (0..f.g.depth.len())
        .map(|i| {
            if !f.g.hit[i] {
                return 1.0;
            }
            let (p, n) = (f.g.position[i], f.g.normal[i]);
            let (mut sum, mut weights, mut last) = (0.0, 0.0, 1.0);
            for l in lights {
                let w = reference::light_weight(l, p, n);
                last = reference::shadow_visibility(&f.tracer, p, n, camera.eye, l, &RayOffset::default(), strata, &mut rng).0;
                sum += w * last;
                weights += w;
            }
            if lights.len() == 1 {
                // One light: its own visibility (the single-light task does not weigh).
                last
            } else if weights > 0.0 {
                sum / weights
            } else {
                1.0
            }
        })
        .collect()
}

fn sun(angular_extent: f32) -> LightInfo {
    LightInfo { light_type: LightType::Directional, direction: Vec3::new(-0.5, -1.0, -0.3), angular_extent, ..Default::default() }
}

/// Issue 12's penumbra goal: after 32 frames of one ray per pixel, the denoised penumbra (0.02
/// < reference < 0.98) of a 0.2 rad sun within 8% relative RMSE of the CPU reference, the mean
/// over four seeds. Why that is reachable: a 1-ray pixel is one Bernoulli sample (~0.72
/// relative there); 32 independent ones leave 0.72 / sqrt(32) = 13%, and a blur cannot make
/// up the rest in a penumbra 2-4 px wide without flattening it. The shadow trace's per-pixel
/// sequence runs on across frames (include/common.glsl, hrt_sequence), so 32 frames are a
/// stratified set of the light's disk: their raw mean is 7.3% off, the denoised image ~7.5%.
/// The reference (576 stratified samples) adds ~1%.
#[test]
fn soft_shadow_denoised_over_32_frames_approaches_the_reference() {
    let (mut raw_e, mut den_e, mut raw_p, mut den_p) = (0.0, 0.0, 0.0, 0.0);
    let seeds = [0u64, 1 << 20, 2 << 20, 3 << 20];
    for seed in seeds {
        let (raw, out, reference, g) = denoised_shadow(sun(0.2), FRAMES, seed);
        let n = seeds.len() as f32;
        raw_e += stats::relative_rmse(&raw, &reference, &g.hit) / n;
        den_e += stats::relative_rmse(&out, &reference, &g.hit) / n;
        let penumbra: Vec<bool> = g.hit.iter().zip(&reference).map(|(h, r)| *h && *r > 0.02 && *r < 0.98).collect();
        raw_p += stats::relative_rmse(&raw, &reference, &penumbra) / n;
        den_p += stats::relative_rmse(&out, &reference, &penumbra) / n;
    }
    eprintln!("soft sun shadow (0.2 rad), 1 ray/pixel, {FRAMES} frames, mean of 4 seeds: relative RMSE raw {raw_e:.4}, denoised {den_e:.4}; penumbra raw {raw_p:.4}, denoised {den_p:.4}");
    assert!(den_p <= 0.08, "denoised penumbra relative RMSE {den_p}");
    assert!(den_e < 0.03, "denoised relative RMSE {den_e}");
    assert!(den_e * 3.0 < raw_e);
}

#[test]
fn hard_shadow_edges_stay_within_one_pixel() {
    const W: usize = 64;
    let (raw, out, _, g) = denoised_shadow(sun(0.0), 8, 0);
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

// ---------------------------------------------------------------- synthetic inputs
// The denoisers only see images: these tests feed known signals (a colour per surface, with
// noise) so what must and must not appear in the output is exact.

const S: u32 = 48;
/// Bound on the first frame's deviation with 16 extra taps against none (see
/// fresh_history_taps_smooth_a_first_frame): the first pass averages 25 samples instead of 9,
/// a deviation of 0.6x were the weights equal; the luminance stop and the second pass leave
/// less to gain (measured 0.65).
const FRESH_TAPS_DEVIATION_RATIO: f32 = 0.8;

/// A wall facing +z at z = -3 and a box in front of it at z = -1.
fn wall_and_box() -> Scene {
    let mut scene = Scene::default();
    let wall = scene.add_mesh(Mesh::grid(12.0, 4));
    let cube = scene.add_mesh(Mesh::cuboid(Vec3::splat(0.5)));
    scene.add_instance(
        wall,
        Affine3A::from_rotation_translation(glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2), Vec3::new(0.0, 0.0, -3.0)),
    );
    scene.add_instance(cube, Affine3A::from_translation(Vec3::new(0.0, 0.0, -1.0)));
    scene
}

fn rgba_bytes(texels: &[[f32; 4]]) -> Vec<u8> {
    bytemuck::cast_slice(texels).to_vec()
}

/// The wall's clean green: a checker of 0.3 m cells (1.0 and 0.4), detail that a spatial
/// filter alone blurs, so fresh pixels need history to become right.
fn wall_green(p: Vec3) -> f32 {
    let cell = ((p.x / 0.3).floor() + (p.y / 0.3).floor()) as i64;
    if cell.rem_euclid(2) == 0 {
        1.0
    } else {
        0.4
    }
}

/// Each surface's colour (the wall's green checker, the box red) times noise of mean 1
/// (uniform in [0.5, 1.5]).
fn noisy_colours(g: &GBuffer, rng: &mut Rng) -> Vec<[f32; 4]> {
    (0..g.depth.len())
        .map(|i| {
            let k = 0.5 + rng.next_f32();
            match (g.hit[i], g.instance[i]) {
                (false, _) => [0.0; 4],
                (true, 0) => [0.0, k * wall_green(g.position[i]), 0.0, 1.0],
                _ => [k, 0.0, 0.0, 1.0],
            }
        })
        .collect()
}

/// Renders a G-buffer for `camera` into the images `gb` (replacing their texels).
fn upload_gbuffer(host: &Host, gb: &GBufferImages, g: &GBuffer) {
    host.write_image(&gb.depth, &g.depth_bytes(), READ).unwrap();
    host.write_image(&gb.normals, &g.normal_bytes_rgba32f(), READ).unwrap();
}

/// Camera A looks at the wall and box; 16 frames; then camera B, 0.8 m to the right, for 12
/// frames, revealing wall that the box hid. Returns per frame after the move: the largest red
/// (box colour) in the revealed wall pixels, and their relative RMSE against the clean green,
/// plus the RMSE of wall pixels seen by both cameras.
fn disocclusion_run(with_motion_vectors: bool) -> Vec<(f32, f32, f32)> {
    let (host, ctx) = host_and_context(InitSettings::default());
    let scene = wall_and_box();
    let tracer = Tracer::new(&scene);
    let cam_a = Camera::look_at(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.0, -3.0));
    let cam_b = Camera::look_at(Vec3::new(0.8, 0.0, 2.0), Vec3::new(0.8, 0.0, -3.0));
    let (ga, gb) = (GBuffer::render(&tracer, &cam_a, S, S), GBuffer::render(&tracer, &cam_b, S, S));
    let images = GBufferImages::upload(&host, &ga).unwrap();
    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let out = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let motion = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, S, S, vk::ImageUsageFlags::SAMPLED, READ).unwrap();
    let dn = context(&ctx, SignalType::Diffuse, S, S);
    let mut frame = ctx.create_task_container();
    let mut rng = Rng::new(77);

    // Where B's pixels were in A (pixels, previous − current), and which were hidden there.
    let a_clip = cam_a.view_to_clip(1.0) * cam_a.world_to_view();
    let mut mv = vec![[0.0f32; 4]; (S * S) as usize];
    let mut revealed = vec![false; mv.len()];
    for i in 0..mv.len() {
        if !gb.hit[i] {
            continue;
        }
        let c = a_clip * gb.position[i].extend(1.0);
        let (ax, ay) = ((c.x / c.w * 0.5 + 0.5) * S as f32, (c.y / c.w * 0.5 + 0.5) * S as f32);
        mv[i] = [ax - ((i as u32 % S) as f32 + 0.5), ay - ((i as u32 / S) as f32 + 0.5), 0.0, 0.0];
        let j = (ay.floor() as i64 * S as i64 + ax.floor() as i64) as usize;
        let hidden = ax < 0.0 || ay < 0.0 || ax >= S as f32 || ay >= S as f32 || ga.instance[j] != gb.instance[i];
        revealed[i] = gb.instance[i] == 0 && hidden;
    }
    let stable: Vec<bool> = (0..mv.len()).map(|i| gb.hit[i] && gb.instance[i] == 0 && !revealed[i]).collect();
    assert!(revealed.iter().filter(|r| **r).count() > 40, "the move reveals wall");

    let green: Vec<f32> =
        (0..mv.len()).map(|i| if gb.hit[i] && gb.instance[i] == 0 { wall_green(gb.position[i]) } else { 0.0 }).collect();
    let mut after = Vec::new();
    for f in 0..28 {
        let (cam, g) = if f < 16 { (&cam_a, &ga) } else { (&cam_b, &gb) };
        if f == 16 {
            upload_gbuffer(&host, &images, &gb);
            if with_motion_vectors {
                host.write_image(&motion, &rgba_bytes(&mv), READ).unwrap();
            }
        }
        if f == 17 && with_motion_vectors {
            host.write_image(&motion, &rgba_bytes(&vec![[0.0; 4]; mv.len()]), READ).unwrap();
        }
        host.write_image(&noisy, &rgba_bytes(&noisy_colours(g, &mut rng)), GENERAL).unwrap();
        let mut common = images.denoising_common(cam);
        if with_motion_vectors {
            common.motion = MotionInput { image: motion.input(READ), motion_type: MotionType::RgViewSpace, scale: [1.0; 3] };
        }
        frame
            .schedule_denoise_diffuse(&DenoiseDiffuseTask {
                context: dn,
                common,
                input: noisy.input(GENERAL),
                output: out.input(GENERAL),
            })
            .unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        if f >= 16 {
            let red = read_channel(&host, &out, 0);
            let max_red = red.iter().zip(&revealed).filter(|(_, r)| **r).map(|(v, _)| *v).fold(0.0, f32::max);
            let g_out = read_channel(&host, &out, 1);
            after.push((max_red, stats::relative_rmse(&g_out, &green, &revealed), stats::relative_rmse(&g_out, &green, &stable)));
        }
    }
    ctx.destroy_denoising_context(dn).unwrap();
    for i in [noisy, out, motion] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    after
}

fn check_disocclusion(with_motion_vectors: bool) {
    let after = disocclusion_run(with_motion_vectors);
    for (k, (red, revealed, stable)) in after.iter().enumerate() {
        eprintln!(
            "frame {k} after the move: revealed wall max red {red:.4}, relative RMSE revealed {revealed:.4}, stable {stable:.4}"
        );
    }
    // No ghost: the box's red never appears on the wall it uncovered.
    assert!(after.iter().all(|(red, _, _)| *red < 0.02), "ghosting: {after:?}");
    // Recovery: the revealed pixels start from one noisy frame, spatially filtered (which
    // blurs the wall's 2.5-pixel checker), and reach the error of the pixels that kept their
    // history within the fast window (4 frames). (Those pixels' history was resampled
    // bilinearly by the 6.6-pixel move, which softens the checker too: see docs.)
    assert!(after[0].1 > after[4].1, "the revealed region improves with history");
    let (_, revealed, stable) = after[4];
    assert!(revealed <= 1.2 * stable, "frame 4: revealed {revealed} stable {stable}");
}

#[test]
fn revealed_pixels_carry_no_old_colour_with_camera_reprojection() {
    check_disocclusion(false);
}

#[test]
fn revealed_pixels_carry_no_old_colour_with_motion_vectors() {
    check_disocclusion(true);
}

/// A plane facing the camera, for tests that only need a surface under every pixel.
fn facing_plane() -> (GBuffer, Camera) {
    let mut scene = Scene::default();
    let wall = scene.add_mesh(Mesh::grid(20.0, 2));
    scene.add_instance(
        wall,
        Affine3A::from_rotation_translation(glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2), Vec3::new(0.0, 0.0, -3.0)),
    );
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.0, -3.0));
    (GBuffer::render(&Tracer::new(&scene), &camera, S, S), camera)
}

#[test]
fn mirror_reflections_stay_sharp_and_glossy_ones_are_filtered() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    assert!(g.hit.iter().filter(|h| **h).count() > (S * S * 9 / 10) as usize);
    let images = GBufferImages::upload(&host, &g).unwrap();
    // A one-pixel checker of reflected radiance (the sharpest detail a mirror can show),
    // with fresh noise each frame as a stochastic trace would have.
    let checker: Vec<[f32; 4]> =
        (0..S * S).map(|i| if (i % S + i / S).is_multiple_of(2) { [2.0, 1.0, 0.5, 3.0] } else { [0.0, 0.0, 0.0, 3.0] }).collect();
    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let mut rng = Rng::new(11);
    let mut results = Vec::new();
    for roughness in [0.0, 0.5] {
        let out = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
        let dn = context(&ctx, SignalType::Specular, S, S);
        let mut common = images.denoising_common(&camera);
        common.roughness.global_roughness = roughness;
        let mut frame = ctx.create_task_container();
        let mut input = Vec::new();
        for _ in 0..8 {
            input = checker
                .iter()
                .map(|c| {
                    let k = 0.5 + rng.next_f32();
                    [c[0] * k, c[1] * k, c[2] * k, c[3]]
                })
                .collect::<Vec<_>>();
            host.write_image(&noisy, &rgba_bytes(&input), GENERAL).unwrap();
            frame
                .schedule_denoise_specular(&DenoiseSpecularTask {
                    context: dn,
                    common,
                    input: noisy.input(GENERAL),
                    output: out.input(GENERAL),
                })
                .unwrap();
            run_frame(&host, &ctx, &mut frame).unwrap();
        }
        let r = read_channel(&host, &out, 0);
        let max_diff =
            r.iter().zip(&input).zip(&g.hit).filter(|(_, h)| **h).map(|((a, c), _)| (a - c[0]).abs()).fold(0.0, f32::max);
        eprintln!("specular, roughness {roughness}: largest difference from this frame's input {max_diff:.4}");
        results.push(max_diff);
        ctx.destroy_denoising_context(dn).unwrap();
        host.destroy_image(out);
    }
    // A mirror's reflection is exact (one deterministic ray): passed through, no blur, no
    // history to smear it when the view moves.
    // (It passes through the fp16 history: values up to 3 round by at most 2^-10 x 3.)
    assert!(results[0] < 3e-3, "a mirror passes through unchanged");
    assert!(results[1] > 0.5, "a glossy surface is filtered");
    host.destroy_image(noisy);
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// Anti-lag (diffuse): the signal jumps from red to green on a still plane; with anti-lag the
/// next frame shows no red, without it the 8-frame history does.
#[test]
fn anti_lag_restarts_a_changed_signal() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let mut left = Vec::new();
    for anti_lag in [true, false] {
        let out = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
        let dn = context(&ctx, SignalType::Diffuse, S, S);
        let mut frame = ctx.create_task_container();
        let mut common = images.denoising_common(&camera);
        common.settings.anti_lag = anti_lag;
        for f in 0..9 {
            let colour = if f < 8 { [1.0f32, 0.0, 0.0, 1.0] } else { [0.0, 1.0, 0.0, 1.0] };
            host.write_image(&noisy, &rgba_bytes(&vec![colour; (S * S) as usize]), GENERAL).unwrap();
            let task = DenoiseDiffuseTask { context: dn, common, input: noisy.input(GENERAL), output: out.input(GENERAL) };
            frame.schedule_denoise_diffuse(&task).unwrap();
            run_frame(&host, &ctx, &mut frame).unwrap();
        }
        left.push(stats::mean(&read_channel(&host, &out, 0)));
        ctx.destroy_denoising_context(dn).unwrap();
        host.destroy_image(out);
    }
    eprintln!("mean red one frame after red -> green: anti-lag {:.4}, without {:.4}", left[0], left[1]);
    assert!(left[0] < 0.01 && left[1] > 0.1, "anti-lag restarts the changed pixels: {left:?}");
    host.destroy_image(noisy);
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// `DenoiserSettings::fresh_history_taps`: a diffuse pixel's first frame is blurred with more
/// taps (on a plane under noise of mean 1 and deviation 1, as a 1-ray GI sample's), less noisy
/// and as bright.
#[test]
fn fresh_history_taps_smooth_a_first_frame() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let mut rng = Rng::new(5);
    // Exponential noise: mean 1, deviation 1, skewed as a 1-ray sample of diffuse light is.
    let texels: Vec<[f32; 4]> = (0..S * S)
        .map(|_| {
            let v = -(1.0 - rng.next_f32()).ln();
            [v, v, v, 3.0]
        })
        .collect();
    host.write_image(&noisy, &rgba_bytes(&texels), GENERAL).unwrap();
    let mut results = Vec::new();
    for taps in [0, 16] {
        let out = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
        let dn = context(&ctx, SignalType::Diffuse, S, S);
        let mut frame = ctx.create_task_container();
        let mut common = images.denoising_common(&camera);
        common.settings.fresh_history_taps = taps;
        let task = DenoiseDiffuseTask { context: dn, common, input: noisy.input(GENERAL), output: out.input(GENERAL) };
        frame.schedule_denoise_diffuse(&task).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        let red: Vec<f32> = read_channel(&host, &out, 0).into_iter().zip(&g.hit).filter(|(_, h)| **h).map(|(v, _)| v).collect();
        let mean = stats::mean(&red);
        let deviation = (red.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / red.len() as f32).sqrt();
        results.push((mean, deviation));
        ctx.destroy_denoising_context(dn).unwrap();
        host.destroy_image(out);
    }
    let [(mean_0, dev_0), (mean_16, dev_16)] = [results[0], results[1]];
    eprintln!("first frame: 0 extra taps mean {mean_0:.4} deviation {dev_0:.4}; 16: mean {mean_16:.4} deviation {dev_16:.4}");
    assert!(dev_16 < FRESH_TAPS_DEVIATION_RATIO * dev_0, "16 extra taps: deviation {dev_16} against {dev_0}");
    assert!((mean_16 - mean_0).abs() < 0.03, "16 extra taps: mean {mean_16} against {mean_0}");
    host.destroy_image(noisy);
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

#[test]
fn reset_history_drops_the_past_at_once() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let noisy = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let red = vec![[1.0f32, 0.0, 0.0, 1.0]; (S * S) as usize];
    let green = vec![[0.0f32, 1.0, 0.0, 1.0]; (S * S) as usize];
    let mut remaining_red = Vec::new();
    for reset in [true, false] {
        let out = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
        let dn = context(&ctx, SignalType::Diffuse, S, S);
        let mut frame = ctx.create_task_container();
        let mut common = images.denoising_common(&camera);
        // The control keeps its history only without anti-lag, which restarts pixels whose
        // signal jumped (red to green) on its own; with it, the same test shows anti-lag.
        common.settings.anti_lag = false;
        host.write_image(&noisy, &rgba_bytes(&red), GENERAL).unwrap();
        for f in 0..9 {
            if f == 8 {
                host.write_image(&noisy, &rgba_bytes(&green), GENERAL).unwrap();
                common.reset_history = reset;
            }
            frame
                .schedule_denoise_diffuse(&DenoiseDiffuseTask {
                    context: dn,
                    common,
                    input: noisy.input(GENERAL),
                    output: out.input(GENERAL),
                })
                .unwrap();
            run_frame(&host, &ctx, &mut frame).unwrap();
        }
        remaining_red.push(read_channel(&host, &out, 0).iter().cloned().fold(0.0, f32::max));
        ctx.destroy_denoising_context(dn).unwrap();
        host.destroy_image(out);
    }
    eprintln!(
        "largest red left one frame after red -> green: with reset {:.4}, without {:.4}",
        remaining_red[0], remaining_red[1]
    );
    assert!(remaining_red[0] < 1e-4, "reset: no red at all");
    assert!(remaining_red[1] > 0.1, "without reset (nor anti-lag) the history shows (the test is not vacuous)");
    host.destroy_image(noisy);
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

#[test]
fn specular_and_diffuse_in_one_task_equal_two_tasks() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let spec_in = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let diff_in = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let outs: Vec<HostImage> = (0..4).map(|_| storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S)).collect();
    let both = context(&ctx, SignalType::SpecularAndDiffuse, S, S);
    let spec = context(&ctx, SignalType::Specular, S, S);
    let diff = context(&ctx, SignalType::Diffuse, S, S);
    let mut common = images.denoising_common(&camera);
    common.roughness.global_roughness = 0.4;
    let mut rng = Rng::new(5);
    let mut frame = ctx.create_task_container();
    for _ in 0..4 {
        let mut noise = || (0..S * S).map(|_| [rng.next_f32(), rng.next_f32(), rng.next_f32(), 2.0]).collect::<Vec<_>>();
        host.write_image(&spec_in, &rgba_bytes(&noise()), GENERAL).unwrap();
        host.write_image(&diff_in, &rgba_bytes(&noise()), GENERAL).unwrap();
        let (si, di) = (spec_in.input(GENERAL), diff_in.input(GENERAL));
        frame
            .schedule_denoise_specular_and_diffuse(&DenoiseSpecularAndDiffuseTask {
                context: both,
                common,
                input_specular: si,
                input_diffuse: di,
                output_specular: outs[0].input(GENERAL),
                output_diffuse: outs[1].input(GENERAL),
            })
            .unwrap();
        frame
            .schedule_denoise_specular(&DenoiseSpecularTask { context: spec, common, input: si, output: outs[2].input(GENERAL) })
            .unwrap();
        frame
            .schedule_denoise_diffuse(&DenoiseDiffuseTask { context: diff, common, input: di, output: outs[3].input(GENERAL) })
            .unwrap();
        let done = run_frame(&host, &ctx, &mut frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == TaskKind::DenoiseSpecularAndDiffuse));
    }
    let read = |i: usize| host.read_image(&outs[i], GENERAL).unwrap();
    assert!(read(0) == read(2), "specular: one task equals its own");
    assert!(read(1) == read(3), "diffuse: one task equals its own");
    for dn in [both, spec, diff] {
        ctx.destroy_denoising_context(dn).unwrap();
    }
    for i in outs.into_iter().chain([spec_in, diff_in]) {
        host.destroy_image(i);
    }
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// Two lights of unequal brightness (the point light 8x): the denoised result converges to
/// their irradiance-weighted visibility.
#[test]
fn multi_light_shadows_denoise_to_the_mean_visibility() {
    const W: u32 = 64;
    let (scene, camera) = sphere_on_plane();
    let mut f = Fixture::new(&scene, None, &camera, W);
    let lights = vec![
        sun(0.2),
        LightInfo {
            light_type: LightType::Point,
            position: Vec3::new(1.0, 2.0, 1.0),
            radius: 0.2,
            intensity: 8.0,
            ..Default::default()
        },
    ];
    let visibility = f.host.image_cleared(vk::Format::R32_UINT, W, W, vk::ImageUsageFlags::STORAGE, GENERAL).unwrap();
    let packed = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let out = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
    let dn = context(&f.ctx, SignalType::MultiShadow, W, W);
    let trace = TraceMultiShadowTask {
        common: f.images.trace_common(&camera),
        lights: lights.clone(),
        visibility: visibility.input(GENERAL),
        packed: packed.input(GENERAL),
        rays_per_pixel: 1,
        first_hit: false,
        ..Default::default()
    };
    let task = DenoiseMultiShadowTask {
        context: dn,
        common: f.images.denoising_common(&camera),
        input: packed.input(GENERAL),
        output: out.input(GENERAL),
    };
    for _ in 0..FRAMES {
        f.frame.schedule_multi_shadow(&trace).unwrap();
        f.frame.schedule_denoise_multi_shadow(&task).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    }
    let raw = read_channel(&f.host, &packed, 0);
    let den = read_channel(&f.host, &out, 0);
    let reference = reference_visibility(&f, &camera, &lights, 24);
    let (raw_e, den_e) = (stats::relative_rmse(&raw, &reference, &f.g.hit), stats::relative_rmse(&den, &reference, &f.g.hit));
    eprintln!("two-light shadows, 1 ray/pixel/light, {FRAMES} frames: relative RMSE raw {raw_e:.4}, denoised {den_e:.4}");
    // The raw weighted mean of two 1-ray lights takes few values, and the 8x brighter point
    // light (small penumbrae) dominates it, so the raw error is already low (0.052; 0.067 for
    // the unweighted mean) and the gain smaller than for one light: the filter still halves it.
    assert!(den_e < 0.04 && den_e * 2.0 < raw_e, "raw {raw_e} denoised {den_e}");
    f.ctx.destroy_denoising_context(dn).unwrap();
    f.finish([visibility, packed, out]);
}

#[test]
fn bad_denoise_inputs_are_typed_errors_and_leave_the_context_usable() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let img = storage_image(&host, vk::Format::R32G32B32A32_SFLOAT, S, S);
    let io = img.input(GENERAL);

    for (w, h) in [(0, 8), (8, 0), (MAX_DENOISING_EXTENT + 1, 8)] {
        let r = ctx.create_denoising_context(&DenoisingContextInput { max_width: w, max_height: h, ..Default::default() });
        assert!(matches!(r, Err(Error::InvalidInput { .. })), "{w}x{h}: {r:?}");
    }
    let ao = context(&ctx, SignalType::DiffuseOcclusion, S, S);
    let small = context(&ctx, SignalType::Diffuse, S / 2, S / 2);
    let diffuse = context(&ctx, SignalType::Diffuse, S, S);
    let common = images.denoising_common(&camera);
    let task = |context| DenoiseDiffuseTask { context, common, input: io, output: io };
    let mut frame = ctx.create_task_container();

    // At scheduling: null and destroyed handles, settings, formats, motion, jitter.
    assert!(matches!(frame.schedule_denoise_diffuse(&task(DenoisingContextHandle::NULL)), Err(Error::InvalidHandle { .. })));
    let gone = context(&ctx, SignalType::Diffuse, S, S);
    ctx.destroy_denoising_context(gone).unwrap();
    assert!(matches!(
        frame.schedule_denoise_diffuse(&task(gone)),
        Err(Error::InvalidHandle { problem: HandleProblem::Destroyed, .. })
    ));
    assert!(matches!(ctx.destroy_denoising_context(gone), Err(Error::InvalidHandle { .. })));
    let mut bad = task(diffuse);
    bad.common.settings.spatial_passes = 7;
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::InvalidInput { .. })));
    let mut bad = task(diffuse);
    bad.common.settings.fast_history_frames = 64;
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::InvalidInput { .. })));
    let mut bad = task(diffuse);
    bad.input.format = vk::Format::R8_UNORM;
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::UnsupportedFormat { .. })));
    let mut bad = task(diffuse);
    bad.output.layout = READ;
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::InvalidInput { .. })));
    let mut bad = task(diffuse);
    bad.common.camera_jitter = [f32::NAN, 0.0];
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::InvalidInput { .. })));
    let mut bad = task(diffuse);
    bad.common.previous_camera =
        Some(hybrid_rt::Camera { world_to_view: glam::Mat4::from_cols_array(&[f32::NAN; 16]), ..Default::default() });
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::InvalidTransform { .. })));
    let mut bad = task(diffuse);
    bad.common.motion = MotionInput { image: images.depth.input(READ), ..Default::default() };
    assert!(matches!(frame.schedule_denoise_diffuse(&bad), Err(Error::UnsupportedFormat { .. })));
    assert!(frame.is_empty(), "refused tasks are not scheduled");

    // At build: a context of another signal, or too small for the viewport. The container
    // keeps its tasks; nothing is recorded.
    for wrong in [ao, small] {
        frame.schedule_denoise_diffuse(&task(wrong)).unwrap();
        let e = run_frame(&host, &ctx, &mut frame).unwrap_err();
        assert!(e.contains("DenoiseDiffuseTask.context") || e.contains("DenoisingCommon.viewport"), "{e}");
        assert_eq!(frame.len(), 1);
        frame.clear();
    }
    // A small viewport far into the image: its pixels lie outside a context that is wide
    // enough for its size but not for its position.
    let narrow = context(&ctx, SignalType::Diffuse, S / 2 + 4, S);
    let mut offset = task(narrow);
    offset.common.viewport = Viewport { x: S / 2, width: 8, ..offset.common.viewport };
    frame.schedule_denoise_diffuse(&offset).unwrap();
    assert!(run_frame(&host, &ctx, &mut frame).unwrap_err().contains("beyond the context"));
    frame.clear();
    ctx.destroy_denoising_context(narrow).unwrap();
    // A context destroyed between scheduling and building.
    let doomed = context(&ctx, SignalType::Diffuse, S, S);
    frame.schedule_denoise_diffuse(&task(doomed)).unwrap();
    ctx.destroy_denoising_context(doomed).unwrap();
    assert!(run_frame(&host, &ctx, &mut frame).unwrap_err().contains("destroyed"));
    frame.clear();

    // Still usable.
    frame.schedule_denoise_diffuse(&task(diffuse)).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    assert!(ctx.resource_allocations().denoiser.bytes > 0);
    for dn in [ao, small, diffuse] {
        ctx.destroy_denoising_context(dn).unwrap();
    }
    ctx.release_device_resources_immediately().unwrap();
    assert_eq!(ctx.resource_allocations().denoiser.count, 0, "destroyed contexts' images are freed");
    host.destroy_image(img);
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// The passes' intermediates are one set shared by every context: a second context of the same
/// size and signal adds only what it keeps (its guide pair, its history, its moving-object
/// tiles), and the last one destroyed frees the shared set too.
#[test]
fn contexts_share_their_intermediates() {
    let (_host, ctx) = host_and_context(InitSettings::default());
    let count = || ctx.resource_allocations().denoiser.count;
    let a = context(&ctx, SignalType::DiffuseOcclusion, 64, 64);
    let first = count();
    assert_eq!(first, 7, "guide pair, history and moving-object tiles (4) + the shared pair and tile map (3)");
    let b = context(&ctx, SignalType::DiffuseOcclusion, 64, 64);
    assert_eq!(count(), first + 4, "the second context keeps only its own guide, history and tiles");
    let bytes_two = ctx.resource_allocations().denoiser.bytes;
    for h in [a, b] {
        ctx.destroy_denoising_context(h).unwrap();
    }
    ctx.release_device_resources_immediately().unwrap();
    assert_eq!(count(), 0, "the last context frees the shared set");
    eprintln!("two 64x64 AO contexts: {bytes_two} bytes of denoiser images (11 images)");
    drop(ctx);
    assert_no_validation_errors();
}

/// A floor, a wall behind it, a low box (its top parallel to the floor, a step) and a sphere:
/// surfaces that share a normal but not a plane, and shadows that cross from one to another.
fn steps() -> (Scene, Camera) {
    let mut scene = Scene::default();
    let floor = scene.add_mesh(Mesh::grid(8.0, 4));
    let wall = scene.add_mesh(Mesh::grid(8.0, 4));
    let step = scene.add_mesh(Mesh::cuboid(Vec3::new(0.6, 0.15, 0.4)));
    let sphere = scene.add_mesh(Mesh::sphere(0.35, 16, 8));
    scene.add_instance(floor, Affine3A::IDENTITY);
    scene.add_instance(
        wall,
        Affine3A::from_rotation_translation(glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2), Vec3::new(0.0, 0.0, -1.2)),
    );
    scene.add_instance(step, Affine3A::from_translation(Vec3::new(0.3, 0.15, -0.2)));
    scene.add_instance(sphere, Affine3A::from_translation(Vec3::new(-0.5, 0.35, 0.1)));
    (scene, Camera::look_at(Vec3::new(0.0, 1.4, 2.0), Vec3::new(0.0, 0.2, -0.4)))
}

/// Every `DenoiserSettings` field changes the image of every denoiser its documentation says
/// reads it: each variant denoises the same noisy frames (one trace, several contexts) and is
/// compared with the defaults after 6 frames. The scene: `steps` (shared normals on different
/// planes, shadows across surfaces), and for GI's firefly cut the closed room, where the rare
/// rays out of its open front see a bright sky.
#[test]
fn every_setting_affects_the_denoisers_that_read_it() {
    type Change = (&'static str, fn(&mut DenoiserSettings));
    let all: [Change; 9] = [
        ("max_history_frames", |s| s.max_history_frames = 4),
        ("fast_history_frames", |s| s.fast_history_frames = 1),
        ("history_clamp_sigma", |s| s.history_clamp_sigma = 0.3),
        ("spatial_passes", |s| s.spatial_passes = 1),
        ("luminance_sigma", |s| s.luminance_sigma = 0.3),
        ("normal_power", |s| s.normal_power = 0.5),
        ("plane_distance_sigma", |s| s.plane_distance_sigma = 1.0),
        ("anti_firefly", |s| s.anti_firefly = false),
        ("max_shadow_blur_radius", |s| s.max_shadow_blur_radius = 1.0),
    ];
    // Which denoisers read each field (DenoiserSettings' documentation). `anti_lag` acts only
    // when the signal changes: a_moving_object_leaves_no_old_occlusion_behind (AO) and
    // anti_lag_restarts_a_changed_signal (diffuse) show it; `moving_object_reach` only while
    // objects move: a_sliding_object_s_occlusion_follows_it (denoise_quality.rs) shows it;
    // `fresh_history_taps` only on pixels with under 4 frames of history:
    // fresh_history_taps_smooth_a_first_frame shows it.
    let reads = |signal: SignalType, field: &str| match field {
        "max_history_frames" | "normal_power" | "plane_distance_sigma" => true,
        "fast_history_frames" | "history_clamp_sigma" | "spatial_passes" | "luminance_sigma" => signal != SignalType::Shadow,
        "anti_firefly" => signal == SignalType::Diffuse,
        _ => signal == SignalType::Shadow,
    };
    const W: u32 = 48;
    for (signal, in_room) in [
        (SignalType::Diffuse, false),
        (SignalType::Diffuse, true),
        (SignalType::DiffuseOcclusion, false),
        (SignalType::Shadow, false),
    ] {
        let (scene, colours, camera) = if in_room {
            let (s, c, cam) = reference::coloured_room(true);
            (s, Some(c), cam)
        } else {
            let (s, cam) = steps();
            (s, None, cam)
        };
        let mut f = Fixture::new(&scene, colours.as_deref(), &camera, W);
        let noisy = storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W);
        let changes: Vec<&Change> =
            all.iter().filter(|(name, _)| reads(signal, name) && (in_room == (*name == "anti_firefly"))).collect();
        let outs: Vec<HostImage> =
            (0..=changes.len()).map(|_| storage_image(&f.host, vk::Format::R32G32B32A32_SFLOAT, W, W)).collect();
        let contexts: Vec<DenoisingContextHandle> = (0..=changes.len()).map(|_| context(&f.ctx, signal, W, W)).collect();
        // A wide sun (1 rad): penumbrae wide enough at 48x48 that the shadow blur crosses the
        // sphere's curve, where normal_power acts.
        let sun = LightInfo {
            light_type: LightType::Directional,
            direction: Vec3::new(0.6, -0.6, -0.5),
            angular_extent: 1.0,
            ..Default::default()
        };
        let common = f.images.trace_common(&camera);
        for _ in 0..6 {
            let output = noisy.input(GENERAL);
            match signal {
                SignalType::Diffuse => f
                    .frame
                    .schedule_diffuse(&TraceDiffuseTask {
                        common,
                        output,
                        ray_length: 100.0,
                        miss_radiance: [40.0; 3],
                        ..Default::default()
                    })
                    .unwrap(),
                SignalType::DiffuseOcclusion => f
                    .frame
                    .schedule_ambient_occlusion(&TraceAmbientOcclusionTask {
                        common,
                        output,
                        ray_length: 1.0,
                        ..Default::default()
                    })
                    .unwrap(),
                _ => f.frame.schedule_shadow(&TraceShadowTask { common, light: sun, output, ..Default::default() }).unwrap(),
            }
            for (k, (&context, out)) in contexts.iter().zip(&outs).enumerate() {
                let mut common = f.images.denoising_common(&camera);
                if k > 0 {
                    (changes[k - 1].1)(&mut common.settings);
                }
                let (input, output) = (noisy.input(GENERAL), out.input(GENERAL));
                match signal {
                    SignalType::Diffuse => {
                        f.frame.schedule_denoise_diffuse(&DenoiseDiffuseTask { context, common, input, output }).unwrap()
                    }
                    SignalType::DiffuseOcclusion => f
                        .frame
                        .schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask { context, common, input, output })
                        .unwrap(),
                    _ => f
                        .frame
                        .schedule_denoise_shadow(&DenoiseShadowTask { context, common, light: sun, input, output })
                        .unwrap(),
                }
            }
            run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        }
        let base = read_channel(&f.host, &outs[0], 0);
        for (k, (name, _)) in changes.iter().enumerate() {
            let other = read_channel(&f.host, &outs[k + 1], 0);
            let diff = base.iter().zip(&other).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
            eprintln!("{signal:?}{}, {name}: max |change| {diff:.4}", if in_room { " (room)" } else { "" });
            assert!(diff > 1e-3, "{signal:?}: {name} has no effect ({diff})");
        }
        for dn in contexts {
            f.ctx.destroy_denoising_context(dn).unwrap();
        }
        f.finish(outs.into_iter().chain([noisy]));
    }
}

/// One frame of a specular + diffuse denoiser and a shadow denoiser on noise, in a context
/// with `time_passes` as given: the two outputs' bytes and the ticket's pass timings.
fn denoise_with_pass_timing(time_passes: bool) -> (Vec<u8>, Vec<u8>, Vec<PassTiming>, Vec<TaskTiming>) {
    let (host, ctx) = host_and_context(InitSettings { time_passes, ..Default::default() });
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let format = vk::Format::R32G32B32A32_SFLOAT;
    let [spec_in, diff_in, spec_out, diff_out, shadow_in, shadow_out] = [(); 6].map(|_| storage_image(&host, format, S, S));
    let mut rng = Rng::new(11);
    for input in [&spec_in, &diff_in, &shadow_in] {
        let noise: Vec<[f32; 4]> = (0..S * S).map(|_| [rng.next_f32(), rng.next_f32(), rng.next_f32(), 2.0]).collect();
        host.write_image(input, &rgba_bytes(&noise), GENERAL).unwrap();
    }
    let both = context(&ctx, SignalType::SpecularAndDiffuse, S, S);
    let shadow = context(&ctx, SignalType::Shadow, S, S);
    let mut common = images.denoising_common(&camera);
    common.roughness.global_roughness = 0.4;
    let mut frame = ctx.create_task_container();
    frame
        .schedule_denoise_specular_and_diffuse(&DenoiseSpecularAndDiffuseTask {
            context: both,
            common,
            input_specular: spec_in.input(GENERAL),
            input_diffuse: diff_in.input(GENERAL),
            output_specular: spec_out.input(GENERAL),
            output_diffuse: diff_out.input(GENERAL),
        })
        .unwrap();
    frame
        .schedule_denoise_shadow(&DenoiseShadowTask {
            context: shadow,
            common,
            light: sun(0.05),
            input: shadow_in.input(GENERAL),
            output: shadow_out.input(GENERAL),
        })
        .unwrap();
    let done = run_frame(&host, &ctx, &mut frame).unwrap();
    let (spec, shadow_bytes) = (host.read_image(&spec_out, GENERAL).unwrap(), host.read_image(&shadow_out, GENERAL).unwrap());
    for dn in [both, shadow] {
        ctx.destroy_denoising_context(dn).unwrap();
    }
    for i in [spec_in, diff_in, spec_out, diff_out, shadow_in, shadow_out] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    (spec, shadow_bytes, done.pass_timings, done.timings)
}

/// `InitSettings::time_passes` reports every denoiser pass by name, in recording order, nested
/// in its task's interval, and changes nothing in the images; without it no pass is timed.
#[test]
fn pass_timings_name_every_denoiser_pass_and_change_no_pixel() {
    let (spec_plain, shadow_plain, none, _) = denoise_with_pass_timing(false);
    assert!(none.is_empty(), "passes timed without time_passes: {none:?}");
    let (spec, shadow, passes, tasks) = denoise_with_pass_timing(true);
    assert!(spec == spec_plain && shadow == shadow_plain, "timing the passes changed the denoised images");
    let names = |kind: TaskKind| passes.iter().filter(|p| p.kind == kind).map(|p| p.pass).collect::<Vec<_>>();
    let radiance = ["temporal", "blur_1", "blur_2"];
    assert_eq!(names(TaskKind::DenoiseSpecularAndDiffuse), radiance);
    assert_eq!(names(TaskKind::DenoiseShadow), ["shadow_prep", "shadow_blur", "shadow_temporal"]);
    // The render tasks' intervals (the recording's others, `CacheUpdate` say, share index 0).
    let denoisers: Vec<&TaskTiming> =
        tasks.iter().filter(|t| matches!(t.kind, TaskKind::DenoiseSpecularAndDiffuse | TaskKind::DenoiseShadow)).collect();
    assert_eq!(denoisers.len(), 2, "{tasks:?}");
    for task in denoisers {
        let parts: Vec<&PassTiming> = passes.iter().filter(|p| p.task_index == task.task_index).collect();
        assert!(parts.iter().all(|p| p.kind == task.kind && p.gpu_ms.is_finite() && p.gpu_ms >= 0.0), "{parts:?}");
        // Nested: the passes lie inside the task's interval (timestamp ticks, so no tolerance
        // beyond rounding).
        let sum: f64 = parts.iter().map(|p| p.gpu_ms).sum();
        assert!(sum <= task.gpu_ms * (1.0 + 1e-9) + 1e-9, "{:?}: passes {sum} ms > task {} ms", task.kind, task.gpu_ms);
    }
}

/// Four frames of an AO and a shadow denoiser on noise over a plane seen by a camera that
/// moves, their contexts created with `view_id`: the two outputs' bytes, and the count and
/// bytes of the denoiser images while the contexts live.
fn denoise_one_view(view_id: u32) -> (Vec<u8>, Vec<u8>, u64, u64) {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let format = vk::Format::R32G32B32A32_SFLOAT;
    let [ao_in, ao_out, shadow_in, shadow_out] = [(); 4].map(|_| storage_image(&host, format, S, S));
    let make = |signal| {
        let input = DenoisingContextInput { max_width: S, max_height: S, signal, view_id, ..Default::default() };
        ctx.create_denoising_context(&input).unwrap()
    };
    let (ao, shadow) = (make(SignalType::DiffuseOcclusion), make(SignalType::Shadow));
    let allocations = ctx.resource_allocations().denoiser;
    let mut rng = Rng::new(23);
    let mut frame = ctx.create_task_container();
    for f in 0..4 {
        for input in [&ao_in, &shadow_in] {
            let noise: Vec<[f32; 4]> = (0..S * S).map(|_| [rng.next_f32(), rng.next_f32(), 0.0, 1.0]).collect();
            host.write_image(input, &rgba_bytes(&noise), GENERAL).unwrap();
        }
        // The camera slides a little each frame (the G-buffer stays: reprojection moves).
        let moved = Camera::look_at(Vec3::new(0.02 * f as f32, 0.0, 2.0), Vec3::new(0.02 * f as f32, 0.0, -3.0));
        let common = DenoisingCommon { camera: images.denoising_common(&moved).camera, ..images.denoising_common(&camera) };
        let (input, output) = (ao_in.input(GENERAL), ao_out.input(GENERAL));
        frame.schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask { context: ao, common, input, output }).unwrap();
        let (input, output) = (shadow_in.input(GENERAL), shadow_out.input(GENERAL));
        frame.schedule_denoise_shadow(&DenoiseShadowTask { context: shadow, common, light: sun(0.1), input, output }).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
    }
    let outputs = (host.read_image(&ao_out, GENERAL).unwrap(), host.read_image(&shadow_out, GENERAL).unwrap());
    for dn in [ao, shadow] {
        ctx.destroy_denoising_context(dn).unwrap();
    }
    for i in [ao_in, ao_out, shadow_in, shadow_out] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    (outputs.0, outputs.1, allocations.count, allocations.bytes)
}

/// Contexts of one view keep one guide between them (two images of 4 bytes a pixel fewer)
/// and denoise exactly as with a guide each.
#[test]
fn contexts_of_one_view_share_their_guide_and_denoise_the_same() {
    let (ao_alone, shadow_alone, count_alone, bytes_alone) = denoise_one_view(0);
    let (ao_shared, shadow_shared, count_shared, bytes_shared) = denoise_one_view(7);
    assert!(ao_alone == ao_shared, "AO denoised differently with a shared guide");
    assert!(shadow_alone == shadow_shared, "shadow denoised differently with a shared guide");
    assert_eq!(count_shared + 2, count_alone, "one guide pair fewer");
    // Two R32_UINT guide images of SxS fewer, as the driver sizes them: their texels' bytes
    // on lavapipe; drivers that pad rows or align sizes add less than a 64 KiB page to each.
    let saved = bytes_alone.checked_sub(bytes_shared).expect("a shared guide took more memory");
    let texels = 4 * (S * S) as u64;
    assert!(
        saved % 2 == 0 && (texels..texels + 65536).contains(&(saved / 2)),
        "saved {saved} bytes: not two R32_UINT guide images of {S}x{S}"
    );
}

/// A view's contexts have one size, and one view's tasks in a container one camera: both are
/// refused with a typed error that leaves the context usable.
#[test]
fn a_view_refuses_a_second_size_and_a_second_camera() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let view = |w, signal| DenoisingContextInput { max_width: w, max_height: w, signal, view_id: 3, ..Default::default() };
    let ao = ctx.create_denoising_context(&view(S, SignalType::DiffuseOcclusion)).unwrap();
    match ctx.create_denoising_context(&view(S / 2, SignalType::Shadow)) {
        Err(Error::InvalidInput { what: "DenoisingContextInput.view_id", .. }) => {}
        other => panic!("a second size in one view: {other:?}"),
    }
    let shadow = ctx.create_denoising_context(&view(S, SignalType::Shadow)).unwrap();
    let (g, camera) = facing_plane();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let format = vk::Format::R32G32B32A32_SFLOAT;
    let [input, output] = [(); 2].map(|_| storage_image(&host, format, S, S));
    let (i, o) = (input.input(GENERAL), output.input(GENERAL));
    let common = images.denoising_common(&camera);
    let elsewhere = Camera::look_at(Vec3::new(1.0, 0.0, 2.0), Vec3::new(0.0, 0.0, -3.0));
    let other = DenoisingCommon { camera: images.denoising_common(&elsewhere).camera, ..common };
    let mut frame = ctx.create_task_container();
    let schedule = |frame: &mut TaskContainer, shadow_common: DenoisingCommon| {
        frame
            .schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask { context: ao, common, input: i, output: o })
            .unwrap();
        let task = DenoiseShadowTask { context: shadow, common: shadow_common, light: sun(0.1), input: i, output: o };
        frame.schedule_denoise_shadow(&task).unwrap();
    };
    schedule(&mut frame, other);
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    match unsafe { ctx.build_gpu_task(&mut frame, cmd) } {
        Err(Error::InvalidInput { what: "DenoisingContextInput.view_id", .. }) => {}
        other => panic!("two cameras in one view: {other:?}"),
    }
    unsafe { host.device.end_command_buffer(cmd).unwrap() };
    frame.clear();
    schedule(&mut frame, common);
    run_frame(&host, &ctx, &mut frame).expect("the view's contexts work after the refusals");
    for dn in [ao, shadow] {
        ctx.destroy_denoising_context(dn).unwrap();
    }
    for img in [input, output] {
        host.destroy_image(img);
    }
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// What one more context of a view keeps, the view's guide and the shared intermediates made:
/// a shadow context 4 bytes a pixel (its single history: visibility and length as halves),
/// an AO context 8 (its slow and fast history, value and moment / length, in one RGBA16F).
#[test]
fn kept_bytes_per_pixel_of_a_view_context() {
    let (_host, ctx) = host_and_context(InitSettings::default());
    let input = |signal| DenoisingContextInput { max_width: 64, max_height: 64, signal, view_id: 2, ..Default::default() };
    let first = ctx.create_denoising_context(&input(SignalType::Shadow)).unwrap();
    let bytes = || ctx.resource_allocations().denoiser.bytes;
    let mut kept = Vec::new();
    let mut made = vec![first];
    for signal in [SignalType::Shadow, SignalType::DiffuseOcclusion] {
        let before = bytes();
        made.push(ctx.create_denoising_context(&input(signal)).unwrap());
        kept.push((bytes() - before) / (64 * 64));
    }
    assert_eq!(kept, [4, 8], "bytes a pixel kept by one more shadow and AO context of the view");
    for h in made {
        ctx.destroy_denoising_context(h).unwrap();
    }
    drop(ctx);
    assert_no_validation_errors();
}
