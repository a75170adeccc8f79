//! Hit lighting (`TraceSpecularTask::hit_lighting`): a mirror's hits shaded from the engine's
//! lights with shadow rays are the reference's direct light, shadow edges included, where
//! the cache is a tile wide; the gather rays add the caches' indirect light; emission is
//! added; bad input is refused.
mod common;
use common::relit_scene::*;
use common::*;
use glam::{Affine3A, Quat, Vec3};
use hybrid_rt::{
    HitIndirect, HitLighting, InitSettings, InstanceInput, InstanceOperation, InstanceTask, LightInfo, RoughnessInput,
    TraceSpecularTask,
};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

/// The mirror tests' camera: low over the ground (a mirror), looking at the box.
fn low() -> Camera {
    Camera::look_at(Vec3::new(-0.6, 0.35, 2.6), Vec3::new(0.2, 0.5, -0.1))
}

/// The box glows a little (relighting and hit lighting add it; the ground does not).
const BOX_EMISSION: [f32; 3] = [0.05, 0.02, 0.0];
/// Albedos of the ground, the box and the wall behind them.
const ALBEDOS: [[f32; 3]; 3] = [ALBEDO[0], ALBEDO[1], [0.6, 0.6, 0.6]];

/// The relighting scene with a wall behind the box: the point light casts the box's hard
/// shadow on it, and the mirror shows the wall.
fn scene_with_wall() -> Scene {
    let mut s = scene();
    let wall = s.add_mesh(Mesh::grid(4.0, 8));
    let upright =
        Affine3A::from_rotation_translation(Quat::from_rotation_x(std::f32::consts::FRAC_PI_2), Vec3::new(0.0, 1.0, -1.2));
    s.add_instance(wall, upright);
    s
}

/// A mirror pixel of the ground: the reflected ray's hit, and the reference's direct light
/// (plus emission) there.
struct Reflected {
    pixel: usize,
    hit: Hit,
    point: Vec3,
    direct: Vec3,
}

fn reflected_pixels(tracer: &Tracer, g: &GBuffer, eye: Vec3) -> Vec<Reflected> {
    let offset = hybrid_rt::RayOffset::default();
    (0..g.depth.len())
        .filter(|&i| g.hit[i] && g.instance[i] == 0)
        .filter_map(|i| {
            let (p, n) = (g.position[i], g.normal[i]);
            let v = (eye - p).normalize();
            let dir = (-v) - 2.0 * (-v).dot(n) * n;
            let origin = offset_origin(p, n, eye, &offset);
            let hit = tracer.closest_hit(origin, dir, 0.0, 100.0)?;
            let point = origin + dir * hit.t;
            let emission = if hit.instance == 1 { Vec3::from(BOX_EMISSION) } else { Vec3::ZERO };
            let direct = reference_radiance(tracer, point, hit.normal, ALBEDOS[hit.instance as usize]) + emission;
            Some(Reflected { pixel: i, hit, point, direct })
        })
        .collect()
}

/// Registers the scene, gives the box its emission, relights every sample once.
fn relit_fixture() -> Fixture {
    let mut f = Fixture::with(scene_with_wall(), &ALBEDOS);
    let input = InstanceInput {
        geometry: f.gpu_scene.geometries[f.scene.instances[1].mesh],
        transform: f.scene.instances[1].transform,
        initial_tile_color: UNLIT,
        albedo: ALBEDO[1],
        emission: BOX_EMISSION,
        ..Default::default()
    };
    let task = InstanceTask { handle: f.gpu_scene.instances[1], operation: InstanceOperation::Update, input };
    f.frame.schedule_instance(&task).unwrap();
    f.relight(hybrid_rt::MAX_RELIGHT_SAMPLES);
    f
}

fn mirror_task(images: &GBufferImages, camera: &Camera, hit_lighting: HitLighting) -> TraceSpecularTask {
    let mut common = images.trace_common(camera);
    common.roughness = RoughnessInput { global_roughness: 0.0, ..Default::default() };
    common.enable_bilinear_sampling = false;
    TraceSpecularTask { common, ray_length: 100.0, hit_lighting, ..Default::default() }
}

