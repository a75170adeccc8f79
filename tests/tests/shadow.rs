//! Shadows against the CPU reference: hard edges land on the reference's pixels, and a
//! sphere light's penumbra has the reference's width and values.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{InitSettings, LightInfo, LightType, TraceShadowTask};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const W: u32 = 64;
const H: u32 = 64;

/// A box floating above the ground, seen from above.
fn scene() -> (Scene, Camera) {
    let mut s = Scene::default();
    let ground = s.add_mesh(Mesh::grid(8.0, 4));
    let cube = s.add_mesh(Mesh::cuboid(Vec3::new(0.6, 0.1, 0.6)));
    s.add_instance(ground, Affine3A::IDENTITY);
    s.add_instance(cube, Affine3A::from_translation(Vec3::new(0.0, 1.0, 0.0)));
    (s, Camera::look_at(Vec3::new(0.0, 5.0, 0.01), Vec3::ZERO))
}

/// Renders `frames` shadow frames; returns (mean visibility G, last R) per pixel.
fn gpu_shadow(light: LightInfo, rays: u32, frames: u32) -> (Vec<f32>, Vec<f32>, GBuffer, Scene, Camera) {
    gpu_shadow_mode(light, rays, frames, false, f32::INFINITY)
}

/// `gpu_shadow` with the task's first-hit mode on or off and its ray length capped.
fn gpu_shadow_mode(
    light: LightInfo,
    rays: u32,
    frames: u32,
    first_hit: bool,
    max_ray_length: f32,
) -> (Vec<f32>, Vec<f32>, GBuffer, Scene, Camera) {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let out =
        host.image_cleared(vk::Format::R32G32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let task = TraceShadowTask {
        common: images.trace_common(&camera),
        light,
        output: out.input(vk::ImageLayout::GENERAL),
        rays_per_pixel: rays,
        first_hit,
        max_ray_length,
    };
    let mut vis = vec![0.0f32; (W * H) as usize];
    let mut dist = Vec::new();
    for _ in 0..frames {
        frame.schedule_shadow(&task).unwrap();
        let done = run_frame(&host, &ctx, &mut frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::Shadow));
        let texels: Vec<[f32; 2]> = bytemuck::cast_slice(&host.read_image(&out, vk::ImageLayout::GENERAL).unwrap()).to_vec();
        for (v, t) in vis.iter_mut().zip(&texels) {
            *v += t[1] / frames as f32;
        }
        dist = texels.iter().map(|t| t[0]).collect();
    }
    host.destroy_image(out);
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    (vis, dist, g, scene, camera)
}

#[test]
fn hard_shadow_edge_lands_on_the_reference_pixels() {
    let sun = LightInfo { light_type: LightType::Directional, direction: Vec3::new(1.2, -1.0, 0.6), ..Default::default() };
    let (vis, dist, g, scene, camera) = gpu_shadow(sun, 1, 1);
    let tracer = Tracer::new(&scene);
    let offset = hybrid_rt::RayOffset::default();
    let mut rng = Rng::new(1);
    let reference: Vec<(f32, Option<f32>)> = (0..g.depth.len())
        .map(|i| {
            if g.hit[i] {
                shadow_visibility(&tracer, g.position[i], g.normal[i], camera.eye, &sun, &offset, 1, &mut rng)
            } else {
                (1.0, None)
            }
        })
        .collect();
    let shadowed = |i: usize| reference[i].0 < 0.5;
    let (mut mismatched, mut in_shadow) = (0, 0);
    for y in 0..H as i32 {
        for x in 0..W as i32 {
            let i = (y * W as i32 + x) as usize;
            in_shadow += shadowed(i) as usize;
            if (vis[i] < 0.5) != shadowed(i) {
                mismatched += 1;
                // Only at the edge: some 8-neighbour of the pixel is on the other side.
                let edge = (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy))).any(|(nx, ny)| {
                    nx >= 0 && ny >= 0 && nx < W as i32 && ny < H as i32 && shadowed((ny * W as i32 + nx) as usize) != shadowed(i)
                });
                assert!(edge, "pixel ({x}, {y}) disagrees away from the shadow edge");
            } else if let (true, Some(t)) = (shadowed(i), reference[i].1) {
                assert!((dist[i] - t).abs() < 1e-3 * t.max(1.0), "occluder distance {} vs {t}", dist[i]);
            } else if !shadowed(i) {
                assert!(dist[i] < 0.0, "visible pixels are negative");
            }
        }
    }
    eprintln!("hard shadow: {in_shadow} shadowed pixels, {mismatched} differ (all on the edge)");
    assert!(in_shadow > 100, "enough shadow in view: {in_shadow}");
    assert!(mismatched * 20 < in_shadow);
}

