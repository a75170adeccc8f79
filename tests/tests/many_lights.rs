//! Many shadowed lights by resampling (`TraceManyLightsTask`) against brute force: 1,024 sphere
//! lights over a floor with boxes on it and a wall that half of them stand behind (they must not
//! leak through), every light evaluated with shadow rays in the CPU reference.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{
    InitSettings, LightInfo, LightListUpdate, LightType, ManyLightsContextInput, ManyLightsSettings, ResamplingMode, TraceCommon,
    TraceManyLightsTask,
};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 64;
const H: u32 = 48;
const ROUGHNESS: f32 = 0.5;

/// A floor, three boxes on it, and a wall 3 m high across the back.
fn scene() -> (Scene, Camera) {
    let mut s = Scene::default();
    let floor = s.add_mesh(Mesh::grid(10.0, 4));
    let wall = s.add_mesh(Mesh::cuboid(Vec3::new(5.0, 1.5, 0.1)));
    let cube = s.add_mesh(Mesh::cuboid(Vec3::splat(0.3)));
    s.add_instance(floor, Affine3A::IDENTITY);
    s.add_instance(wall, Affine3A::from_translation(Vec3::new(0.0, 1.5, -1.2)));
    for x in [-1.5f32, 0.2, 1.6] {
        s.add_instance(cube, Affine3A::from_translation(Vec3::new(x, 0.3, 0.6 - x * 0.3)));
    }
    (s, Camera::look_at(Vec3::new(0.0, 3.2, 4.2), Vec3::new(0.0, 0.3, -0.6)))
}

/// 32 x 32 small sphere lights of random colour and brightness over the whole floor, 0.9-2 m
/// up (above the boxes) and at least 0.35 m from the wall, each reaching 2.5 m: those behind
/// the wall light only its back. (A light a few centimetres from a surface is a singularity
/// that no light sampler finds in a few frames, and that would dominate the error measures.)
fn lights() -> Vec<LightInfo> {
    let mut rng = Rng::new(7);
    let mut lights = Vec::new();
    for j in 0..32 {
        for i in 0..32 {
            let x = -4.6 + 9.2 * (i as f32 + rng.next_f32()) / 32.0;
            let mut z = -4.6 + 8.6 * (j as f32 + rng.next_f32()) / 32.0;
            if (z + 1.2).abs() < 0.35 {
                z = -1.2 + 0.35 * (z + 1.2).signum();
            }
            let y = 0.9 + 1.1 * rng.next_f32();
            let colour = [0.2 + rng.next_f32(), 0.2 + rng.next_f32(), 0.2 + rng.next_f32()];
            lights.push(LightInfo {
                light_type: LightType::Point,
                position: Vec3::new(x, y, z),
                radius: 0.02,
                range: 2.5,
                intensity: 0.1 + 0.9 * rng.next_f32() * rng.next_f32(),
                color: colour,
                ..Default::default()
            });
        }
    }
    lights
}

/// The reference's combined radiance per pixel (diffuse + specular, white albedo and F0), and
/// the surface mask.
fn reference(scene: &Scene, camera: &Camera, g: &GBuffer, lights: &[LightInfo]) -> (Vec<f32>, Vec<bool>) {
    let tracer = Tracer::new(scene);
    let mut rng = Rng::new(3);
    let r = many_lights_reference(&tracer, g, camera.eye, lights, ROUGHNESS, &Default::default(), 2, &mut rng);
    let radiance = r.iter().map(|(d, s)| luminance(Vec3::from_array(*d) + Vec3::from_array(*s))).collect();
    (radiance, g.hit.clone())
}

/// Frames of the task on the scene: per frame the combined radiance (luminance of diffuse +
/// specular) and the debug output's sample counts.
struct Run {
    frames: Vec<Vec<f32>>,
    counts: Vec<Vec<f32>>,
    /// With `denoise`: the outputs through `DenoiseSpecularAndDiffuseTask`, per frame.
    denoised: Vec<Vec<f32>>,
}

fn run(settings: ManyLightsSettings, lights: &[LightInfo], frames: u32, change: impl Fn(u32) -> Option<LightListUpdate>) -> Run {
    run_seeded(settings, lights, frames, 0, false, change)
}