/// Relative RMSE of `got` (RGB of the output's pixels) against `want`.
fn rel_rmse(pairs: impl Iterator<Item = (Vec3, Vec3)>) -> f64 {
    let (mut err2, mut ref2) = (0.0f64, 0.0f64);
    for (got, want) in pairs {
        err2 += (got - want).length_squared() as f64;
        ref2 += want.length_squared() as f64;
    }
    (err2 / ref2.max(1e-12)).sqrt()
}

/// The case: with hard lights one hit-lit frame is exact, so the mirror shows the
/// reference's direct light at every reflected hit — at the box's shadow edge too, which the
/// cache (5 cm tiles) blurs. Error sources left: float offsets of the shadow rays (a ray that
/// grazes the box's edge may go either way), so a few pixels on the edge itself may differ.
#[test]
fn hit_lit_mirrors_are_as_sharp_as_the_lights() {
    let mut f = relit_fixture();
    let camera = low();
    let tracer = Tracer::new(&f.scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let cached = f.trace_specular(mirror_task(&images, &camera, HitLighting::default()));
    let hit_lit = f.trace_specular(mirror_task(
        &images,
        &camera,
        HitLighting { lights: lights(), max_roughness: 0.0, indirect: HitIndirect::None, ..Default::default() },
    ));
    // The default indirect part: the cache sample less the same lights' direct light there.
    // These caches hold relit direct light only, so it adds nothing: the subtraction lights
    // the sample exactly as the relight did.
    let residual = f.trace_specular(mirror_task(
        &images,
        &camera,
        HitLighting { lights: lights(), max_roughness: 0.0, ..Default::default() },
    ));
    let pixels = reflected_pixels(&tracer, &g, camera.eye);
    let rgb = |img: &[[f32; 4]], i: usize| Vec3::from_slice(&img[i][..3]);
    // (A vertex or edge sample shared by triangles was relit a hair inside one of them, so it
    // may differ from its light inside another by the light's gradient over 0.1% of a
    // triangle, or where a shadow edge crosses there.)
    let residual_rmse = rel_rmse(pixels.iter().map(|r| (rgb(&residual, r.pixel), rgb(&hit_lit, r.pixel))));
    let residual_off = pixels
        .iter()
        .filter(|r| (rgb(&residual, r.pixel) - rgb(&hit_lit, r.pixel)).length() > 0.01 * r.direct.length() + 1e-3)
        .count();
    // Pixels near an edge of the reference's light (within 1.5 tiles it changes by > 10%):
    // where the cache's resolution shows.
    let edge: Vec<&Reflected> = pixels
        .iter()
        .filter(|r| {
            let albedo = ALBEDOS[r.hit.instance as usize];
            let base = reference_radiance(&tracer, r.point, r.hit.normal, albedo);
            let n = r.hit.normal;
            let (t, b) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
            [t, -t, b, -b].iter().any(|d| {
                (reference_radiance(&tracer, r.point + *d * 1.5 * TILE, n, albedo) - base).length() > 0.1 * base.length() + 0.02
            })
        })
        .collect();
    let all_lit = rel_rmse(pixels.iter().map(|r| (rgb(&hit_lit, r.pixel), r.direct)));
    let edge_lit = rel_rmse(edge.iter().map(|r| (rgb(&hit_lit, r.pixel), r.direct)));
    let edge_cached = rel_rmse(edge.iter().map(|r| (rgb(&cached, r.pixel), r.direct)));
    let off = pixels.iter().filter(|r| (rgb(&hit_lit, r.pixel) - r.direct).length() > 0.01 * r.direct.length() + 1e-3).count();
    let box_hits = pixels.iter().filter(|r| r.hit.instance == 1).count();
    let wall_hits = pixels.iter().filter(|r| r.hit.instance == 2).count();
    eprintln!(
        "hit lighting: {} reflected pixels ({box_hits} on the box, {wall_hits} on the wall, {} near light edges); relative RMSE all {all_lit:.4}, \
         edges {edge_lit:.4} (cache {edge_cached:.4}); {off} pixels off by > 1%; residual mode: relative RMSE {residual_rmse:.5}, {residual_off} pixels off by > 1%",
        pixels.len(),
        edge.len()
    );
    assert!(
        pixels.len() > 150 && box_hits > 30 && wall_hits > 30 && edge.len() > 20,
        "the mirror shows the box, the wall and a shadow's edge"
    );
    assert!(all_lit < 0.02, "hit-lit mirror vs reference: relative RMSE {all_lit}");
    assert!(
        residual_rmse < 0.01 && residual_off * 100 <= pixels.len(),
        "the cache's residual over relit direct light: relative RMSE {residual_rmse}, {residual_off} pixels off by > 1%"
    );
    assert!(off * 50 <= pixels.len(), "{off} of {} pixels off by more than 1%", pixels.len());
    assert!(edge_lit * 4.0 < edge_cached, "at light edges hit lighting {edge_lit} vs the cache {edge_cached}");
    f.finish(images, Vec::new());
}

/// A cosine-weighted mean of the relit caches' radiance (their direct light plus the box's
/// emission), as the gather reads it: the reference, stratified, `strata`² rays at (p, n).
fn reference_gather(tracer: &Tracer, p: Vec3, n: Vec3, strata: u32, rng: &mut Rng) -> Vec3 {
    let origin = p + n * 1e-3;
    let (t, b) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
    let mut sum = Vec3::ZERO;
    for sy in 0..strata {
        for sx in 0..strata {
            let u1 = (sx as f32 + rng.next_f32()) / strata as f32;
            let u2 = (sy as f32 + rng.next_f32()) / strata as f32;
            let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let dir = (t * r * phi.cos() + b * r * phi.sin() + n * (1.0 - u1).max(0.0).sqrt()).normalize();
            if let Some(h) = tracer.closest_hit(origin, dir, 0.0, 1e30) {
                let q = origin + dir * h.t;
                let emission = if h.instance == 1 { Vec3::from(BOX_EMISSION) } else { Vec3::ZERO };
                sum += reference_radiance(tracer, q, h.normal, ALBEDOS[h.instance as usize]) + emission;
            }
        }
    }
    sum / (strata * strata) as f32
}

/// With gather rays the hit adds its albedo x the caches' cosine-weighted radiance (misses
/// see the task's miss radiance: black here). Over 24 frames of 8 gather rays (192 rays per
/// pixel) against a 32² stratified reference: the mean over the mirror's pixels agrees
/// within 5% (the estimate's own noise is ~0.5% there: ~1,200 pixels x 192 rays; measured 0.7%),
/// each pixel within a relative RMSE of 25% (one pixel's 192 rays: ~10% noise, plus the caches'
/// 5 cm tiles; measured 11%).
#[test]
fn gather_rays_add_the_caches_indirect_light() {
    let mut f = relit_fixture();
    let camera = low();
    let tracer = Tracer::new(&f.scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let images = GBufferImages::upload(&f.host, &g).unwrap();
    let direct_only = HitLighting { lights: lights(), max_roughness: 0.0, indirect: HitIndirect::None, ..Default::default() };
    let direct = f.trace_specular(mirror_task(&images, &camera, direct_only.clone()));
    const FRAMES: usize = 24;
    let mut sum = vec![Vec3::ZERO; direct.len()];
    for _ in 0..FRAMES {
        let out = f.trace_specular(mirror_task(
            &images,
            &camera,
            HitLighting { indirect: HitIndirect::Gather, gather_rays: 8, ..direct_only.clone() },
        ));
        for (s, o) in sum.iter_mut().zip(&out) {
            *s += Vec3::from_slice(&o[..3]) / FRAMES as f32;
        }
    }
    let mut rng = Rng::new(11);
    let pixels = reflected_pixels(&tracer, &g, camera.eye);
    let pairs: Vec<(Vec3, Vec3)> = pixels
        .iter()
        .map(|r| {
            let n = if r.hit.normal.dot(r.point - camera.eye) > 0.0 { -r.hit.normal } else { r.hit.normal };
            let want = Vec3::from(ALBEDOS[r.hit.instance as usize]) * reference_gather(&tracer, r.point, n, 32, &mut rng);
            (sum[r.pixel] - Vec3::from_slice(&direct[r.pixel][..3]), want)
        })
        .collect();
    let (got_mean, want_mean) = pairs.iter().fold((Vec3::ZERO, Vec3::ZERO), |(a, b), (g, w)| (a + *g, b + *w));
    let mean_err = (got_mean - want_mean).length() / want_mean.length();
    let per_pixel = rel_rmse(pairs.iter().copied());
    eprintln!(
        "gathered indirect over {} pixels: mean {:?} vs reference {:?} ({:.2}% off); per pixel relative RMSE {per_pixel:.3}",
        pairs.len(),
        got_mean / pairs.len() as f32,
        want_mean / pairs.len() as f32,
        100.0 * mean_err
    );
    assert!(want_mean.min_element() > 0.0, "the mirror's hits see lit caches");
    assert!(mean_err < 0.05, "mean indirect {mean_err} off");
    assert!(per_pixel < 0.25, "per-pixel relative RMSE {per_pixel}");
    f.finish(images, Vec::new());
}

/// Bad hit lighting and emission are typed errors that leave the container usable.
#[test]
fn bad_hit_lighting_is_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut frame = ctx.create_task_container();
    let scene = scene();
    let g = GBuffer::render(&Tracer::new(&scene), &camera(), W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let out = host
        .image_cleared(
            ash::vk::Format::R32G32B32A32_SFLOAT,
            W,
            H,
            ash::vk::ImageUsageFlags::STORAGE,
            ash::vk::ImageLayout::GENERAL,
        )
        .unwrap();
    let good = TraceSpecularTask {
        output: out.input(ash::vk::ImageLayout::GENERAL),
        ..mirror_task(&images, &camera(), HitLighting { lights: lights(), ..Default::default() })
    };
    let light = LightInfo::default();
    let bad = [
        HitLighting { lights: vec![light; 33], ..Default::default() },
        HitLighting { lights: vec![LightInfo { intensity: f32::NAN, ..light }], ..Default::default() },
        HitLighting { lights: vec![light], max_roughness: f32::NAN, ..Default::default() },
        HitLighting { lights: vec![light], max_roughness: 1.5, ..Default::default() },
        HitLighting { lights: vec![light], gather_rays: hybrid_rt::MAX_HIT_GATHER_RAYS + 1, ..Default::default() },
        HitLighting { lights: vec![light], gather_rays: 0, ..Default::default() },
    ];
    for h in bad {
        let e = frame.schedule_specular(&TraceSpecularTask { hit_lighting: h.clone(), ..good.clone() }).expect_err("refused");
        assert!(matches!(e, hybrid_rt::Error::InvalidInput { .. }), "{h:?}: {e}");
    }
    let mut s = Scene::default();
    let quad = s.add_mesh(Mesh::quad(1.0));
    s.add_instance(quad, Affine3A::IDENTITY);
    let gpu = SceneOnGpu::register(&host, &ctx, &mut frame, &s).unwrap();
    for emission in [[f32::NAN, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, f32::INFINITY]] {
        let input = InstanceInput { geometry: gpu.geometries[0], emission, ..Default::default() };
        let task = InstanceTask { handle: gpu.instances[0], operation: InstanceOperation::Update, input };
        let e = frame.schedule_instance(&task).expect_err("refused");
        assert!(matches!(e, hybrid_rt::Error::InvalidInput { .. }), "{emission:?}: {e}");
    }
    // Still usable: the good task records and runs.
    frame.schedule_specular(&good).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    host.destroy_image(out);
    images.destroy(&host);
    gpu.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
