//! Specular reflections against the reference: a mirror reflects exactly where the reference
//! puts it; glossy reflections converge to an independent estimate of the GGX integral; the
//! roughness channel mask reads the right channel.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{InitSettings, RoughnessInput, TraceSpecularTask};
use hybrid_rt_testkit::host::Host;
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 48;
const H: u32 = 48;
const SKY: [f32; 3] = [0.1, 0.2, 0.3];

/// The coloured room without its ceiling, seen looking down at the floor.
fn room() -> (Scene, Vec<[f32; 3]>, Camera) {
    let (s, colours, _) = coloured_room(false);
    (s, colours, Camera::look_at(Vec3::new(0.0, 1.6, 1.9), Vec3::new(0.0, 0.0, -0.8)))
}

struct Fixture {
    host: Host,
    ctx: hybrid_rt::ExecuteContext,
    frame: hybrid_rt::TaskContainer,
    images: GBufferImages,
    out: hybrid_rt_testkit::host::HostImage,
    gpu_scene: SceneOnGpu,
    g: GBuffer,
    tracer: Tracer,
    colours: Vec<[f32; 3]>,
    camera: Camera,
}

fn fixture() -> Fixture {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, colours, camera) = room();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let out = host
        .image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)
        .unwrap();
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register_coloured(&host, &ctx, &mut frame, &scene, Default::default(), &colours).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    Fixture { host, ctx, frame, images, out, gpu_scene, g, tracer, colours, camera }
}

impl Fixture {
    fn trace(&mut self, task: &TraceSpecularTask, frames: u32) -> Vec<[f32; 4]> {
        let mut acc = vec![[0.0f32; 4]; (W * H) as usize];
        for _ in 0..frames {
            self.frame.schedule_specular(task).unwrap();
            let done = run_frame(&self.host, &self.ctx, &mut self.frame).unwrap();
            assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::Specular));
            let texels: Vec<[f32; 4]> =
                bytemuck::cast_slice(&self.host.read_image(&self.out, vk::ImageLayout::GENERAL).unwrap()).to_vec();
            for (a, t) in acc.iter_mut().zip(&texels) {
                for c in 0..4 {
                    a[c] += t[c] / frames as f32;
                }
            }
        }
        acc
    }

    fn task(&self, roughness: RoughnessInput, rays: u32) -> TraceSpecularTask {
        let mut common = self.images.trace_common(&self.camera);
        common.roughness = roughness;
        TraceSpecularTask {
            common,
            output: self.out.input(vk::ImageLayout::GENERAL),
            rays_per_pixel: rays,
            ray_length: 100.0,
            miss_radiance: SKY,
            ..Default::default()
        }
    }

    fn radiance(&self, origin: Vec3, dir: Vec3) -> [f32; 3] {
        self.tracer.closest_hit(origin, dir, 0.0, 100.0).map_or(SKY, |h| self.colours[h.instance as usize])
    }

    fn finish(self) {
        self.host.destroy_image(self.out);
        self.images.destroy(&self.host);
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
    }
}

#[test]
fn a_mirror_reflects_exactly_where_the_reference_does() {
    let mut f = fixture();
    let mirror = f.task(RoughnessInput { global_roughness: 0.0, ..Default::default() }, 1);
    let gpu = f.trace(&mirror, 1);
    let offset = hybrid_rt::RayOffset::default();
    let (mut same, mut total) = (0, 0);
    for i in (0..f.g.depth.len()).filter(|&i| f.g.hit[i]) {
        let (p, n) = (f.g.position[i], f.g.normal[i]);
        let v = (f.camera.eye - p).normalize();
        let dir = (-v) - 2.0 * (-v).dot(n) * n;
        let want = f.radiance(offset_origin(p, n, f.camera.eye, &offset), dir);
        total += 1;
        if (0..3).all(|c| (gpu[i][c] - want[c]).abs() < 1e-4) {
            same += 1;
        }
    }
    eprintln!("mirror: {same} of {total} pixels identical to the reference");
    // Only pixels whose reflected ray grazes a wall's edge may differ.
    assert!(same as f32 >= 0.98 * total as f32);
    f.finish();
}