/// `run` with the frames numbered from `first_frame` (the SDK's random numbers follow it).
fn run_seeded(
    settings: ManyLightsSettings,
    lights: &[LightInfo],
    frames: u32,
    first_frame: u64,
    denoise: bool,
    change: impl Fn(u32) -> Option<LightListUpdate>,
) -> Run {
    run_with(settings, lights, frames, first_frame, denoise, false, change)
}

/// `run_seeded`, through inline ray queries when `inline` (where the device has them).
fn run_with(
    settings: ManyLightsSettings,
    lights: &[LightInfo],
    frames: u32,
    first_frame: u64,
    denoise: bool,
    inline: bool,
    change: impl Fn(u32) -> Option<LightListUpdate>,
) -> Run {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let rgba = |_: ()| host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, usage, vk::ImageLayout::GENERAL).unwrap();
    let (diffuse, specular, debug) = (rgba(()), rgba(()), rgba(()));
    let (denoised_diffuse, denoised_specular) = (rgba(()), rgba(()));
    let denoiser = ctx
        .create_denoising_context(&hybrid_rt::DenoisingContextInput {
            max_width: W,
            max_height: H,
            signal: hybrid_rt::SignalType::SpecularAndDiffuse,
            ..Default::default()
        })
        .unwrap();
    let context =
        ctx.create_many_lights_context(&ManyLightsContextInput { max_width: W, max_height: H, max_lights: 4096 }).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let mut common = images.trace_common(&camera);
    common.roughness.global_roughness = ROUGHNESS;
    common.use_inline_rt = inline;
    let mut out = Run { frames: Vec::new(), counts: Vec::new(), denoised: Vec::new() };
    for f in 0..frames {
        let update = if f == 0 { Some(LightListUpdate::Replace(lights.to_vec())) } else { change(f) };
        let task = TraceManyLightsTask {
            context,
            common,
            lights: update.unwrap_or_default(),
            diffuse_output: diffuse.input(vk::ImageLayout::GENERAL),
            specular_output: specular.input(vk::ImageLayout::GENERAL),
            debug_output: debug.input(vk::ImageLayout::GENERAL),
            settings,
            ..Default::default()
        };
        frame.schedule_many_lights(&task).unwrap();
        if denoise {
            let mut dc = images.denoising_common(&camera);
            dc.roughness = common.roughness;
            frame
                .schedule_denoise_specular_and_diffuse(&hybrid_rt::DenoiseSpecularAndDiffuseTask {
                    context: denoiser,
                    common: dc,
                    input_specular: specular.input(vk::ImageLayout::GENERAL),
                    input_diffuse: diffuse.input(vk::ImageLayout::GENERAL),
                    output_specular: denoised_specular.input(vk::ImageLayout::GENERAL),
                    output_diffuse: denoised_diffuse.input(vk::ImageLayout::GENERAL),
                })
                .unwrap();
        }
        frame.set_frame_index(first_frame + f as u64);
        let done = run_frame(&host, &ctx, &mut frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::ManyLights));
        let read =
            |i: &_| -> Vec<[f32; 4]> { bytemuck::cast_slice(&host.read_image(i, vk::ImageLayout::GENERAL).unwrap()).to_vec() };
        let (d, sp, db) = (read(&diffuse), read(&specular), read(&debug));
        out.frames.push(d.iter().zip(&sp).map(|(a, b)| luminance(Vec3::new(a[0] + b[0], a[1] + b[1], a[2] + b[2]))).collect());
        out.counts.push(db.iter().map(|t| t[3]).collect());
        if denoise {
            let (d, sp) = (read(&denoised_diffuse), read(&denoised_specular));
            out.denoised
                .push(d.iter().zip(&sp).map(|(a, b)| luminance(Vec3::new(a[0] + b[0], a[1] + b[1], a[2] + b[2]))).collect());
        }
    }
    ctx.destroy_many_lights_context(context).unwrap();
    ctx.destroy_denoising_context(denoiser).unwrap();
    for i in [diffuse, specular, debug, denoised_diffuse, denoised_specular] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    out
}

/// Mean over frames `from..`.
fn mean_of(frames: &[Vec<f32>], from: usize) -> Vec<f32> {
    let n = (frames.len() - from) as f32;
    (0..frames[0].len()).map(|i| frames[from..].iter().map(|f| f[i]).sum::<f32>() / n).collect()
}

