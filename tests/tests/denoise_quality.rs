//! Denoiser image quality, second generation (issue 12's CI thresholds), measured against the
//! SDK's own trace averaged over many frames (its converged reference) by
//! `hybrid_rt_testkit::quality`, each figure the mean over its four seeds.
//!
//! - Bias: the denoised GI and glossy reflections keep the mean of the frames they were made
//!   from within 1% per channel. (The first generation was 1.5-6% dark: its anti-firefly clamp
//!   cut every 1-ray sample to its brightest neighbour, and its half-float history rounded
//!   towards zero on drivers that may.)
//! - Light that reaches few of a pixel's rays keeps its mean (within 6%; it was 18% dark).
//! - Moving objects leave no old AO or shadow behind; shadows are never worse than a raw frame;
//!   creases keep their occlusion; GI follows a light switched on. (The penumbra error against
//!   the CPU reference is in denoise.rs.)
mod common;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::quality::*;
use hybrid_rt_testkit::reference;

/// Diffuse GI and glossy reflections (roughness 0.5) in the coloured room, 1 ray per pixel,
/// 32 frames denoised: the image mean per channel within 1% of the same 32 raw frames' mean.
/// Against the 256-frame converged reference the raw 32-frame mean itself is off by up to
/// ~0.4% (sampling noise of 2,000 pixels x 32 rays), so that comparison gets 1.5%.
#[test]
fn gi_and_glossy_reflections_keep_their_mean() {
    let sky = [0.1, 0.2, 0.3];
    for signal in [Signal::Diffuse { sky }, Signal::Specular { sky, roughness: 0.5 }] {
        let b = bias(signal, 32, 256, SEEDS[0]);
        for (c, (same, converged)) in b.iter().enumerate() {
            let what = signal.name();
            eprintln!(
                "{what}, channel {c}: denoised vs its 32 raw frames {:+.2}%, vs the 256-frame reference {:+.2}%",
                same * 100.0,
                converged * 100.0
            );
            assert!(same.abs() <= 0.01, "{what} channel {c}: bias {:.2}% against its own frames", same * 100.0);
            assert!(converged.abs() <= 0.015, "{what} channel {c}: bias {:.2}% against the reference", converged * 100.0);
        }
    }
    assert_no_validation_errors();
}

/// Light that reaches few of a pixel's rays is signal, not fireflies: a small bright box
/// (0.3 m, radiance 20) on a black floor, seen by ~30% of the rays of the floor beside it and
/// by under 1% a metre away. Diffuse GI, 1 ray per pixel, 32 frames denoised, against the same
/// raw frames' mean, over four seeds. Two things darkened it by 18%: the history clamp's box,
/// whose 3x3 fast histories mostly hold no hit (a spread of 0 at 0), and the firefly cut at 4
/// deviations. Measured now: -4.4% (seeds -3.0% to -7.6%; what remains is the cut of light
/// under 1% of the rays and anti-lag's restarts on a sparse signal): the mean within 6%.
#[test]
fn light_seen_by_few_rays_keeps_its_mean() {
    let mut scene = reference::Scene::default();
    let floor = scene.add_mesh(reference::Mesh::quad(8.0));
    scene.add_instance(floor, Affine3A::IDENTITY);
    let box_mesh = scene.add_mesh(reference::Mesh::cuboid(Vec3::splat(0.15)));
    scene.add_instance(box_mesh, Affine3A::from_translation(Vec3::new(0.0, 0.15, 0.0)));
    let colours = [[0.0; 3], [20.0; 3]];
    let camera = reference::Camera::look_at(Vec3::new(0.0, 2.5, 2.0), Vec3::ZERO);
    let runs = SEEDS.map(|seed| bias_in((&scene, &colours, camera), Signal::Diffuse { sky: [0.0; 3] }, 32, 32, seed)[0].0);
    let same = runs.iter().sum::<f64>() / runs.len() as f64;
    let per_seed: Vec<String> = runs.iter().map(|r| format!("{:+.1}%", r * 100.0)).collect();
    eprintln!(
        "a small bright box's light on the floor: denoised vs its 32 raw frames {:+.2}% ({})",
        same * 100.0,
        per_seed.join(" ")
    );
    assert!(same.abs() <= 0.06, "light seen by few rays: bias {:.2}% against its own frames", same * 100.0);
    assert_no_validation_errors();
}