#[test]
fn sphere_light_penumbra_matches_the_reference() {
    let light = LightInfo { light_type: LightType::Point, position: Vec3::new(0.3, 3.0, 0.0), radius: 0.5, ..Default::default() };
    let (rays, frames) = (16, 4);
    let (vis, _, g, scene, camera) = gpu_shadow(light, rays, frames);
    let tracer = Tracer::new(&scene);
    let offset = hybrid_rt::RayOffset::default();
    let strata = 16;
    let mut rng = Rng::new(2);
    let reference: Vec<f32> = (0..g.depth.len())
        .map(|i| {
            if g.hit[i] {
                shadow_visibility(&tracer, g.position[i], g.normal[i], camera.eye, &light, &offset, strata, &mut rng).0
            } else {
                1.0
            }
        })
        .collect();
    // Visibility is a mean of rays x frames Bernoulli samples: sigma <= sqrt(1/4N + 1/4M).
    let sigma = stats::sample_sigma(rays * frames, strata * strata);
    let report = stats::compare_blocks(&vis, &reference, W, H, 4, sigma, 0.02);
    eprintln!(
        "penumbra: worst 4x4 block error {:.4} (tolerance {:.4}), mean |err| {:.4}",
        report.worst_block_error, report.tolerance, report.mean_abs_error
    );
    assert!(report.worst_block_error <= report.tolerance);
    // Penumbra width along the row through the light: pixels with 0.1 < visibility < 0.9.
    let row = |v: &[f32]| {
        (0..W)
            .filter(|x| {
                let s = v[(H / 2 * W + x) as usize];
                s > 0.1 && s < 0.9
            })
            .count() as i32
    };
    let (gw, rw) = (row(&vis), row(&reference));
    eprintln!("penumbra width on the centre row: GPU {gw} px, reference {rw} px");
    assert!(rw >= 4, "the test has a real penumbra");
    assert!((gw - rw).abs() <= 2, "penumbra width GPU {gw} vs reference {rw}");
}

#[test]
fn bad_lights_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, 16, 16);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let good = TraceShadowTask {
        common: images.trace_common(&camera),
        output: images.output.input(vk::ImageLayout::GENERAL),
        ..Default::default()
    };
    frame.schedule_shadow(&good).unwrap();
    for bad in [
        LightInfo { position: Vec3::new(f32::NAN, 0.0, 0.0), ..Default::default() },
        LightInfo { direction: Vec3::ZERO, ..Default::default() },
        LightInfo { light_type: LightType::Point, radius: -1.0, ..Default::default() },
        LightInfo { angular_extent: 4.0, ..Default::default() },
        LightInfo { light_type: LightType::Point, range: -1.0, ..Default::default() },
        LightInfo { intensity: f32::NAN, ..Default::default() },
        LightInfo { intensity: -2.0, ..Default::default() },
        LightInfo { light_type: LightType::Spot, inner_cone: 0.7, outer_cone: 0.6, ..Default::default() },
        LightInfo { light_type: LightType::Spot, inner_cone: 0.1, outer_cone: 1.6, ..Default::default() },
    ] {
        assert!(matches!(
            frame.schedule_shadow(&TraceShadowTask { light: bad, ..good }),
            Err(hybrid_rt::Error::InvalidInput { .. })
        ));
    }
    let mut wrong_format = good;
    wrong_format.output.format = vk::Format::R8_UNORM; // distances need a float format
    assert!(matches!(frame.schedule_shadow(&wrong_format), Err(hybrid_rt::Error::UnsupportedFormat { .. })));
    frame.clear();
    images.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// Multi-light visibility equals the single-light results, light by light (with a spot cone and