/// Relative bias over the masked pixels: sum(x) / sum(reference) - 1.
fn bias(x: &[f32], reference: &[f32], mask: &[bool]) -> f32 {
    let (a, b) = x
        .iter()
        .zip(reference)
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0f64, 0.0f64), |(a, b), ((x, r), _)| (a + *x as f64, b + *r as f64));
    (a / b.max(1e-12) - 1.0) as f32
}

/// Relative RMSE over the masked pixels.
fn rmse(x: &[f32], reference: &[f32], mask: &[bool]) -> f32 {
    hybrid_rt_testkit::stats::relative_rmse(x, reference, mask)
}

/// Per seed (independent runs of 32 frames, the frames numbered from seed x 1000), the bias of
/// the mean of frames 16..32; returns their mean and its standard error.
fn bias_over_seeds(
    settings: ManyLightsSettings,
    lights: &[LightInfo],
    reference: &[f32],
    mask: &[bool],
    seeds: u64,
) -> (f32, f32) {
    let biases: Vec<f32> = (1..=seeds)
        .map(|seed| bias(&mean_of(&run_seeded(settings, lights, 32, seed * 1000, false, |_| None).frames, 16), reference, mask))
        .collect();
    eprintln!("per run: {biases:?}");
    let n = biases.len() as f32;
    let mean = biases.iter().sum::<f32>() / n;
    let sd = (biases.iter().map(|b| (b - mean).powi(2)).sum::<f32>() / (n - 1.0)).sqrt();
    (mean, sd / n.sqrt())
}

/// The test image is 64 pixels wide: neighbours within 4 pixels (24 at 1080p cover a similar
/// part of a surface).
fn settings(mode: ResamplingMode) -> ManyLightsSettings {
    ManyLightsSettings { mode, spatial_radius: 4.0, ..Default::default() }
}

/// The unbiased mode converges to brute force: over independent runs the image's mean after 16
/// frames of warm-up is the reference's within three standard errors of the runs' spread (the
/// frames of one run are correlated by reuse, so runs, not frames, are the samples), plus 0.5%
/// for the reference's own error (four shadow rays per light and pixel).
#[test]
fn unbiased_mode_converges_to_brute_force() {
    let lights = lights();
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (reference, mask) = reference(&scene, &camera, &g, &lights);
    let (b, se) = bias_over_seeds(settings(ResamplingMode::Unbiased), &lights, &reference, &mask, 12);
    eprintln!("unbiased: bias {b:+.4} (standard error {se:.4}, 12 runs)");
    assert!(b.abs() <= 3.0 * se + 0.005, "unbiased mode off by {b:+.4} (standard error {se:.4})");
    assert!(se <= 0.02, "the runs' spread grew: standard error {se:.4}");
}

/// Every kind of light in one list: the test's sphere lights, every third turned into a spot
/// light aimed down at a random tilt (cones of 0.3-0.7 rad), and two directional lights with
/// angular size (a low sun the wall shades, and a dim one from above) — the directional
/// candidates are a strategy of their own. The unbiased mode's mean over independent runs is
/// brute force's within three standard errors plus 1% (the reference's own error).
#[test]
fn every_light_type_converges_to_brute_force() {
    let mut lights = lights();
    let mut rng = Rng::new(11);
    for l in lights.iter_mut().step_by(3) {
        let tilt = Vec3::new(rng.next_f32() - 0.5, -1.0, rng.next_f32() - 0.5);
        let outer = 0.3 + 0.4 * rng.next_f32();
        *l = LightInfo {
            light_type: LightType::Spot,
            direction: tilt,
            outer_cone: outer,
            inner_cone: 0.6 * outer,
            intensity: 3.0 * l.intensity,
            ..*l
        };
    }
    let sun = |direction: Vec3, intensity: f32| LightInfo {
        light_type: LightType::Directional,
        direction,
        angular_extent: 0.05,
        intensity,
        color: [1.0, 0.95, 0.9],
        ..Default::default()
    };
    lights.push(sun(Vec3::new(0.3, -0.5, 1.0), 0.5));
    lights.push(sun(Vec3::new(-0.2, -1.0, -0.1), 0.2));
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (reference, mask) = reference(&scene, &camera, &g, &lights);
    let (b, se) = bias_over_seeds(settings(ResamplingMode::Unbiased), &lights, &reference, &mask, 8);
    eprintln!("every light type, unbiased: bias {b:+.4} (standard error {se:.4}, 8 runs)");
    assert!(b.abs() <= 3.0 * se + 0.01, "unbiased mode off by {b:+.4} (standard error {se:.4})");
    let (b, se) = bias_over_seeds(settings(ResamplingMode::Biased), &lights, &reference, &mask, 8);
    eprintln!("every light type, biased: bias {b:+.4} (standard error {se:.4}, 8 runs)");
    assert!(b >= -0.03 - 3.0 * se && b <= 3.0 * se + 0.01, "biased mode off by {b:+.4} (standard error {se:.4})");
}

