//! Environment maps for rays that miss, against the reference: a mirror floor reflects the
//! map pixel by pixel; diffuse GI under an open sky converges to the cosine-weighted integral
//! of the map; both with a rotation and an intensity.
//!
//! The map is chosen so that its bilinear lookup is a closed-form function of the direction
//! (R linear in v between texel centres, G a triangle wave in u with its kinks on texel
//! centres, B constant), so the reference evaluates the exact function the GPU interpolates.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Mat3, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 48;
const H: u32 = 48;
const MAP_W: u32 = 16;
const MAP_H: u32 = 8;
const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

fn map_texels() -> Vec<[f32; 4]> {
    let mut t = Vec::new();
    for j in 0..MAP_H {
        for i in 0..MAP_W {
            let r = 0.2 + 0.6 * (j as f32 + 0.5) / MAP_H as f32;
            let g = (i as f32 - MAP_W as f32 / 2.0).abs() / (MAP_W as f32 / 2.0);
            t.push([r, g, 0.5, 1.0]);
        }
    }
    t
}

/// What the GPU's bilinear lookup of `map_texels` returns for a world direction.
fn environment(rotation: Mat3, intensity: f32, dir: Vec3) -> Vec3 {
    let d = (rotation.transpose() * dir).normalize();
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * std::f32::consts::PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
    let (x, y) = (u * MAP_W as f32 - 0.5, v * MAP_H as f32 - 0.5);
    let r = 0.2 + 0.6 * (y.clamp(0.0, (MAP_H - 1) as f32) + 0.5) / MAP_H as f32;
    let g = (x.rem_euclid(MAP_W as f32) - MAP_W as f32 / 2.0).abs() / (MAP_W as f32 / 2.0);
    Vec3::new(r, g, 0.5) * intensity
}

struct Floor {
    host: hybrid_rt_testkit::host::Host,
    ctx: ExecuteContext,
    frame: TaskContainer,
    images: GBufferImages,
    gpu_scene: SceneOnGpu,
    g: GBuffer,
    camera: Camera,
    map: hybrid_rt_testkit::host::HostImage,
    out: hybrid_rt_testkit::host::HostImage,
}

/// A floor alone under the map: every secondary ray leaving it upwards misses.
fn floor() -> Floor {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let plane = scene.add_mesh(Mesh::grid(40.0, 2));
    scene.add_instance(plane, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 1.5, 2.0), Vec3::new(0.0, 0.0, 0.5));
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    assert!(g.hit.iter().all(|h| *h), "the floor fills the view");
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let map = host
        .image_with_data(
            vk::Format::R32G32B32A32_SFLOAT,
            MAP_W,
            MAP_H,
            vk::ImageUsageFlags::SAMPLED,
            bytemuck::cast_slice(&map_texels()),
            READ,
        )
        .unwrap();
    let out = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, GENERAL).unwrap();
    Floor { host, ctx, frame, images, gpu_scene, g, camera, map, out }
}

impl Floor {
    fn environment(&self, rotation: Mat3, intensity: f32) -> EnvironmentInput {
        EnvironmentInput { image: self.map.input(READ), rotation, intensity }
    }

    fn read(&self) -> Vec<[f32; 4]> {
        bytemuck::cast_slice(&self.host.read_image(&self.out, GENERAL).unwrap()).to_vec()
    }

    fn finish(self) {
        self.host.destroy_image(self.map);
        self.host.destroy_image(self.out);
        self.images.destroy(&self.host);
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
    }
}

fn rotation() -> Mat3 {
    Mat3::from_rotation_y(1.0) * Mat3::from_rotation_x(0.4)
}

/// A mirror floor shows the map in the reflected direction, pixel by pixel (one deterministic
/// ray each); the tolerance covers the G-buffer position's reconstruction from clip depth.
#[test]
fn a_mirror_reflects_the_environment_map() {
    let mut f = floor();
    let mut common = f.images.trace_common(&f.camera);
    common.roughness.global_roughness = 0.0;
    // (The default ray offset moves the origin off the floor; a miss's radiance depends on
    // the direction only.)
    for (rotation, intensity) in [(Mat3::IDENTITY, 1.0), (rotation(), 1.5)] {
        let task = TraceSpecularTask {
            common,
            output: f.out.input(GENERAL),
            ray_length: 100.0,
            miss_radiance: [9.0; 3],
            environment: f.environment(rotation, intensity),
            ..Default::default()
        };
        f.frame.schedule_specular(&task).unwrap();
        run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
        let gpu = f.read();
        let mut worst = 0.0f32;
        for ((texel, p), n) in gpu.iter().zip(&f.g.position).zip(&f.g.normal) {
            let v = (f.camera.eye - *p).normalize();
            let r = -v + 2.0 * n.dot(v) * *n;
            let expected = environment(rotation, intensity, r);
            worst = worst.max((Vec3::new(texel[0], texel[1], texel[2]) - expected).abs().max_element());
        }
        eprintln!("mirror, intensity {intensity}: worst |GPU - reference| {worst:.2e}");
        assert!(worst < 1e-3, "the mirror shows the map ({worst})");
    }
    f.finish();
}

