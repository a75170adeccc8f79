//! Cache relighting (`RelightCacheTask`): surfaces no camera injected take their direct light
//! from the engine's lights, against the CPU reference; injected light wins; the per-build
//! budget walks the caches round-robin; bad input is refused.
mod common;
use ash::vk;
use common::relit_scene::*;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{
    DepthInput, DepthType, DirectLightingInjectionTask, InitSettings, InstanceInput, InstanceOperation, InstanceTask, LightInfo,
    LightType, RelightCacheTask, Viewport,
};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

/// Pixels whose reference light is the same within a tile around them (shadow edges move by
/// up to a tile in the cache), with their reference radiance and whether a light is occluded.
fn comparable(tracer: &Tracer, g: &GBuffer) -> Vec<(usize, Vec3, bool)> {
    (0..g.depth.len())
        .filter(|&i| g.hit[i])
        .filter_map(|i| {
            let (p, n) = (g.position[i], g.normal[i]);
            let albedo = ALBEDO[g.instance[i] as usize];
            let (here, occluded) = reference_light(tracer, p, n, albedo);
            let (t, b) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
            let steady = [t, -t, b, -b].iter().all(|d| {
                let there = reference_radiance(tracer, p + *d * 1.5 * TILE, n, albedo);
                (there - here).length() <= 0.1 * here.length() + 0.02
            });
            steady.then_some((i, here, occluded))
        })
        .collect()
}