/// The biased mode's darkening (neighbours that cannot see the light still count) is bounded.
#[test]
fn biased_mode_bias_is_bounded() {
    let lights = lights();
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (reference, mask) = reference(&scene, &camera, &g, &lights);
    let (b, se) = bias_over_seeds(settings(ResamplingMode::Biased), &lights, &reference, &mask, 12);
    eprintln!("biased: bias {b:+.4} (standard error {se:.4}, 12 runs)");
    assert!(b >= -0.03 - 3.0 * se && b <= 3.0 * se + 0.005, "biased mode off by {b:+.4} (standard error {se:.4})");
    // With the candidates' visibility tested (a ray a pixel more).
    let tested = ManyLightsSettings { candidate_visibility: true, ..settings(ResamplingMode::Biased) };
    let (b, se) = bias_over_seeds(tested, &lights, &reference, &mask, 12);
    eprintln!("biased, candidates' visibility tested: bias {b:+.4} (standard error {se:.4}, 12 runs)");
    assert!(b >= -0.03 - 3.0 * se && b <= 3.0 * se + 0.005, "biased mode off by {b:+.4} (standard error {se:.4})");
}

/// One frame of the resampled estimate against lights drawn by power without reuse, at equal
/// shadow rays: the biased mode traces one a pixel (the shading ray), so power sampling gets one
/// light a pixel; with the candidates' visibility tested, two against two. Then the denoised
/// output after 32 frames.
#[test]
fn resampling_beats_power_sampling_at_equal_rays() {
    let lights = lights();
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (reference, mask) = reference(&scene, &camera, &g, &lights);
    let (mut resampled, mut power, mut denoised) = ([0.0; 2], [0.0; 2], 0.0);
    for seed in [1000u64, 2000, 3000, 4000] {
        for (k, tested) in [false, true].into_iter().enumerate() {
            let s = ManyLightsSettings { candidate_visibility: tested, ..settings(ResamplingMode::Biased) };
            let r = run_seeded(s, &lights, 32, seed, !tested, |_| None);
            resampled[k] += rmse(&r.frames[31], &reference, &mask) / 4.0;
            if !tested {
                denoised += rmse(&r.denoised[31], &reference, &mask) / 4.0;
            }
            let p = ManyLightsSettings { initial_candidates: 1 + k as u32, ..settings(ResamplingMode::PowerSampling) };
            power[k] += rmse(&run_seeded(p, &lights, 1, seed, false, |_| None).frames[0], &reference, &mask) / 4.0;
        }
    }
    for k in 0..2 {
        eprintln!(
            "one frame at {} ray(s) a pixel, relative RMSE: resampled {:.3}, power sampling {:.3} ({:.1}x)",
            k + 1,
            resampled[k],
            power[k],
            power[k] / resampled[k]
        );
        assert!(power[k] >= 4.0 * resampled[k], "resampling {:.3} vs power sampling {:.3}", resampled[k], power[k]);
    }
    eprintln!("denoised after 32 frames: {denoised:.3}");
    assert!(denoised <= 0.3, "denoised after 32 frames: relative RMSE {denoised:.3}");
}