/// GGX D and separable Smith G for the reference estimator.
fn ggx_d(ndoth: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = ndoth * ndoth * (a2 - 1.0) + 1.0;
    a2 / (std::f32::consts::PI * d * d)
}
fn smith_g1(ndotx: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    2.0 * ndotx / (ndotx + (a2 + (1.0 - a2) * ndotx * ndotx).sqrt())
}

#[test]
fn glossy_reflections_converge_to_the_reference_and_read_the_roughness_channel() {
    let mut f = fixture();
    // Roughness 0.5 in G; R holds 0.9 to catch a wrong mask.
    let texels = vec![[0.9f32, 0.5, 0.0, 0.0]; (W * H) as usize];
    let rough = f
        .host
        .image_with_data(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::SAMPLED, bytemuck::cast_slice(&texels), READ)
        .unwrap();
    let input = RoughnessInput { image: rough.input(READ), channel_mask: [0.0, 1.0, 0.0, 0.0], ..Default::default() };
    let (rays, frames) = (16u32, 4u32);
    let gpu = f.trace(&f.task(input, rays), frames);

    // Independent reference: cosine-weighted sampling of the whole integrand
    // L(l) D(h) G1(v) G1(l) / (4 n.v n.l), estimator pi D G1 G1 / (4 n.v n.l) L.
    let alpha = 0.25f32;
    let strata = 32u32;
    let offset = hybrid_rt::RayOffset::default();
    let mut rng = Rng::new(9);
    let mut worst = 0.0f32;
    let mut blocks = 0;
    for by in 0..H / 8 {
        for bx in 0..W / 8 {
            // Block means of GPU and reference, with the reference's own standard error.
            let (mut g_sum, mut r_sum, mut r_var, mut n) = (0.0f32, 0.0f32, 0.0f32, 0);
            for y in by * 8..by * 8 + 8 {
                for x in bx * 8..bx * 8 + 8 {
                    let i = (y * W + x) as usize;
                    if !f.g.hit[i] {
                        continue;
                    }
                    let (p, nrm) = (f.g.position[i], f.g.normal[i]);
                    let v = (f.camera.eye - p).normalize();
                    let nv = nrm.dot(v).max(1e-4);
                    let origin = offset_origin(p, nrm, f.camera.eye, &offset);
                    let t = if nrm.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
                    let t = (t - nrm * nrm.dot(t)).normalize();
                    let b = nrm.cross(t);
                    let (mut s1, mut s2) = (0.0f32, 0.0f32);
                    for sy in 0..strata {
                        for sx in 0..strata {
                            let u1 = (sx as f32 + rng.next_f32()) / strata as f32;
                            let u2 = (sy as f32 + rng.next_f32()) / strata as f32;
                            let (r, phi) = (u1.sqrt(), 2.0 * std::f32::consts::PI * u2);
                            let l = (t * r * phi.cos() + b * r * phi.sin() + nrm * (1.0 - u1).max(0.0).sqrt()).normalize();
                            let nl = nrm.dot(l).max(1e-4);
                            let h = (v + l).normalize();
                            let w = std::f32::consts::PI
                                * ggx_d(nrm.dot(h).max(0.0), alpha)
                                * smith_g1(nv, alpha)
                                * smith_g1(nl, alpha)
                                / (4.0 * nv * nl);
                            let e = w * f.radiance(origin, l)[0];
                            s1 += e;
                            s2 += e * e;
                        }
                    }
                    let m = (strata * strata) as f32;
                    let mean = s1 / m;
                    r_sum += mean;
                    r_var += (s2 / m - mean * mean).max(0.0) / m;
                    g_sum += gpu[i][0];
                    n += 1;
                }
            }
            if n < 32 {
                continue;
            }
            let nf = n as f32;
            // GPU samples of the red channel lie in [0, 0.9]: variance <= 0.9^2/4 per sample.
            let gpu_var = 0.81 / 4.0 / (rays * frames) as f32 / nf;
            let tolerance = 4.0 * (gpu_var + r_var / (nf * nf)).sqrt() + 0.01;
            let err = (g_sum / nf - r_sum / nf).abs();
            worst = worst.max(err / tolerance);
            blocks += 1;
            assert!(
                err <= tolerance,
                "block ({bx}, {by}): GPU {:.4} vs reference {:.4} (tolerance {tolerance:.4})",
                g_sum / nf,
                r_sum / nf
            );
        }
    }
    eprintln!("glossy: {blocks} blocks, worst error / tolerance = {worst:.2}");
    assert!(blocks >= 10);
    // With the R channel (0.9) the lobe is much wider: the image must differ.
    let wrong = f.trace(&f.task(RoughnessInput { channel_mask: [1.0, 0.0, 0.0, 0.0], ..input }, rays), frames);
    let diff: f32 = gpu.iter().zip(&wrong).map(|(a, b)| (a[0] - b[0]).abs()).sum::<f32>() / gpu.len() as f32;
    assert!(diff > 0.01, "the channel mask matters ({diff})");
    f.host.destroy_image(rough);
    f.finish();
}

