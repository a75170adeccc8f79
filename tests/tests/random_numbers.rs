//! `TraceCommon::random_numbers`: white and blue noise against the default sequences, on AO
//! under a ceiling that covers the ray length everywhere, so every pixel draws from the same
//! distribution and the statistics of the images are the generators' own.
mod common;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{InitSettings, RandomNumbers};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

const SIZE: u32 = 64;
const FRAMES: u64 = 8;

/// One-ray AO of `FRAMES` frames (frame index 0..FRAMES) with `generator`, and the reference
/// AO of the scene's centre.
fn one_ray_frames(generator: RandomNumbers) -> (Vec<Vec<f32>>, f32) {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let grid = scene.add_mesh(Mesh::grid(20.0, 4));
    scene.add_instance(grid, Affine3A::IDENTITY);
    // 0.3 of the ray length above the floor: 91% of the cosine-weighted rays reach it, at
    // distances that the falloff weighs anywhere from 0.3 to 1.
    scene.add_instance(grid, Affine3A::from_translation(Vec3::new(0.0, 0.3, 0.0)));
    let camera = Camera::look_at(Vec3::new(0.0, 0.25, 0.01), Vec3::ZERO);
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, SIZE, SIZE);
    assert!(g.hit.iter().all(|h| *h), "the floor fills the view");

    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut task = images.ao_task(&camera, 1.0, 1);
    task.common.random_numbers = generator;
    let mut frames = Vec::new();
    for k in 0..FRAMES {
        frame.schedule_ambient_occlusion(&task).unwrap();
        frame.set_frame_index(k);
        run_frame(&host, &ctx, &mut frame).unwrap();
        frames.push(images.read_output(&host).unwrap());
    }
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    let params = AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset: hybrid_rt::RayOffset::default() };
    let reference = ao_at(&tracer, Vec3::ZERO, Vec3::Y, camera.eye, &params, 128, &mut Rng::new(7));
    (frames, reference)
}

fn mean(v: &[f32]) -> f64 {
    v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64
}

fn variance(v: &[f32]) -> f64 {
    let m = mean(v);
    v.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / v.len() as f64
}

/// The variance of the 4x4-block means of a frame, over its per-pixel variance: 1/16 for
/// spatially independent pixels, less where a frame's error sits at high frequencies.
fn block_variance_ratio(f: &[f32]) -> f64 {
    let blocks = SIZE as usize / 4;
    let mut means = Vec::with_capacity(blocks * blocks);
    for by in 0..blocks {
        for bx in 0..blocks {
            let s: f32 = (0..16).map(|k| f[(by * 4 + k / 4) * SIZE as usize + bx * 4 + k % 4]).sum();
            means.push(s / 16.0);
        }
    }
    variance(&means) / variance(f)
}

/// The correlation of two frames' pixels: near 0 when frames draw independent numbers.
fn correlation(a: &[f32], b: &[f32]) -> f64 {
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(&x, &y)| (x as f64 - ma) * (y as f64 - mb)).sum::<f64>() / a.len() as f64;
    cov / (variance(a) * variance(b)).sqrt()
}

#[test]
fn white_and_blue_noise_are_unbiased_and_shaped_as_named() {
    let mut ratios = Vec::new();
    for generator in [RandomNumbers::Default, RandomNumbers::WhiteNoise, RandomNumbers::BlueNoise] {
        let (frames, reference) = one_ray_frames(generator);
        let all: Vec<f32> = frames.concat();
        // Unbiased: 8 x 4096 one-ray samples of a value in [0, 1] have a mean within
        // 5 sigma = 5 x 0.5 / sqrt(32768) = 0.014 of the reference's (4 sigma of the
        // reference's 16,384 samples adds 0.016 at worst).
        let m = mean(&all);
        let ratio = frames.iter().map(|f| block_variance_ratio(f)).sum::<f64>() / frames.len() as f64;
        let corr = frames.windows(2).map(|w| correlation(&w[0], &w[1]).abs()).fold(0.0, f64::max);
        eprintln!(
            "{generator:?}: mean AO {m:.4} (reference {reference:.4}), pixel variance {:.4}, 4x4-block variance ratio {ratio:.4} (independent pixels: 0.0625), worst frame-to-frame correlation {corr:.3}",
            variance(&all)
        );
        assert!((m - reference as f64).abs() < 0.03, "{generator:?}: mean {m} vs reference {reference}");
        // Not a constant: one ray gives a pixel either side of the mean.
        assert!(variance(&all) > 0.02, "{generator:?}: the frames barely vary");
        // Frames draw new numbers (a ratio's error over 256 blocks is ~9%; a correlation's
        // over 4096 pixels ~0.016).
        assert!(corr < 0.1, "{generator:?}: consecutive frames correlate ({corr})");
        ratios.push(ratio);
    }
    let (default, white, blue) = (ratios[0], ratios[1], ratios[2]);
    // White noise: independent pixels (1/16 within 25%).
    assert!((white - 0.0625).abs() < 0.016, "white noise's block ratio {white}");
    // The default's AO rotations are independent per pixel too.
    assert!((default - 0.0625).abs() < 0.016, "the default's block ratio {default}");
    // Blue noise: a frame's error at high frequencies; its 4x4 means come out about a fifth as
    // noisy as white noise's.
    assert!(blue < 0.35 * white, "blue noise's block ratio {blue} vs white noise's {white}");
}
