//! Diffuse GI against the reference: inside a box whose walls carry known cache colours, the
//! traced mean incoming radiance matches the reference's cosine-weighted integral.
mod common;
use ash::vk;
use common::*;
use glam::Vec3;
use hybrid_rt::{InitSettings, TraceDiffuseTask};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const W: u32 = 48;
const H: u32 = 48;
const SKY: [f32; 3] = [0.1, 0.2, 0.3];

fn room() -> (Scene, Vec<[f32; 3]>, Camera) {
    coloured_room(true)
}

/// Normalized Disney diffuse relative to Lambert (Frostbite / Burley), for the reference.
fn disney_factor(ndotl: f32, ndotv: f32, ldoth: f32, roughness: f32) -> f32 {
    let energy_bias = 0.5 * roughness;
    let energy_factor = 1.0 + (1.0 / 1.51 - 1.0) * roughness;
    let fd90 = energy_bias + 2.0 * ldoth * ldoth * roughness;
    let light = 1.0 + (fd90 - 1.0) * (1.0 - ndotl).powi(5);
    let view = 1.0 + (fd90 - 1.0) * (1.0 - ndotv).powi(5);
    light * view * energy_factor
}

#[test]
fn diffuse_gi_in_a_coloured_box_matches_the_reference() {
    check_room(hybrid_rt::DiffuseBrdfType::Lambertian, 0.0, false);
}

#[test]
fn normalized_disney_diffuse_matches_the_reference() {
    check_room(hybrid_rt::DiffuseBrdfType::NormalizedDisney, 0.8, false);
}

/// With the lit image as direct-lighting input (here each pixel the complement of its wall's
/// cache colour, so the source shows), a diffuse ray that lands on a surface the screen shows
/// takes the lit pixel, any other the cache: the reference does the same per sample.
#[test]
fn the_lit_image_lights_diffuse_hits_that_land_on_screen() {
    check_room(hybrid_rt::DiffuseBrdfType::Lambertian, 0.0, true);
}

/// The lit image of the room's view: each pixel the complement of its surface's cache colour.
fn complement_image(g: &GBuffer, colours: &[[f32; 3]]) -> Vec<[f32; 4]> {
    (0..g.depth.len())
        .map(|i| {
            let c = colours[g.instance[i] as usize];
            if g.hit[i] {
                [1.0 - c[0], 1.0 - c[1], 1.0 - c[2], 1.0]
            } else {
                [0.0; 4]
            }
        })
        .collect()
}

/// The screen pixel showing world point `p` (the same surface within 1% of its distance, as
/// the SDK tests), if any.
fn on_screen(g: &GBuffer, camera: &Camera, p: Vec3) -> Option<usize> {
    let c = camera.view_to_clip(W as f32 / H as f32) * camera.world_to_view() * p.extend(1.0);
    let ndc = c.truncate() / c.w;
    if c.w <= 0.0 || ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
        return None;
    }
    let px = ((ndc.x * 0.5 + 0.5) * W as f32).min(W as f32 - 1.0) as u32;
    let py = ((ndc.y * 0.5 + 0.5) * H as f32).min(H as f32 - 1.0) as u32;
    let j = (py * W + px) as usize;
    (g.hit[j] && g.position[j].distance(p) <= 0.01 * p.distance(camera.eye) + 1e-3).then_some(j)
}