/// When an object moves away, its old contact AO and shadow leave the denoised image, and so
/// does its glossy reflection (roughness 0.3, on the floor): at most 10% of the old occlusion
/// or the old reflection remains 4 frames later (the first generation kept 62% of the
/// occlusion; measured now: AO 0%, the shadow 1%, the reflection 4%).
#[test]
fn a_moving_object_leaves_no_old_occlusion_behind() {
    let sun = LightInfo { direction: Vec3::new(0.4, -1.0, -0.3), angular_extent: 0.1, ..Default::default() };
    // The sphere is unlit: its reflection is black against the sky.
    let glossy = Signal::Specular { sky: [1.0; 3], roughness: 0.3 };
    for signal in [Signal::Ao, Signal::Shadow(sun), glossy] {
        let r = mean_over_seeds(|seed| moving_object_residual(signal, seed));
        let shown: Vec<String> = r.iter().map(|v| format!("{:.0}%", v * 100.0)).collect();
        let name = signal.name();
        eprintln!("{name}: old occlusion kept, frames 1-12 after the move: {}", shown.join(" "));
        assert!(r[3] <= 0.10, "{name}: {:.0}% of the old occlusion kept 4 frames after the move", r[3] * 100.0);
    }
    assert_no_validation_errors();
}

/// An object sliding over a static floor (a 0.4 m cube, 2.6 pixels a frame): its contact AO and
/// its shadow follow it — of the change the last 4 frames brought, at most 10% missing in the
/// denoised image, and no more than 10% overshoot (mean of 4 seeds; measured 0% for AO, 1% for
/// the shadow; AO kept 44% before it restarted pixels near moving objects). The floor's pixels
/// reproject onto themselves and their change is within the noise of 25 1-ray samples: AO
/// finds the moving object instead (`DenoiserSettings::moving_object_reach`).
#[test]
fn a_sliding_object_s_occlusion_follows_it() {
    let sun = LightInfo { direction: Vec3::new(-0.5, -1.0, -0.3), angular_extent: 0.1, ..Default::default() };
    for signal in [Signal::Ao, Signal::Shadow(sun)] {
        let r = mean_over_seeds(|seed| sliding_object_residual(signal, seed, &[4], Default::default()));
        let name = signal.name();
        eprintln!("{name}: {:.0}% of the last 4 frames' change missing, mean |error| {:.3}", r[0] * 100.0, r[1]);
        assert!(r[0].abs() <= 0.10, "{name}: {:.0}% of a sliding object's change missing after 4 frames", r[0] * 100.0);
    }
    assert_no_validation_errors();
}

/// The sample's sun (0.03 rad) and a soft one (0.2 rad): after 32 frames the denoised shadow
/// is no worse than one raw frame in the umbra, in the light and in the penumbra.
#[test]
fn denoised_shadows_are_never_worse_than_a_raw_frame() {
    for extent in [0.03f32, 0.2] {
        let per_seed: Vec<_> = SEEDS.iter().map(|&s| shadow_regions(extent, 0.0, s)).collect();
        for (k, name) in REGIONS.iter().enumerate() {
            let mean = |f: fn(&(f32, f32, usize)) -> f32| per_seed.iter().map(|r| f(&r[k])).sum::<f32>() / SEEDS.len() as f32;
            let (raw, den, n) = (mean(|r| r.0), mean(|r| r.1), per_seed[0][k].2);
            eprintln!("sun {extent} rad, {name} ({n} px): mean |error| raw {raw:.4}, denoised {den:.4}");
            if n > 0 {
                assert!(den <= raw + 0.005, "sun {extent}: the denoised {name} is worse than a raw frame ({den} vs {raw})");
            }
        }
    }
    assert_no_validation_errors();
}