/// A light switched off is gone at once: the samples that chose it die the next frame (their
/// target is zero with the light's new intensity), so two frames after half the lights go dark
/// the image is the reference without them, within the noise of one frame.
#[test]
fn lights_switched_off_are_gone_within_two_frames() {
    let lights = lights();
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (on, mask) = reference(&scene, &camera, &g, &lights);
    // The front half (lights 512..): most of the floor's light.
    let dark: Vec<LightInfo> = lights[512..].iter().map(|l| LightInfo { intensity: 0.0, ..*l }).collect();
    let mut off_list = lights.clone();
    off_list[512..].copy_from_slice(&dark);
    let (off, _) = reference(&scene, &camera, &g, &off_list);
    let r = run(settings(ResamplingMode::Biased), &lights, 23, |f| {
        (f == 20).then(|| LightListUpdate::Write { first: 512, lights: dark.clone() })
    });
    // Where the switched-off lights gave most of the light: what is left of them.
    let changed: Vec<bool> = (0..on.len()).map(|i| mask[i] && on[i] - off[i] > 0.5 * on[i] && on[i] > 0.5).collect();
    let left = |frame: &[f32]| {
        let (mut excess, mut removed) = (0.0, 0.0);
        for i in (0..on.len()).filter(|i| changed[*i]) {
            excess += frame[i] - off[i];
            removed += on[i] - off[i];
        }
        excess / removed
    };
    let before = left(&r.frames[19]);
    let after: Vec<f32> = r.frames[20..].iter().map(|f| left(f)).collect();
    eprintln!(
        "{} pixels lit mostly by the lights switched off: their light left {before:.3} before, {after:.3?} 0, 1, 2 frames after",
        changed.iter().filter(|c| **c).count()
    );
    assert!(changed.iter().filter(|c| **c).count() > 200, "the change covers enough pixels");
    assert!(before > 0.8, "before the switch the lights are there: {before:.3}");
    assert!(after[1].abs() <= 0.05 && after[2].abs() <= 0.05, "switched-off light left: {after:.3?}");
}

/// A moving light's highlight leaves no trail: a sample keeps its light's index, and the light is
/// evaluated where it is now. Four frames after a bright light moved 2.5 m, the pixels it lit
/// before hold the reference's light there, within one frame's noise.
#[test]
fn a_moving_light_leaves_no_trail() {
    let mut lights = lights();
    let bright = LightInfo {
        light_type: LightType::Point,
        position: Vec3::new(-1.0, 1.0, 2.0),
        radius: 0.05,
        range: 2.5,
        intensity: 6.0,
        color: [1.0, 0.9, 0.8],
        ..Default::default()
    };
    lights.push(bright);
    let moved = LightInfo { position: Vec3::new(1.5, 1.0, 2.0), ..bright };
    let mut moved_list = lights.clone();
    *moved_list.last_mut().unwrap() = moved;
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (before_ref, mask) = reference(&scene, &camera, &g, &lights);
    let (after_ref, _) = reference(&scene, &camera, &g, &moved_list);
    let index = lights.len() as u32 - 1;
    let r = run(settings(ResamplingMode::Biased), &lights, 25, |f| {
        (f == 20).then(|| LightListUpdate::Write { first: index, lights: vec![moved] })
    });
    // The old highlight: pixels that lost more than half their light.
    let trail: Vec<bool> =
        (0..mask.len()).map(|i| mask[i] && before_ref[i] - after_ref[i] > 0.5 * before_ref[i] && before_ref[i] > 1.0).collect();
    let left = |frame: &[f32]| {
        let (mut excess, mut lost) = (0.0, 0.0);
        for i in (0..mask.len()).filter(|i| trail[*i]) {
            excess += frame[i] - after_ref[i];
            lost += before_ref[i] - after_ref[i];
        }
        excess / lost
    };
    let series: Vec<f32> = r.frames[19..].iter().map(|f| left(f)).collect();
    eprintln!(
        "{} pixels of the old highlight; its light left, from the frame before the move: {series:.3?}",
        trail.iter().filter(|t| **t).count()
    );
    assert!(trail.iter().filter(|t| **t).count() > 50, "the highlight covers enough pixels");
    assert!(series[0] > 0.8, "the highlight is there before the move: {:.3}", series[0]);
    assert!(series[5].abs() <= 0.1, "trail four frames after the move: {:.3}", series[5]);
}