/// a point-light range that leave part of the ground unlit, and unequal intensities); the
/// packed visibility is their irradiance-weighted mean; per-light outputs are the single-light
/// images, bit for bit; 20 lights fill `visibility` and `visibility_high`.
#[test]
fn multi_light_visibility_equals_single_light_results() {
    use hybrid_rt::TraceMultiShadowTask;
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let lights = vec![
        LightInfo { light_type: LightType::Directional, direction: Vec3::new(1.2, -1.0, 0.6), ..Default::default() },
        LightInfo {
            light_type: LightType::Point,
            position: Vec3::new(0.3, 3.0, 0.0),
            radius: 0.5,
            range: 4.0,
            intensity: 12.0,
            ..Default::default()
        },
        LightInfo {
            light_type: LightType::Spot,
            position: Vec3::new(-1.5, 2.5, 0.5),
            direction: Vec3::new(0.5, -1.0, 0.0),
            radius: 0.1,
            inner_cone: 0.3,
            outer_cone: 0.5,
            intensity: 6.0,
            ..Default::default()
        },
    ];
    let rays = 8;
    let rg =
        || host.image_cleared(vk::Format::R32G32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
    let singles: Vec<_> = lights.iter().map(|_| rg()).collect();
    let visibility =
        host.image_cleared(vk::Format::R32_UINT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
    let (spot_out, point_out) = (rg(), rg());
    let packed = host
        .image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)
        .unwrap();
    let common = images.trace_common(&camera);
    for (l, out) in lights.iter().zip(&singles) {
        frame
            .schedule_shadow(&TraceShadowTask {
                common,
                light: *l,
                output: out.input(vk::ImageLayout::GENERAL),
                rays_per_pixel: rays,
                ..Default::default()
            })
            .unwrap();
    }
    frame
        .schedule_multi_shadow(&TraceMultiShadowTask {
            common,
            lights: lights.clone(),
            visibility: visibility.input(vk::ImageLayout::GENERAL),
            packed: packed.input(vk::ImageLayout::GENERAL),
            light_outputs: vec![
                hybrid_rt::LightShadowOutput { light: 2, output: spot_out.input(vk::ImageLayout::GENERAL) },
                hybrid_rt::LightShadowOutput { light: 1, output: point_out.input(vk::ImageLayout::GENERAL) },
            ],
            rays_per_pixel: rays,
            first_hit: false,
            ..Default::default()
        })
        .unwrap();
    // 20 lights: the three, cycled, in two visibility images.
    let many: Vec<LightInfo> = (0..20).map(|k| lights[k % 3]).collect();
    let rgba_u = || {
        host.image_cleared(vk::Format::R32G32B32A32_UINT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap()
    };
    let (low, high) = (rgba_u(), rgba_u());
    let packed_many = host
        .image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)
        .unwrap();
    frame
        .schedule_multi_shadow(&TraceMultiShadowTask {
            common,
            lights: many.clone(),
            visibility: low.input(vk::ImageLayout::GENERAL),
            visibility_high: high.input(vk::ImageLayout::GENERAL),
            packed: packed_many.input(vk::ImageLayout::GENERAL),
            rays_per_pixel: rays,
            ..Default::default()
        })
        .unwrap();
    let done = run_frame(&host, &ctx, &mut frame).unwrap();
    assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::MultiShadow));
    let words: Vec<u32> = bytemuck::cast_slice(&host.read_image(&visibility, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    let pk: Vec<[f32; 4]> = bytemuck::cast_slice(&host.read_image(&packed, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    let read_rg = |img: &hybrid_rt_testkit::host::HostImage| -> Vec<[f32; 2]> {
        bytemuck::cast_slice(&host.read_image(img, vk::ImageLayout::GENERAL).unwrap()).to_vec()
    };
    let singles_read: Vec<Vec<[f32; 2]>> = singles.iter().map(read_rg).collect();
    let (mut weighted, mut weights) = (vec![0.0f32; words.len()], vec![0.0f32; words.len()]);
    let mut partial = 0;
    for (k, single) in singles_read.iter().enumerate() {
        for i in 0..words.len() {
            let byte = (words[i] >> (8 * k)) & 255;
            assert_eq!(byte, (single[i][1] * 255.0).round() as u32, "light {k}, pixel {i}");
            if g.hit[i] {
                let w = light_weight(&lights[k], g.position[i], g.normal[i]);
                weighted[i] += w * single[i][1];
                weights[i] += w;
            }
            partial += (single[i][1] > 0.0 && single[i][1] < 1.0) as usize;
        }
    }
    let mut worst = 0.0f32;
    for i in (0..words.len()).filter(|&i| g.hit[i]) {
        let expected = if weights[i] > 0.0 { weighted[i] / weights[i] } else { 1.0 };
        worst = worst.max((pk[i][0] - expected).abs());
    }
    // The GPU's positions come from clip depth (~1e-6 relative): weights agree to ~1e-5.
    eprintln!("irradiance-weighted packed visibility: worst |GPU - expected| {worst:.2e}");
    assert!(worst < 1e-3, "packed visibility is the irradiance-weighted mean ({worst})");
    assert!(partial > 20, "soft lights give partial visibility somewhere ({partial} pixels)");
    // The cone and the range leave surfaces unlit: (0, 0), where the CPU says they are out.
    for (k, what) in [(1usize, "beyond the point light's range"), (2, "outside the spot's cone")] {
        let out: Vec<usize> = (0..words.len())
            .filter(|&i| {
                g.hit[i]
                    && light_weight(&lights[k], g.position[i], g.normal[i]) == 0.0
                    && (g.position[i] - lights[k].position).length() > 0.0
            })
            .collect();
        let reached: Vec<usize> =
            (0..words.len()).filter(|&i| g.hit[i] && light_weight(&lights[k], g.position[i], g.normal[i]) > 1e-3).collect();
        let unlit = out.iter().filter(|&&i| singles_read[k][i] == [0.0, 0.0]).count();
        eprintln!("{what}: {unlit} of {} pixels unlit ({} reached)", out.len(), reached.len());
        assert!(out.len() > 50 && reached.len() > 50, "{what}: the test covers both sides");
        assert!(unlit as f32 >= 0.98 * out.len() as f32, "{what}: {unlit} of {} unlit", out.len());
        assert!(
            reached.iter().all(|&i| singles_read[k][i][1] > 0.0 || singles_read[k][i][0] > 0.0),
            "{what}: reached pixels are traced"
        );
    }
    // Per-light outputs are the single-light task's images (the same rays): the same visible
    // fractions exactly, the same occluder distances to float rounding (two shaders compile the
    // ray set-up differently on NVIDIA: the last bits differ; on lavapipe they are equal).
    for (img, k) in [(&spot_out, 2usize), (&point_out, 1)] {
        let own = read_rg(img);
        for (a, b) in own.iter().zip(&singles_read[k]) {
            assert_eq!(a[1], b[1], "light {k}: the per-light output's visible fraction is the single-light task's");
            assert!((a[0] - b[0]).abs() <= 1e-4 * b[0].abs().max(1.0), "light {k}: occluder distance {} vs {}", a[0], b[0]);
        }
    }
    // 20 lights: light j's byte in the low or high image is light j % 3's.
    let low_words: Vec<[u32; 4]> = bytemuck::cast_slice(&host.read_image(&low, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    let high_words: Vec<[u32; 4]> = bytemuck::cast_slice(&host.read_image(&high, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    for i in 0..words.len() {
        for j in 0..20usize {
            let (w, jj) = if j < 16 { (&low_words[i], j) } else { (&high_words[i], j - 16) };
            let byte = (w[jj / 4] >> (8 * (jj % 4))) & 255;
            assert_eq!(byte, (words[i] >> (8 * (j % 3))) & 255, "light {j} of 20, pixel {i}");
        }
    }
    // Too many lights, or too few channels for them, are refused.
    let mut bad = TraceMultiShadowTask {
        common,
        lights: vec![lights[0]; 33],
        visibility: visibility.input(vk::ImageLayout::GENERAL),
        packed: packed.input(vk::ImageLayout::GENERAL),
        rays_per_pixel: 1,
        first_hit: false,
        ..Default::default()
    };
    assert!(frame.schedule_multi_shadow(&bad).is_err());
    bad.lights.truncate(5);
    assert!(
        matches!(frame.schedule_multi_shadow(&bad), Err(hybrid_rt::Error::UnsupportedFormat { .. })),
        "5 lights need RGBA32_UINT"
    );
    bad.lights = vec![lights[0]; 17];
    bad.visibility = low.input(vk::ImageLayout::GENERAL);
    assert!(frame.schedule_multi_shadow(&bad).is_err(), "17 lights need visibility_high");
    bad.lights.truncate(3);
    bad.visibility = visibility.input(vk::ImageLayout::GENERAL);
    bad.light_outputs = vec![hybrid_rt::LightShadowOutput { light: 3, output: spot_out.input(vk::ImageLayout::GENERAL) }];
    assert!(frame.schedule_multi_shadow(&bad).is_err(), "a per-light output of a light that is not there");
    bad.light_outputs = vec![hybrid_rt::LightShadowOutput { light: 0, output: bad.packed }];
    assert!(frame.schedule_multi_shadow(&bad).is_err(), "a per-light output that is the packed image");
    for o in singles.into_iter().chain([visibility, packed, spot_out, point_out, low, high, packed_many]) {
        host.destroy_image(o);
    }
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// First-hit mode changes traversal, not visibility: the same visible fractions as the closest-
/// hit mode (same rays), and where a pixel is occluded an occluder distance no shorter than the
/// closest one (here the box is the only occluder, so equal within float rounding).
#[test]
fn first_hit_mode_keeps_visibility() {
    let light = LightInfo { light_type: LightType::Point, position: Vec3::new(0.3, 3.0, 0.2), radius: 0.2, ..Default::default() };
    let (vis_closest, dist_closest, ..) = gpu_shadow_mode(light, 8, 1, false, f32::INFINITY);
    let (vis_first, dist_first, ..) = gpu_shadow_mode(light, 8, 1, true, f32::INFINITY);
    assert_eq!(vis_closest, vis_first, "the same rays reach the light");
    let occluded = dist_closest.iter().filter(|&&d| d >= 0.0).count();
    assert!(occluded > 100, "the box shadows the ground ({occluded} pixels)");
    for (c, f) in dist_closest.iter().zip(&dist_first) {
        assert_eq!(*c < 0.0, *f < 0.0);
        if *c >= 0.0 {
            assert!(*f >= *c - 1e-4 && *f <= *c + 0.25, "an occluder's distance: {f} vs closest {c}");
        }
    }
}

/// `max_ray_length` (Kickstart RT's `maxRayLength`): the box floats 0.9 above the ground, so
/// rays capped at 0.5 find no occluder and every pixel is lit, while a cap of 2 leaves the
/// image exactly as without one.
#[test]
fn capped_shadow_rays_ignore_farther_occluders() {
    let sun = LightInfo { light_type: LightType::Directional, direction: Vec3::new(1.2, -1.0, 0.6), ..Default::default() };
    let (free_vis, free_dist, ..) = gpu_shadow(sun, 2, 1);
    let (short_vis, short_dist, ..) = gpu_shadow_mode(sun, 2, 1, false, 0.5);
    let (long_vis, long_dist, ..) = gpu_shadow_mode(sun, 2, 1, false, 2.0);
    let shadowed = free_vis.iter().filter(|v| **v < 0.5).count();
    assert!(shadowed > 100, "the box shadows the ground ({shadowed} px)");
    assert!(short_vis.iter().all(|v| *v == 1.0) && short_dist.iter().all(|d| *d < 0.0), "a 0.5 cap: nothing occludes");
    assert!(long_vis == free_vis && long_dist == free_dist, "a cap beyond every occluder changes nothing");
    // The multi-light task caps its rays alike (its per-light output is the single task's image).
    let multi = |cap| gpu_multi_shadow_output(sun, 2, cap);
    assert!(multi(0.5).iter().all(|t| t[1] == 1.0 && t[0] < 0.0), "a 0.5 cap: nothing occludes in the multi-light task");
    let free = multi(f32::INFINITY);
    assert!(free.iter().filter(|t| t[1] < 0.5).count() > 100, "the box shadows the ground in the multi-light task");
    assert!(multi(2.0) == free, "a cap beyond every occluder changes nothing in the multi-light task");
}

/// One frame of the multi-light task with `light` alone: its per-light output (R distance,
/// G visibility), with the task's rays capped at `max_ray_length`.
fn gpu_multi_shadow_output(light: LightInfo, rays: u32, max_ray_length: f32) -> Vec<[f32; 2]> {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let storage = |format| host.image_cleared(format, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
    let (visibility, packed, out) =
        (storage(vk::Format::R32_UINT), storage(vk::Format::R32G32B32A32_SFLOAT), storage(vk::Format::R32G32_SFLOAT));
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame
        .schedule_multi_shadow(&hybrid_rt::TraceMultiShadowTask {
            common: images.trace_common(&camera),
            lights: vec![light],
            visibility: visibility.input(vk::ImageLayout::GENERAL),
            packed: packed.input(vk::ImageLayout::GENERAL),
            light_outputs: vec![hybrid_rt::LightShadowOutput { light: 0, output: out.input(vk::ImageLayout::GENERAL) }],
            rays_per_pixel: rays,
            max_ray_length,
            ..Default::default()
        })
        .unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let texels: Vec<[f32; 2]> = bytemuck::cast_slice(&host.read_image(&out, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    for img in [visibility, packed, out] {
        host.destroy_image(img);
    }
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    texels
}