/// The sample's sun while the camera pans a quarter of a pixel a frame: every frame's history
/// is resampled between texels, which softens a hard edge a little more each frame, while a
/// raw frame is exact but for its sub-pixel penumbrae (here 20 of 3,200 pixels). Where the
/// penumbra is under a pixel wide the denoiser keeps at most two frames while the view moves
/// (and blurs along the edge): the edge carries one resampled frame's softening, not a long
/// history's. Bounds (mean of 4 seeds): the summed error within 2x the raw frame's (measured
/// 1.5x; 5.2x when such edges accumulated like soft penumbrae), the umbra beside the edge
/// within 0.05 (0.028; was 0.12), the light within 0.002 (0.0004; was 0.0043).
#[test]
fn hard_shadows_stay_sharp_while_the_camera_pans() {
    let per_seed: Vec<_> = SEEDS.iter().map(|&s| shadow_regions(0.03, 0.013, s)).collect();
    let (mut raw_all, mut den_all) = (0.0f32, 0.0f32);
    let mut den_region = [0.0f32; 3];
    for (k, name) in REGIONS.iter().enumerate() {
        let mean = |f: fn(&(f32, f32, usize)) -> f32| per_seed.iter().map(|r| f(&r[k])).sum::<f32>() / SEEDS.len() as f32;
        let (raw, den, n) = (mean(|r| r.0), mean(|r| r.1), per_seed[0][k].2);
        eprintln!("panning, {name} ({n} px): mean |error| raw {raw:.4}, denoised {den:.4}");
        raw_all += raw * n as f32;
        den_all += den * n as f32;
        den_region[k] = den;
    }
    eprintln!("panning, summed |error|: raw {raw_all:.2}, denoised {den_all:.2}");
    assert!(den_all <= 2.0 * raw_all, "panning: denoised error {den_all} against a raw frame's {raw_all}");
    assert!(den_region[0] <= 0.05, "panning: umbra error {}", den_region[0]);
    assert!(den_region[1] <= 0.002, "panning: light error {}", den_region[1]);
    assert_no_validation_errors();
}

/// Creases (where the room's walls meet its floor and ceiling): the denoised AO after 32
/// frames is not brighter than the converged trace, nor than its own raw frames, by more than
/// 1% there (before the crease rule of denoise_atrous.comp the spatial filter lifted them by
/// 6%).
#[test]
fn creases_keep_their_occlusion() {
    let [bias, vs_raw, pixels] = mean_over_seeds(|s| crease_bias(s).to_vec()).try_into().unwrap();
    eprintln!(
        "creases ({pixels:.0} px, converged AO < 0.75): denoised {:+.2}% against the converged trace, {:+.2}% against its 32 raw frames",
        bias * 100.0,
        vs_raw * 100.0
    );
    assert!(pixels > 100.0, "the room has creases ({pixels} px)");
    assert!(bias <= 0.01, "creases come out {:.2}% brighter than converged", bias * 100.0);
    assert!(vs_raw <= 0.01, "creases come out {:.2}% brighter than their frames", vs_raw * 100.0);
    assert_no_validation_errors();
}

/// How fast denoised GI follows a light switched on (the sky brightens 5x): at most 20% of the
/// old lighting left 4 frames later and 10% after 12 (mean of 4 seeds; measured 15% and 7%).
/// The first generation kept 87% and 66%. The change is small against 1-ray noise in this room,
/// where the sky is seen by few rays: the anti-lag test also compares each 8x8 workgroup's mean.
#[test]
fn gi_follows_a_light_switched_on() {
    let r = mean_over_seeds(gi_switch_residual);
    let shown: Vec<String> = r.iter().map(|v| format!("{:.0}%", v * 100.0)).collect();
    eprintln!("GI: old lighting kept, frames 1-12 after the sky brightened: {}", shown.join(" "));
    assert!(r[3] <= 0.20 && r[11] <= 0.10, "the old lighting lingers: {shown:?}");
    assert_no_validation_errors();
}