fn check_room(brdf: hybrid_rt::DiffuseBrdfType, roughness: f32, lit_input: bool) {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, colours, camera) = room();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let lit_texels = complement_image(&g, &colours);
    let lit = host
        .image_with_data(
            vk::Format::R32G32B32A32_SFLOAT,
            W,
            H,
            vk::ImageUsageFlags::SAMPLED,
            bytemuck::cast_slice(&lit_texels),
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        )
        .unwrap();
    let out = host
        .image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)
        .unwrap();

    // Each instance's cache holds its wall's colour (its initial colour).
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register_coloured(&host, &ctx, &mut frame, &scene, Default::default(), &colours).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();

    let (rays, frames) = (16u32, 4u32);
    let mut common = images.trace_common(&camera);
    common.roughness.global_roughness = roughness;
    if lit_input {
        common.direct_lighting = lit.input(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
    }
    let task = TraceDiffuseTask {
        common,
        output: out.input(vk::ImageLayout::GENERAL),
        rays_per_pixel: rays,
        ray_length: 100.0,
        miss_radiance: SKY,
        brdf,
        ..Default::default()
    };
    let disney = brdf == hybrid_rt::DiffuseBrdfType::NormalizedDisney;
    let mut gpu = vec![[0.0f32; 4]; (W * H) as usize];
    for _ in 0..frames {
        frame.schedule_diffuse(&task).unwrap();
        let done = run_frame(&host, &ctx, &mut frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::Diffuse));
        let texels: Vec<[f32; 4]> = bytemuck::cast_slice(&host.read_image(&out, vk::ImageLayout::GENERAL).unwrap()).to_vec();
        for (a, t) in gpu.iter_mut().zip(&texels) {
            for c in 0..4 {
                a[c] += t[c] / frames as f32;
            }
        }
    }

    // Reference: stratified cosine-weighted samples; a hit takes its instance's colour.
    let strata = 16;
    let (from_screen, from_cache) = (std::cell::Cell::new(0u64), std::cell::Cell::new(0u64));
    let radiance = |hit: Option<(Vec3, u32)>| match hit {
        None => SKY,
        Some((p, instance)) => match on_screen(&g, &camera, p).filter(|_| lit_input) {
            Some(j) => {
                from_screen.set(from_screen.get() + 1);
                [lit_texels[j][0], lit_texels[j][1], lit_texels[j][2]]
            }
            None => {
                from_cache.set(from_cache.get() + 1);
                colours[instance as usize]
            }
        },
    };
    let reference = diffuse_reference_with(&tracer, &g, camera.eye, radiance, 100.0, strata, |n, dir, v| {
        if disney {
            disney_factor(n.dot(dir).max(0.0), n.dot(v).clamp(1e-4, 1.0), dir.dot((dir + v).normalize()), roughness)
        } else {
            1.0
        }
    });
    // Each channel of a sample lies in [0, 0.9 x max weight]: variance <= (that)^2 / 4 per
    // sample. Disney's weight at roughness 0.8 is at most (1 + 1)^2 x 0.69 < 2.8.
    if lit_input {
        eprintln!("reference samples: {} lit from the screen, {} from the cache", from_screen.get(), from_cache.get());
        assert!(from_screen.get() > 10 * from_cache.get().max(1) / 100, "the test exercises on-screen hits");
    }
    let max_weight = if disney { 2.8 } else { 1.0 };
    let sigma = 0.9 * max_weight * stats::sample_sigma(rays * frames, strata * strata);
    for k in 0..3 {
        let gpu_k: Vec<f32> = gpu.iter().map(|v| v[k]).collect();
        let ref_k: Vec<f32> = reference.iter().map(|v| v[k]).collect();
        let report = stats::compare_blocks(&gpu_k, &ref_k, W, H, 8, sigma, 0.01);
        eprintln!(
            "{brdf:?} channel {k}: worst 8x8 block error {:.4} (tolerance {:.4}), mean |err| {:.4}",
            report.worst_block_error, report.tolerance, report.mean_abs_error
        );
        assert!(report.worst_block_error <= report.tolerance, "channel {k}");
        if lit_input {
            // And the test tells: the cache alone (the lit image ignored) is far off.
            let cache_only = diffuse_reference(&tracer, &g, camera.eye, &colours, SKY, 100.0, 8, |_, _, _| 1.0);
            let cache_k: Vec<f32> = cache_only.iter().map(|v| v[k]).collect();
            let ignored = stats::compare_blocks(&gpu_k, &cache_k, W, H, 8, sigma, 0.01);
            assert!(ignored.worst_block_error > 2.0 * ignored.tolerance, "channel {k}: the lit image made no difference");
        }
    }
    // Colour bleeding is visible: the floor near the red wall is redder than near the green.
    let floor = |x_sign: f32| -> f32 {
        let px: Vec<usize> =
            (0..g.depth.len()).filter(|&i| g.hit[i] && g.normal[i].y > 0.9 && g.position[i].x * x_sign > 1.2).collect();
        px.iter().map(|&i| gpu[i][0] - gpu[i][1]).sum::<f32>() / px.len().max(1) as f32
    };
    assert!(floor(-1.0) > 0.05 && floor(1.0) < -0.05, "red near red, green near green: {} {}", floor(-1.0), floor(1.0));
    // A = mean hit distance: inside a 4 m box, between the offset and the box's diagonal.
    assert!(gpu.iter().zip(&g.hit).filter(|(_, h)| **h).all(|(v, _)| v[3] > 0.0 && v[3] < 100.0));

    host.destroy_image(out);
    host.destroy_image(lit);
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