/// Nothing was injected: after one relight of every sample (hard lights, so no noise), the
/// cache seen by the camera is the reference's direct light — the sun's shadow, the point
/// light's colour and falloff, each instance's albedo — within the cache's resolution.
#[test]
fn relit_caches_match_the_reference_direct_light() {
    let mut f = Fixture::new();
    let g = GBuffer::render(&Tracer::new(&f.scene), &camera(), W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let before = f.cache_view(&images);
    assert!(
        (0..before.len()).filter(|&i| g.hit[i]).all(|i| (Vec3::from_slice(&before[i][..3]) - Vec3::from(UNLIT)).length() < 1e-3),
        "before relighting every cache holds its initial colour"
    );
    f.relight(hybrid_rt::MAX_RELIGHT_SAMPLES);
    let view = f.cache_view(&images);
    let tracer = Tracer::new(&f.scene);
    let pixels = comparable(&tracer, &g);
    let hits = g.hit.iter().filter(|h| **h).count();
    assert!(pixels.len() > hits * 3 / 4, "{} of {hits} pixels away from shadow edges", pixels.len());
    let (mut err2, mut ref2, mut shadowed, mut bias) = (0.0f64, 0.0f64, 0, Vec3::ZERO);
    for &(i, expected, occluded) in &pixels {
        let got = Vec3::from_slice(&view[i][..3]);
        err2 += (got - expected).length_squared() as f64;
        ref2 += expected.length_squared() as f64;
        bias += got - expected;
        shadowed += occluded as usize;
    }
    let rel_rmse = (err2 / ref2).sqrt();
    let bias = bias / pixels.len() as f32 / (ref2 / pixels.len() as f64).sqrt() as f32;
    eprintln!(
        "relit cache vs reference: {} pixels ({shadowed} in shadow), relative RMSE {rel_rmse:.4}, bias {bias}",
        pixels.len()
    );
    assert!(shadowed > 50, "the box's shadow is in view ({shadowed} pixels)");
    // Tiles of 5 cm: the point light's irradiance varies by a few percent across one.
    assert!(rel_rmse < 0.05, "relative RMSE {rel_rmse}");
    assert!(bias.abs().max_element() < 0.02, "bias {bias}");
    f.finish(images, Vec::new());
}

/// A sample a camera injected keeps the camera's light; a relit sample that a camera then
/// sees takes the camera's light at once (its relit history does not count).
#[test]
fn injected_light_wins_over_relighting() {
    let mut f = Fixture::new();
    let g = GBuffer::render(&Tracer::new(&f.scene), &camera(), W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let injected = [0.25f32, 0.5, 0.125];
    let texels: Vec<[f32; 4]> =
        (0..g.depth.len()).map(|i| if g.hit[i] { [injected[0], injected[1], injected[2], 1.0] } else { [0.0; 4] }).collect();
    let lit = f
        .host
        .image_with_data(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::SAMPLED, bytemuck::cast_slice(&texels), READ)
        .unwrap();
    let inject = DirectLightingInjectionTask {
        depth: DepthInput { image: images.depth.input(READ), depth_type: DepthType::ClipSpace },
        lit: lit.input(READ),
        viewport: Viewport::full(W, H),
        camera: camera().sdk_camera(W, H),
        average_window: 8.0,
        ..Default::default()
    };
    // Relit first, then seen by the camera: the camera's colour replaces the relit one.
    f.relight(hybrid_rt::MAX_RELIGHT_SAMPLES);
    f.frame.schedule_direct_lighting_injection(&inject).unwrap();
    run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    // Relit again: the injected samples are left alone.
    f.relight(hybrid_rt::MAX_RELIGHT_SAMPLES);
    let view = f.cache_view(&images);
    let hits: Vec<usize> = (0..view.len()).filter(|&i| g.hit[i]).collect();
    let kept = hits.iter().filter(|&&i| (Vec3::from_slice(&view[i][..3]) - Vec3::from(injected)).length() < 1e-3).count();
    eprintln!("{kept} of {} pixels show the injected colour", hits.len());
    // Pixels whose nearest sample no pixel of the view injected (a tile's sample can sit past
    // a silhouette) may show relit light: a few percent.
    assert!(kept as f32 > 0.95 * hits.len() as f32, "{kept} of {}", hits.len());
    f.finish(images, vec![lit]);
}

/// A budget of a quarter of the samples relights part of them per build, round-robin, and
/// every sample within five builds. (The budget counts the launch: each triangle takes the
/// samples of the layout's largest, so layouts of uneven triangles light fewer per build.)
#[test]
fn the_budget_spreads_relighting_over_builds() {
    let mut f = Fixture::new();
    let g = GBuffer::render(&Tracer::new(&f.scene), &camera(), W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let samples: u64 = f.gpu_scene.instances.iter().map(|&h| f.ctx.instance_cache_bytes(h).unwrap() / 32).sum();
    let budget = (samples / 4).max(1) as u32;
    let hits: Vec<usize> = (0..g.depth.len()).filter(|&i| g.hit[i]).collect();
    let mut coverage = Vec::new();
    for _ in 0..5 {
        f.relight(budget);
        let view = f.cache_view(&images);
        let relit = hits.iter().filter(|&&i| (Vec3::from_slice(&view[i][..3]) - Vec3::from(UNLIT)).length() > 1e-3).count();
        coverage.push(relit as f32 / hits.len() as f32);
    }
    eprintln!("{samples} samples, budget {budget}: coverage after each build {coverage:?}");
    assert!(coverage[0] > 0.05 && coverage[0] < 0.6, "one build of a quarter budget: {coverage:?}");
    assert!(coverage.windows(2).all(|w| w[1] >= w[0]), "{coverage:?}");
    assert!(coverage[4] > 0.999, "every sample after five quarter-budget builds: {coverage:?}");
    f.finish(images, Vec::new());
}

/// The case: a surface no camera injected, seen only in a mirror. The ground is a
/// mirror (roughness 0) seen from low down; its reflections show the box's sides and
/// underside, which the camera never sees, and read the relit cache: within the cache's
/// resolution of the reference's direct light at the reflected hit.
#[test]
fn a_mirror_shows_relit_surfaces_no_camera_saw() {
    let mut f = Fixture::new();
    let low = Camera::look_at(Vec3::new(-0.6, 0.35, 2.6), Vec3::new(0.2, 0.5, -0.1));
    let tracer = Tracer::new(&f.scene);
    let g = GBuffer::render(&tracer, &low, W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    f.relight(hybrid_rt::MAX_RELIGHT_SAMPLES);
    let mut common = images.trace_common(&low);
    common.roughness = hybrid_rt::RoughnessInput { global_roughness: 0.0, ..Default::default() };
    let gpu = f.trace_specular(hybrid_rt::TraceSpecularTask { common, ray_length: 100.0, ..Default::default() });
    let offset = hybrid_rt::RayOffset::default();
    let (mut err2, mut ref2, mut n, mut unseen) = (0.0f64, 0.0f64, 0, 0);
    for i in (0..g.depth.len()).filter(|&i| g.hit[i] && g.instance[i] == 0) {
        let (p, normal) = (g.position[i], g.normal[i]);
        let v = (low.eye - p).normalize();
        let dir = (-v) - 2.0 * (-v).dot(normal) * normal;
        let origin = offset_origin(p, normal, low.eye, &offset);
        let Some(hit) = tracer.closest_hit(origin, dir, 0.0, 100.0) else { continue };
        let q = origin + dir * hit.t;
        let albedo = ALBEDO[hit.instance as usize];
        let want = reference_radiance(&tracer, q, hit.normal, albedo);
        let (t, b) = (hit.normal.any_orthonormal_vector(), hit.normal.cross(hit.normal.any_orthonormal_vector()));
        let steady = [t, -t, b, -b].iter().all(|d| {
            (reference_radiance(&tracer, q + *d * 1.5 * TILE, hit.normal, albedo) - want).length() <= 0.1 * want.length() + 0.02
        });
        if !steady {
            continue;
        }
        // Seen only in the mirror: a face of the box that looks away from the camera or down.
        unseen += (hit.instance == 1 && (hit.normal.dot(low.eye - q) < 0.0 || hit.normal.y < -0.5)) as usize;
        let got = Vec3::from_slice(&gpu[i][..3]);
        err2 += (got - want).length_squared() as f64;
        ref2 += want.length_squared() as f64;
        n += 1;
    }
    let rel_rmse = (err2 / ref2.max(1e-12)).sqrt();
    eprintln!("mirror: {n} reflected pixels ({unseen} show faces the camera cannot see), relative RMSE {rel_rmse:.4}");
    assert!(n > 150 && unseen > 30, "{n} pixels, {unseen} of them unseen faces");
    assert!(rel_rmse < 0.05, "relative RMSE {rel_rmse}");
    f.finish(images, Vec::new());
}

/// A closed box lit by one point light inside: with `bounce`, the relit caches gather light
/// from each other, one bounce more per build, and converge to the multi-bounce solution —
/// the CPU reference's random walk (12 bounces; albedo^12 < 1e-3 of the light is left out).
/// Without bounces the box is 40-70% darker than the reference (more in the channels of
/// higher albedo).
#[test]
fn bounces_converge_to_the_reference_in_a_closed_box() {
    const BOX_ALBEDO: [f32; 3] = [0.7, 0.55, 0.4];
    let mut inside = Mesh::cuboid(Vec3::new(1.2, 1.0, 1.5));
    for t in inside.indices.chunks_mut(3) {
        t.swap(1, 2); // the faces look inwards
    }
    let mut s = Scene::default();
    let m = s.add_mesh(inside);
    s.add_instance(m, Affine3A::IDENTITY);
    let light =
        LightInfo { light_type: LightType::Point, position: Vec3::new(0.5, 0.6, 0.7), intensity: 1.5, ..Default::default() };
    let mut f = Fixture::with(s, &[BOX_ALBEDO]);
    let eye = Camera::look_at(Vec3::new(-1.0, -0.7, 1.3), Vec3::new(0.8, 0.4, -1.4));
    let tracer = Tracer::new(&f.scene);
    let g = GBuffer::render(&tracer, &eye, W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let mut task = RelightCacheTask {
        lights: vec![light],
        max_samples: hybrid_rt::MAX_RELIGHT_SAMPLES,
        history_frames: 16,
        bounce: false,
        ..Default::default()
    };
    f.relight_with(&task);
    let direct = f.cache_view_from(&images, &eye);
    task.bounce = true;
    // Each build moves a sample 1/16 of the way to albedo x (direct + what it gathers):
    // the error falls by (1 - (1 - albedo) / 16) per build, to 1% of the direct-only start
    // after 256 builds at the red channel's albedo of 0.7.
    for _ in 0..256 {
        f.relight_with(&task);
    }
    let bounced = f.cache_view_from(&images, &eye);

    // The reference: L(p) = albedo x (E_direct(p) + cosine mean of L), by random walks.
    let albedo = Vec3::from(BOX_ALBEDO);
    let direct_at = |p: Vec3, n: Vec3| -> f32 {
        let w = light_weight(&light, p, n);
        let to = light.position - p;
        if w > 0.0 && tracer.closest_hit(p + n * 1e-3, to.normalize(), 0.0, to.length() * 0.999).is_none() {
            w
        } else {
            0.0
        }
    };
    let mut rng = Rng::new(11);
    let paths = 96;
    let mut rows = Vec::new();
    for i in (0..g.depth.len()).filter(|&i| g.hit[i]) {
        let mut sum = Vec3::ZERO;
        for _ in 0..paths {
            let (mut p, mut n, mut weight) = (g.position[i], g.normal[i], albedo);
            for _ in 0..12 {
                sum += weight * direct_at(p, n);
                let (t, b) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
                let (u, v) = (rng.next_f32(), rng.next_f32());
                let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
                let dir = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u).max(0.0).sqrt()).normalize();
                let Some(hit) = tracer.closest_hit(p + n * 1e-3, dir, 0.0, 100.0) else { break };
                p = p + n * 1e-3 + dir * hit.t;
                n = if hit.normal.dot(dir) < 0.0 { hit.normal } else { -hit.normal };
                weight *= albedo;
            }
        }
        let want = sum / paths as f32;
        rows.push((i, want, Vec3::from_slice(&bounced[i][..3]), Vec3::from_slice(&direct[i][..3])));
    }
    // Means over the view (per channel) and the relative RMSE per pixel.
    let n = rows.len() as f32;
    let mean = |k: usize| rows.iter().fold(Vec3::ZERO, |a, r| a + [r.1, r.2, r.3][k]) / n;
    let (want, got, only_direct) = (mean(0), mean(1), mean(2));
    let rel = |a: Vec3, b: Vec3| (a - b) / b;
    let (err2, ref2) = rows
        .iter()
        .fold((0.0f64, 0.0f64), |(e, r), row| (e + (row.2 - row.1).length_squared() as f64, r + row.1.length_squared() as f64));
    let rel_rmse = (err2 / ref2).sqrt();
    eprintln!(
        "closed box, {} pixels: mean reference {want}, bounced {got} ({}), direct only {only_direct} ({}); per-pixel relative RMSE {rel_rmse:.4}",
        rows.len(),
        rel(got, want),
        rel(only_direct, want)
    );
    // The bounce is most of the light; the converged caches find it within 4% in the mean
    // over the view (the reference's 96 paths and the caches' running means are each under
    // 1% over thousands of pixels; tiles average the light's falloff), and within 12% per
    // pixel: a sample's running mean over 16 builds of one gather ray keeps about 8% noise.
    assert!(rel(only_direct, want).max_element() < -0.25, "without bounces the box is darker: {only_direct} vs {want}");
    assert!(rel(got, want).abs().max_element() < 0.04, "mean {got} vs the reference {want}");
    assert!(rel_rmse < 0.12, "per-pixel relative RMSE {rel_rmse}");
    f.finish(images, Vec::new());
}

/// The ground's albedo from all three sources: its instance's tint x per-vertex colours
/// (linear in x and z, so barycentric interpolation is exact; given as RGB32F, kept as RGBA8)
/// x a 512² texture whose quadrants each hold a one-texel checker of two colours (the SDK's
/// 256² copy box-filters each 2 x 2 to their mean). After one relight the cache the camera
/// sees is the reference's direct light times that albedo, within the cache's resolution
/// (pixels within 1.5 tiles of a quadrant's edge or a light edge are left out) and 8-bit
/// storage (< 1%).
#[test]
fn vertex_colours_and_textures_give_the_relit_albedo() {
    const TINT: [f32; 3] = [0.9, 0.8, 0.9];
    let mut f = Fixture::with(scene(), &[TINT, ALBEDO[1]]);
    let ground = Mesh::grid(4.0, 8);
    let colour = |p: Vec3| Vec3::new(0.3 + 0.1 * p.x, 0.5, 0.4 - 0.05 * p.z);
    // Quadrant q (u >= 0.5: +1, v >= 0.5: +2) alternates these two colours texel by texel.
    let checker: [[Vec3; 2]; 4] = [
        [Vec3::new(1.0, 0.2, 0.2), Vec3::new(0.6, 0.6, 0.2)],
        [Vec3::new(0.2, 1.0, 0.2), Vec3::new(0.2, 0.6, 0.6)],
        [Vec3::new(0.2, 0.2, 1.0), Vec3::new(1.0, 1.0, 1.0)],
        [Vec3::new(0.6, 0.4, 0.2), Vec3::new(0.2, 0.4, 0.6)],
    ];
    let uv_of = |p: Vec3| (p.x / 4.0 + 0.5, p.z / 4.0 + 0.5);
    let quadrant = |u: f32, v: f32| (u >= 0.5) as usize + 2 * (v >= 0.5) as usize;
    let mut texels = vec![0u8; 512 * 512 * 4];
    for y in 0..512 {
        for x in 0..512 {
            let c = checker[quadrant(x as f32 / 512.0, y as f32 / 512.0)][(x + y) % 2];
            let t = &mut texels[(y * 512 + x) * 4..][..4];
            t.copy_from_slice(&[(c.x * 255.0).round() as u8, (c.y * 255.0).round() as u8, (c.z * 255.0).round() as u8, 255]);
        }
    }
    let texture =
        f.host.image_with_data(vk::Format::R8G8B8A8_UNORM, 512, 512, vk::ImageUsageFlags::SAMPLED, &texels, READ).unwrap();
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    let colours: Vec<[f32; 3]> = ground.positions.iter().map(|p| colour(*p).to_array()).collect();
    let uvs: Vec<[f32; 2]> = ground.positions.iter().map(|p| [uv_of(*p).0, uv_of(*p).1]).collect();
    let cb = f.host.buffer_with_data(bytemuck::cast_slice(&colours), usage).unwrap();
    let ub = f.host.buffer_with_data(bytemuck::cast_slice(&uvs), usage).unwrap();
    let (vb, ib) = &f.gpu_scene.buffers[0];
    let n = ground.positions.len() as u32;
    let input = hybrid_rt::GeometryInput {
        vertices: hybrid_rt::VertexBufferInput { buffer: vb.buffer, count: n, ..Default::default() },
        indices: hybrid_rt::IndexBufferInput { buffer: ib.buffer, count: ground.indices.len() as u32, ..Default::default() },
        colors: Some(hybrid_rt::VertexBufferInput {
            buffer: cb.buffer,
            count: n,
            stride: 12,
            format: vk::Format::R32G32B32_SFLOAT,
            ..Default::default()
        }),
        uvs: Some(hybrid_rt::VertexBufferInput {
            buffer: ub.buffer,
            count: n,
            stride: 8,
            format: vk::Format::R32G32_SFLOAT,
            ..Default::default()
        }),
        albedo_texture: Some(hybrid_rt::AlbedoTextureInput { texture: texture.input(READ) }),
        surfels: hybrid_rt::SurfelSettings { tile_unit_length: TILE, ..Default::default() },
        ..Default::default()
    };
    let task = hybrid_rt::GeometryTask { handle: f.gpu_scene.geometries[0], operation: hybrid_rt::TaskOperation::Update, input };
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { f.frame.schedule_geometry(&task) }.unwrap();
    for _ in 0..2 {
        f.frame.schedule_bvh_build(&Default::default()).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
    }
    f.relight(hybrid_rt::MAX_RELIGHT_SAMPLES);
    let tracer = Tracer::new(&f.scene);
    let g = GBuffer::render(&tracer, &camera(), W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let view = f.cache_view(&images);
    let albedo_at = |p: Vec3| {
        let (u, v) = uv_of(p);
        let q = checker[quadrant(u, v)];
        Vec3::from(TINT) * colour(p) * (q[0] + q[1]) * 0.5
    };
    let (mut err2, mut ref2, mut n_px) = (0.0f64, 0.0f64, 0);
    for &(i, _, _) in &comparable(&tracer, &g) {
        let p = g.position[i];
        if g.instance[i] != 0 || p.x.abs() < 1.5 * TILE || p.z.abs() < 1.5 * TILE {
            continue;
        }
        let want = reference_radiance(&tracer, p, g.normal[i], albedo_at(p).to_array());
        let got = Vec3::from_slice(&view[i][..3]);
        err2 += (got - want).length_squared() as f64;
        ref2 += want.length_squared() as f64;
        n_px += 1;
    }
    let rel_rmse = (err2 / ref2.max(1e-12)).sqrt();
    eprintln!("relit albedo (tint x vertex colours x filtered texture): {n_px} ground pixels, relative RMSE {rel_rmse:.4}");
    assert!(n_px > 500, "{n_px} pixels");
    assert!(rel_rmse < 0.05, "relative RMSE {rel_rmse}");
    f.host.destroy_buffer(cb);
    f.host.destroy_buffer(ub);
    f.finish(images, vec![texture]);
}

/// Bad albedo sources are typed errors, and the container stays usable.
#[test]
fn bad_albedo_sources_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut frame = ctx.create_task_container();
    let quad = Mesh::quad(1.0);
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    let vb = host.buffer_with_data(bytemuck::cast_slice(&quad.positions), usage).unwrap();
    let ib = host.buffer_with_data(bytemuck::cast_slice(&quad.indices), usage).unwrap();
    let attributes = host.buffer_with_data(&[0u8; 256], usage).unwrap();
    let texture =
        host.image_with_data(vk::Format::R8G8B8A8_UNORM, 2, 2, vk::ImageUsageFlags::SAMPLED, &[128u8; 16], READ).unwrap();
    let n = quad.positions.len() as u32;
    let attribute =
        |format, stride| hybrid_rt::VertexBufferInput { buffer: attributes.buffer, count: n, stride, format, offset: 0 };
    let good = hybrid_rt::GeometryInput {
        vertices: hybrid_rt::VertexBufferInput { buffer: vb.buffer, count: n, ..Default::default() },
        indices: hybrid_rt::IndexBufferInput { buffer: ib.buffer, count: quad.indices.len() as u32, ..Default::default() },
        colors: Some(attribute(vk::Format::R8G8B8A8_UNORM, 4)),
        uvs: Some(attribute(vk::Format::R32G32_SFLOAT, 8)),
        albedo_texture: Some(hybrid_rt::AlbedoTextureInput { texture: texture.input(READ) }),
        ..Default::default()
    };
    let bad = [
        hybrid_rt::GeometryInput { colors: Some(attribute(vk::Format::R8_UNORM, 4)), ..good.clone() },
        hybrid_rt::GeometryInput { colors: Some(attribute(vk::Format::R32G32B32_SFLOAT, 8)), ..good.clone() },
        hybrid_rt::GeometryInput {
            colors: Some(hybrid_rt::VertexBufferInput { count: 1, ..attribute(vk::Format::R8G8B8A8_UNORM, 4) }),
            ..good.clone()
        },
        hybrid_rt::GeometryInput { uvs: None, ..good.clone() },
        hybrid_rt::GeometryInput {
            albedo_texture: Some(hybrid_rt::AlbedoTextureInput {
                texture: hybrid_rt::ImageInput { width: 0, ..texture.input(READ) },
            }),
            ..good.clone()
        },
        hybrid_rt::GeometryInput {
            albedo_texture: Some(hybrid_rt::AlbedoTextureInput {
                texture: hybrid_rt::ImageInput { format: vk::Format::D32_SFLOAT, ..texture.input(READ) },
            }),
            ..good.clone()
        },
        hybrid_rt::GeometryInput { colors: Some(attribute(vk::Format::R8G8B8A8_UNORM, 1 << 20)), ..good.clone() },
    ];
    let handle = ctx.create_geometry_handles(1)[0];
    for input in bad {
        let task = hybrid_rt::GeometryTask { handle, operation: hybrid_rt::TaskOperation::Register, input: input.clone() };
        // SAFETY: the engine's buffers the task names are alive.
        let e = unsafe { frame.schedule_geometry(&task) }.expect_err("refused");
        assert!(
            matches!(
                e,
                hybrid_rt::Error::InvalidInput { .. }
                    | hybrid_rt::Error::UnsupportedFormat { .. }
                    | hybrid_rt::Error::BufferTooSmall { .. }
            ),
            "{e}"
        );
    }
    let task = hybrid_rt::GeometryTask { handle, operation: hybrid_rt::TaskOperation::Register, input: good };
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { frame.schedule_geometry(&task) }.unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    ctx.destroy_geometry_handles(&[handle]).unwrap();
    for b in [vb, ib, attributes] {
        host.destroy_buffer(b);
    }
    host.destroy_image(texture);
    drop(ctx);
    assert_no_validation_errors();
}

/// Bad relight tasks and albedos are typed errors that leave the container usable.
#[test]
fn bad_relight_input_is_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut frame = ctx.create_task_container();
    let light = LightInfo::default();
    let bad = [
        RelightCacheTask { lights: vec![], ..Default::default() },
        RelightCacheTask { lights: vec![light; 33], ..Default::default() },
        RelightCacheTask { lights: vec![light], max_samples: 0, ..Default::default() },
        RelightCacheTask { lights: vec![light], max_samples: hybrid_rt::MAX_RELIGHT_SAMPLES + 1, ..Default::default() },
        RelightCacheTask { lights: vec![light], history_frames: 0, ..Default::default() },
        RelightCacheTask { lights: vec![LightInfo { color: [f32::NAN, 1.0, 1.0], ..light }], ..Default::default() },
        RelightCacheTask { lights: vec![LightInfo { color: [-1.0, 1.0, 1.0], ..light }], ..Default::default() },
        RelightCacheTask { lights: vec![light], sky: [0.0, f32::INFINITY, 0.0], ..Default::default() },
    ];
    for t in &bad {
        let e = frame.schedule_cache_relight(t).expect_err("refused");
        assert!(matches!(e, hybrid_rt::Error::InvalidInput { .. }), "{e}");
    }
    let geometry = ctx.create_geometry_handles(1)[0];
    let instance = ctx.create_instance_handles(1)[0];
    for albedo in [[f32::NAN, 0.5, 0.5], [1.5, 0.5, 0.5], [-0.1, 0.5, 0.5]] {
        let task = InstanceTask {
            handle: instance,
            operation: InstanceOperation::Register,
            input: InstanceInput { geometry, albedo, ..Default::default() },
        };
        assert!(frame.schedule_instance(&task).is_err(), "albedo {albedo:?}");
    }
    assert!(frame.is_empty());
    frame.schedule_cache_relight(&RelightCacheTask { lights: vec![light], ..Default::default() }).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    drop(ctx);
    drop(host);
    assert_no_validation_errors();
}