/// With the lit image as direct-lighting input, a mirror shows the lit pixels where its
/// reflection lands on screen, and the cache elsewhere.
#[test]
fn the_lit_image_lights_reflections_that_land_on_screen() {
    let mut f = fixture();
    // The lit image: the complement of each surface's cache colour, so the source is visible.
    let lit_texels: Vec<[f32; 4]> = (0..f.g.depth.len())
        .map(|i| {
            if f.g.hit[i] {
                let c = f.colours[f.g.instance[i] as usize];
                [1.0 - c[0], 1.0 - c[1], 1.0 - c[2], 1.0]
            } else {
                [0.0; 4]
            }
        })
        .collect();
    let lit = f
        .host
        .image_with_data(
            vk::Format::R32G32B32A32_SFLOAT,
            W,
            H,
            vk::ImageUsageFlags::SAMPLED,
            bytemuck::cast_slice(&lit_texels),
            READ,
        )
        .unwrap();
    let mut mirror = f.task(RoughnessInput { global_roughness: 0.0, ..Default::default() }, 1);
    mirror.common.direct_lighting = lit.input(READ);
    let gpu = f.trace(&mirror, 1);
    let world_to_clip = f.camera.view_to_clip(W as f32 / H as f32) * f.camera.world_to_view();
    let offset = hybrid_rt::RayOffset::default();
    let (mut same, mut total, mut from_screen) = (0, 0, 0);
    for i in (0..f.g.depth.len()).filter(|&i| f.g.hit[i]) {
        let (p, n) = (f.g.position[i], f.g.normal[i]);
        let v = (f.camera.eye - p).normalize();
        let dir = (-v) - 2.0 * (-v).dot(n) * n;
        let origin = offset_origin(p, n, f.camera.eye, &offset);
        let want = match f.tracer.closest_hit(origin, dir, 0.0, 100.0) {
            None => SKY,
            Some(h) => {
                let hit = origin + dir * h.t;
                let c = world_to_clip * hit.extend(1.0);
                let ndc = c.truncate() / c.w;
                let on_screen = c.w > 0.0 && ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0;
                let j = if on_screen {
                    let px = ((ndc.x * 0.5 + 0.5) * W as f32).min(W as f32 - 1.0) as u32;
                    let py = ((ndc.y * 0.5 + 0.5) * H as f32).min(H as f32 - 1.0) as u32;
                    Some((py * W + px) as usize)
                } else {
                    None
                };
                match j.filter(|&j| f.g.hit[j] && f.g.position[j].distance(hit) <= 0.01 * hit.distance(f.camera.eye) + 1e-3) {
                    Some(j) => {
                        from_screen += 1;
                        [lit_texels[j][0], lit_texels[j][1], lit_texels[j][2]]
                    }
                    None => f.colours[h.instance as usize],
                }
            }
        };
        total += 1;
        if (0..3).all(|c| (gpu[i][c] - want[c]).abs() < 1e-4) {
            same += 1;
        }
    }
    eprintln!("lit input: {same} of {total} pixels as the reference; {from_screen} reflections from the screen");
    assert!(from_screen > 100, "the test exercises on-screen hits");
    // Pixels whose reflection lands on a screen pixel's edge may pick the neighbouring texel.
    assert!(same as f32 >= 0.97 * total as f32);
    f.host.destroy_image(lit);
    f.finish();
}