/// Diffuse GI under the open map: every pixel's expectation is the cosine-weighted mean of the
/// map over the upper hemisphere (the floor's normal is +Y everywhere), which the reference
/// integrates on a 256 x 256 stratified grid; the GPU's image mean averages 2304 pixels x 64
/// rays, so its standard error is below range / 2 / sqrt(147456) = 0.002 per channel (range
/// <= 1.5); the tolerance is 4 of them plus the reference's own error.
#[test]
fn diffuse_gi_under_the_map_converges_to_its_cosine_integral() {
    let mut f = floor();
    let common = f.images.trace_common(&f.camera);
    let (rays, frames) = (16u32, 4u32);
    for (rotation, intensity) in [(Mat3::IDENTITY, 1.0), (rotation(), 1.5)] {
        let task = TraceDiffuseTask {
            common,
            output: f.out.input(GENERAL),
            rays_per_pixel: rays,
            ray_length: 100.0,
            miss_radiance: [9.0; 3],
            environment: f.environment(rotation, intensity),
            ..Default::default()
        };
        let mut mean = Vec3::ZERO;
        for _ in 0..frames {
            f.frame.schedule_diffuse(&task).unwrap();
            run_frame(&f.host, &f.ctx, &mut f.frame).unwrap();
            let gpu = f.read();
            mean += gpu.iter().map(|t| Vec3::new(t[0], t[1], t[2])).sum::<Vec3>() / (gpu.len() * frames as usize) as f32;
        }
        // Cosine-weighted hemisphere around +Y: stratified (u1, u2), r = sqrt(u1).
        let n = 256;
        let mut reference = Vec3::ZERO;
        for a in 0..n {
            for b in 0..n {
                let (u1, u2) = ((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
                let (r, phi) = (u1.sqrt(), 2.0 * std::f32::consts::PI * u2);
                let d = Vec3::new(r * phi.cos(), (1.0 - u1).max(0.0).sqrt(), r * phi.sin());
                reference += environment(rotation, intensity, d);
            }
        }
        reference /= (n * n) as f32;
        let err = (mean - reference).abs().max_element();
        let tolerance = 4.0 * (1.5 / 2.0) / ((W * H * rays * frames) as f32).sqrt() + 1e-3;
        eprintln!("diffuse, intensity {intensity}: GPU {mean:?} vs reference {reference:?} (tolerance {tolerance:.4})");
        assert!(err < tolerance, "diffuse GI under the map: {err} > {tolerance}");
    }
    f.finish();
}

#[test]
fn bad_environments_are_refused() {
    let mut f = floor();
    let good = TraceSpecularTask {
        common: f.images.trace_common(&f.camera),
        output: f.out.input(GENERAL),
        environment: f.environment(Mat3::IDENTITY, 1.0),
        ..Default::default()
    };
    f.frame.schedule_specular(&good).unwrap();
    let mut bad = good.clone();
    bad.environment.rotation = Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0));
    assert!(matches!(f.frame.schedule_specular(&bad).unwrap_err(), Error::InvalidTransform { .. }), "a mirror is no rotation");
    bad = good.clone();
    bad.environment.rotation = Mat3::IDENTITY * 2.0;
    assert!(matches!(f.frame.schedule_specular(&bad).unwrap_err(), Error::InvalidTransform { .. }), "a scale is no rotation");
    bad = good.clone();
    bad.environment.intensity = f32::NAN;
    assert!(matches!(f.frame.schedule_specular(&bad).unwrap_err(), Error::InvalidInput { .. }));
    bad = good.clone();
    bad.environment.image.format = vk::Format::R32_SFLOAT;
    assert!(matches!(f.frame.schedule_specular(&bad).unwrap_err(), Error::UnsupportedFormat { .. }));
    bad = good.clone();
    bad.environment.image.usage = vk::ImageUsageFlags::STORAGE;
    assert!(matches!(f.frame.schedule_specular(&bad).unwrap_err(), Error::InvalidInput { .. }));
    let diffuse =
        TraceDiffuseTask { common: good.common, output: good.output, environment: bad.environment, ..Default::default() };
    assert!(f.frame.schedule_diffuse(&diffuse).is_err());
    f.frame.clear();
    f.finish();
}