/// The debug output names each pixel's light (a colour per light: the shader's hash, mirrored
/// here) and its reservoir's sample count: every chosen light reaches its pixel, and counts grow
/// with reuse.
#[test]
fn debug_output_shows_each_pixels_light_and_count() {
    let lights = lights();
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (host, ctx) = host_and_context(InitSettings::default());
    let images = GBufferImages::upload(&host, &g).unwrap();
    let usage = vk::ImageUsageFlags::STORAGE;
    let rgba = || host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, usage, vk::ImageLayout::GENERAL).unwrap();
    let (diffuse, specular, debug) = (rgba(), rgba(), rgba());
    let context =
        ctx.create_many_lights_context(&ManyLightsContextInput { max_width: W, max_height: H, max_lights: 1024 }).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let mut texels = Vec::new();
    for f in 0..6 {
        let task = TraceManyLightsTask {
            context,
            common: images.trace_common(&camera),
            lights: if f == 0 { LightListUpdate::Replace(lights.clone()) } else { LightListUpdate::Keep },
            diffuse_output: diffuse.input(vk::ImageLayout::GENERAL),
            specular_output: specular.input(vk::ImageLayout::GENERAL),
            debug_output: debug.input(vk::ImageLayout::GENERAL),
            settings: settings(ResamplingMode::Biased),
            ..Default::default()
        };
        frame.schedule_many_lights(&task).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        texels = bytemuck::cast_slice::<u8, [f32; 4]>(&host.read_image(&debug, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    }
    // `hrt_ml_light_colour`.
    let pcg = |v: u32| {
        let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
        let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
        (word >> 22) ^ word
    };
    let colour = |l: u32| {
        let h = pcg(l.wrapping_mul(0x9e3779b9).wrapping_add(1));
        [(h & 0xff) as f32 / 255.0, ((h >> 8) & 0xff) as f32 / 255.0, ((h >> 16) & 0xff) as f32 / 255.0]
    };
    let colours: Vec<[f32; 3]> = (0..lights.len() as u32).map(colour).collect();
    let (mut named, mut reaching, mut counted) = (0, 0, 0.0f32);
    for (i, t) in texels.iter().enumerate().filter(|(i, _)| g.hit[*i]) {
        if t[..3] == [0.0; 3] {
            continue;
        }
        named += 1;
        let same = |c: &[f32; 3]| c.iter().zip(&t[..3]).all(|(a, b)| (a - b).abs() < 1e-6);
        let reaches = (0..lights.len()).filter(|l| same(&colours[*l])).any(|l| {
            let (e, ..) = many_lights_irradiance(&lights[l], g.position[i], g.normal[i]);
            luminance(e) > 0.0
        });
        reaching += reaches as usize;
        counted = counted.max(t[3]);
    }
    eprintln!("{named} pixels name a light, {reaching} of them one that reaches them; largest count {counted}");
    assert!(named > g.hit.iter().filter(|h| **h).count() * 9 / 10, "most surface pixels chose a light: {named}");
    assert_eq!(reaching, named, "every chosen light reaches its pixel");
    assert!(counted > 20.0, "reuse gathers samples: largest count {counted}");
    ctx.destroy_many_lights_context(context).unwrap();
    for i in [diffuse, specular, debug] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// The ray-tracing pipeline and inline ray queries give the same image, frame after frame (the
/// same random numbers, the same rays), in both modes.
#[test]
fn inline_ray_queries_give_the_pipelines_image() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let inline = ctx.supports_inline_rt();
    drop(ctx);
    drop(host);
    if !inline {
        eprintln!("no ray queries on this device: only the pipeline runs");
        return;
    }
    let lights = lights();
    for mode in [ResamplingMode::Biased, ResamplingMode::Unbiased] {
        let [pipeline, inline] = [false, true].map(|i| run_with(settings(mode), &lights, 3, 7, false, i, |_| None));
        assert_eq!(pipeline.frames, inline.frames, "{mode:?}: the two paths differ");
    }
}

/// Bad input gets a typed error at scheduling or build, and the context stays usable.
#[test]
fn bad_many_lights_input_is_refused() {
    use hybrid_rt::Error;
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let (host, ctx) = host_and_context(InitSettings::default());
    let images = GBufferImages::upload(&host, &g).unwrap();
    let rgba = || {
        host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap()
    };
    let (diffuse, specular) = (rgba(), rgba());
    for (what, input) in [
        ("zero width", ManyLightsContextInput { max_width: 0, max_height: H, max_lights: 16 }),
        ("too tall", ManyLightsContextInput { max_width: W, max_height: 1 << 20, max_lights: 16 }),
        ("no lights", ManyLightsContextInput { max_width: W, max_height: H, max_lights: 0 }),
        ("too many lights", ManyLightsContextInput { max_width: W, max_height: H, max_lights: hybrid_rt::MAX_MANY_LIGHTS + 1 }),
    ] {
        assert!(matches!(ctx.create_many_lights_context(&input), Err(Error::InvalidInput { .. })), "{what}");
    }
    let small =
        ctx.create_many_lights_context(&ManyLightsContextInput { max_width: W / 2, max_height: H, max_lights: 4 }).unwrap();
    let good = TraceManyLightsTask {
        context: small,
        common: images.trace_common(&camera),
        diffuse_output: diffuse.input(vk::ImageLayout::GENERAL),
        specular_output: specular.input(vk::ImageLayout::GENERAL),
        ..Default::default()
    };
    let mut c = ctx.create_task_container();
    let point = LightInfo { light_type: LightType::Point, position: Vec3::Y, ..Default::default() };
    let schedule_errors: Vec<(&str, TraceManyLightsTask)> = vec![
        ("null context", TraceManyLightsTask { context: hybrid_rt::ManyLightsContextHandle::NULL, ..good.clone() }),
        (
            "NaN light",
            TraceManyLightsTask {
                lights: LightListUpdate::Replace(vec![LightInfo { position: Vec3::NAN, ..point }]),
                ..good.clone()
            },
        ),
        (
            "no candidates",
            TraceManyLightsTask { settings: ManyLightsSettings { initial_candidates: 0, ..Default::default() }, ..good.clone() },
        ),
        (
            "NaN radius",
            TraceManyLightsTask {
                settings: ManyLightsSettings { spatial_radius: f32::NAN, ..Default::default() },
                ..good.clone()
            },
        ),
        ("wrong format", TraceManyLightsTask { diffuse_output: images.output.input(vk::ImageLayout::GENERAL), ..good.clone() }),
        ("checkerboard", {
            let mut t = good.clone();
            t.common.half_resolution_mode = hybrid_rt::HalfResolutionMode::Checkerboard;
            t
        }),
    ];
    for (what, task) in schedule_errors {
        let e = c.schedule_many_lights(&task).unwrap_err();
        assert!(
            matches!(e, Error::InvalidInput { .. } | Error::InvalidHandle { .. } | Error::UnsupportedFormat { .. }),
            "{what}: {e}"
        );
    }
    // At build: the viewport beyond the context, a list beyond its capacity, a write past the end.
    let cmd = host.allocate_command_buffer().unwrap();
    for (what, task) in [
        ("viewport beyond the context", good.clone()),
        (
            "five lights in a context of four",
            TraceManyLightsTask {
                common: TraceCommon { viewport: hybrid_rt::Viewport::full(W / 2, H), ..good.common },
                lights: LightListUpdate::Replace(vec![point; 5]),
                ..good.clone()
            },
        ),
        (
            "a write past the list's end",
            TraceManyLightsTask {
                common: TraceCommon { viewport: hybrid_rt::Viewport::full(W / 2, H), ..good.common },
                lights: LightListUpdate::Write { first: 1, lights: vec![point] },
                ..good.clone()
            },
        ),
    ] {
        c.schedule_many_lights(&task).unwrap();
        // SAFETY: a fresh command buffer of the host's device.
        let e = unsafe { ctx.build_gpu_task(&mut c, cmd) }.unwrap_err();
        assert!(matches!(e, Error::InvalidInput { .. }), "{what}: {e}");
        c = ctx.create_task_container();
    }
    ctx.destroy_many_lights_context(small).unwrap();
    assert!(matches!(c.schedule_many_lights(&good), Err(Error::InvalidHandle { .. })), "destroyed context");
    assert!(ctx.destroy_many_lights_context(small).is_err(), "destroyed twice");
    // The context still works.
    let context = ctx.create_many_lights_context(&ManyLightsContextInput { max_width: W, max_height: H, max_lights: 4 }).unwrap();
    let s = SceneOnGpu::register(&host, &ctx, &mut c, &scene).unwrap();
    c.schedule_bvh_build(&Default::default()).unwrap();
    c.schedule_many_lights(&TraceManyLightsTask { context, lights: LightListUpdate::Replace(vec![point]), ..good.clone() })
        .unwrap();
    run_frame(&host, &ctx, &mut c).unwrap();
    host.free_command_buffer(cmd);
    ctx.destroy_many_lights_context(context).unwrap();
    for i in [diffuse, specular] {
        host.destroy_image(i);
    }
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