/// The scene each signal is measured on: the coloured room (AO, GI, reflections) or the sphere
/// on a plane (a 0.2 rad sun's shadow), with its cache colours and camera.
fn stage_for(signal: Signal, size: u32, seed: u64) -> Stage {
    if let Signal::Shadow(_) = signal {
        let (scene, camera) = hybrid_rt_testkit::reference::sphere_on_plane();
        Stage::new(&scene, None, camera, size, signal.signal_type(), seed)
    } else {
        let (scene, colours, camera) = room();
        Stage::new(&scene, Some(&colours), camera, size, signal.signal_type(), seed)
    }
}

fn every_signal() -> [Signal; 4] {
    let sky = [0.1, 0.2, 0.3];
    let sun = LightInfo { direction: Vec3::new(-0.5, -1.0, -0.3), angular_extent: 0.2, ..Default::default() };
    [Signal::Ao, Signal::Shadow(sun), Signal::Diffuse { sky }, Signal::Specular { sky, roughness: 0.5 }]
}

/// `DenoisingMethod::SpatialOnly` keeps no history: after five frames its image is, bit for
/// bit, what a fresh context makes of the fifth frame alone — and it is closer to the
/// converged trace than that raw frame, for every signal.
#[test]
fn spatial_only_filters_each_frame_alone() {
    for signal in every_signal() {
        let mut st = stage_for(signal, 48, SEEDS[1]);
        st.use_method(DenoisingMethod::SpatialOnly, signal.signal_type());
        for _ in 0..5 {
            signal.frame(&mut st, 1, true);
        }
        let (raw, after_five) = (signal.noisy(&st), signal.denoised(&st));
        let mut fresh = stage_for(signal, 48, SEEDS[1] + 4);
        fresh.use_method(DenoisingMethod::SpatialOnly, signal.signal_type());
        signal.frame(&mut fresh, 1, true);
        assert!(after_five == signal.denoised(&fresh), "{}: SpatialOnly carried something from earlier frames", signal.name());
        let reference = signal.converged(&mut st, 2);
        let (r, d) = (relative_rmse(&raw, &reference, &st.g.hit), relative_rmse(&after_five, &reference, &st.g.hit));
        eprintln!("{}, SpatialOnly, one frame: relative RMSE raw {r:.3}, denoised {d:.3}", signal.name());
        // Shadows: most pixels are exact at one ray, and the penumbra blur is half a penumbra
        // wide (measured 0.88 of the raw error); the radiance and AO filters 0.15-0.45.
        let bound = if matches!(signal, Signal::Shadow(_)) { 0.95 } else { 0.8 };
        assert!(d < bound * r, "{}: SpatialOnly {d} vs raw {r}", signal.name());
        st.finish();
        fresh.finish();
    }
    assert_no_validation_errors();
}

/// Half resolution (checkerboard: each frame traces half the pixels) for every signal: after
/// 32 frames the denoised image is better than one full-resolution raw frame and within twice
/// the full-resolution denoised image's error (it was made from half the rays).
#[test]
fn half_resolution_denoises_every_signal() {
    for signal in every_signal() {
        let error = |half: bool| {
            let mut st = stage_for(signal, 48, SEEDS[2]);
            st.half_resolution = half;
            let c = convergence(&mut st, signal, &[32], 2, None);
            st.finish();
            (c.raw[0], c.denoised[0])
        };
        let ((full_raw, full), (_, half)) = (error(false), error(true));
        eprintln!(
            "{}: relative RMSE after 32 frames, full resolution {full:.3}, half {half:.3} (one raw frame {full_raw:.3})",
            signal.name()
        );
        assert!(half < full_raw && half <= 2.0 * full, "{}: half resolution {half} (full {full}, raw {full_raw})", signal.name());
    }
    assert_no_validation_errors();
}