/// The output is the demodulated radiance times the specular colour, channel by channel.
#[test]
fn specular_colour_modulates_and_the_demodulated_output_does_not() {
    let mut f = fixture();
    let spec_texels = vec![[0.9f32, 0.5, 0.1, 0.7]; (W * H) as usize];
    let spec = f
        .host
        .image_with_data(
            vk::Format::R32G32B32A32_SFLOAT,
            W,
            H,
            vk::ImageUsageFlags::SAMPLED,
            bytemuck::cast_slice(&spec_texels),
            READ,
        )
        .unwrap();
    let demod = f
        .host
        .image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)
        .unwrap();
    let mut task = f.task(RoughnessInput { global_roughness: 0.3, ..Default::default() }, 4);
    task.common.specular = hybrid_rt::SpecularInput { image: spec.input(READ), global_metalness: 0.5 };
    task.demodulated_output = demod.input(vk::ImageLayout::GENERAL);
    let main = f.trace(&task, 1);
    let plain: Vec<[f32; 4]> = bytemuck::cast_slice(&f.host.read_image(&demod, vk::ImageLayout::GENERAL).unwrap()).to_vec();
    let want = [0.45f32, 0.25, 0.05];
    let mut lit = 0;
    for (m, d) in main.iter().zip(&plain) {
        for c in 0..3 {
            assert!((m[c] - d[c] * want[c]).abs() <= 1e-5 * (1.0 + d[c]), "{m:?} vs {d:?}");
        }
        assert_eq!(m[3], d[3], "same hit distance");
        lit += (d[0] > 0.01) as usize;
    }
    assert!(lit > 100);
    f.host.destroy_image(spec);
    f.host.destroy_image(demod);
    f.finish();
}

/// Reflections off clear glass: a second specular task whose G-buffer is the glass pane's
/// own (the pane is not in the TLAS, as transparent geometry usually is not).
#[test]
fn a_glass_pane_reflects_from_its_own_gbuffer() {
    let mut f = fixture();
    // A horizontal pane 0.5 above the floor, seen from the fixture's camera.
    let mut pane = Scene::default();
    let quad = pane.add_mesh(Mesh::grid(3.0, 1));
    pane.add_instance(quad, Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)));
    let gp = GBuffer::render(&Tracer::new(&pane), &f.camera, W, H);
    let glass = GBufferImages::upload(&f.host, &gp).unwrap();
    let mut task = f.task(RoughnessInput { global_roughness: 0.0, ..Default::default() }, 1);
    task.common = glass.trace_common(&f.camera);
    task.common.roughness.global_roughness = 0.0;
    let gpu = f.trace(&task, 1);
    let offset = hybrid_rt::RayOffset::default();
    let (mut same, mut total) = (0, 0);
    for i in (0..gp.depth.len()).filter(|&i| gp.hit[i]) {
        let (p, n) = (gp.position[i], gp.normal[i]);
        let v = (f.camera.eye - p).normalize();
        let dir = (-v) - 2.0 * (-v).dot(n) * n;
        let want = f.radiance(offset_origin(p, n, f.camera.eye, &offset), dir);
        total += 1;
        same += (0..3).all(|c| (gpu[i][c] - want[c]).abs() < 1e-4) as usize;
    }
    eprintln!("glass: {same} of {total} pane pixels as the reference");
    assert!(total > 300 && same as f32 >= 0.98 * total as f32);
    glass.destroy(&f.host);
    f.finish();
}

/// The firefly clamp caps each sample's luminance.
#[test]
fn the_firefly_clamp_caps_sample_luminance() {
    let mut f = fixture();
    let mut task = f.task(RoughnessInput { global_roughness: 0.5, ..Default::default() }, 4);
    task.firefly_clamp = 0.05;
    let clamped = f.trace(&task, 1);
    let luminance = |c: &[f32; 4]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    // A mean of samples each at most 0.05 (times a lobe weight <= 1).
    assert!(clamped.iter().all(|c| luminance(c) <= 0.05 + 1e-5));
    task.firefly_clamp = 0.0;
    let free = f.trace(&task, 1);
    assert!(free.iter().any(|c| luminance(c) > 0.1), "without the clamp the walls are brighter");
    f.finish();
}
