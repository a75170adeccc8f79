//! Denoiser image quality, second generation (issue 12's CI thresholds): measured against the
//! SDK's own trace averaged over many frames (its converged reference).
//!
//! - Bias: the denoised GI and glossy reflections keep the mean of the frames they were made
//!   from within 1% per channel. (The first generation was 1.5-6% dark: its anti-firefly clamp
//!   cut every 1-ray sample to its brightest neighbour, and its half-float history rounded
//!   towards zero on drivers that may.)
mod common;
use ash::vk;
use common::*;
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostImage};
use hybrid_rt_testkit::reference::{self, Camera, GBuffer, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;

const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

/// A scene registered and built, its G-buffer uploaded, a noisy and a denoised image, a
/// denoising context: what every test here starts from.
struct Stage {
    host: Host,
    ctx: ExecuteContext,
    frame: TaskContainer,
    g: GBuffer,
    camera: Camera,
    images: GBufferImages,
    gpu_scene: SceneOnGpu,
    noisy: HostImage,
    den: HostImage,
    dn: DenoisingContextHandle,
    /// The frame index of the next build: it seeds every ray (`set_frame_index`).
    next_frame: u64,
}

/// Seeds (first frame indices) a measurement is repeated with. One realisation of 1-ray noise
/// moves these small-image figures by about a percent (the crease bias read -0.3% with one
/// seed and +1.9% with another), as much as the thresholds they are held to: each figure is
/// the mean over these.
const SEEDS: [u64; 4] = [0, 1 << 20, 2 << 20, 3 << 20];

impl Stage {
    /// `colours`: each instance's cache colour (None: black).
    fn new(scene: &Scene, colours: Option<&[[f32; 3]]>, camera: Camera, size: u32, signal: SignalType, seed: u64) -> Stage {
        let (host, ctx) = host_and_context(InitSettings::default());
        let g = GBuffer::render(&Tracer::new(scene), &camera, size, size);
        let images = GBufferImages::upload(&host, &g).unwrap();
        let mut frame = ctx.create_task_container();
        let black = vec![[0.0; 3]; scene.instances.len()];
        let gpu_scene =
            SceneOnGpu::register_coloured(&host, &ctx, &mut frame, scene, Default::default(), colours.unwrap_or(&black)).unwrap();
        frame.schedule_bvh_build(&Default::default()).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
        let rgba = || host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, size, size, usage, GENERAL).unwrap();
        let (noisy, den) = (rgba(), rgba());
        let dn = ctx
            .create_denoising_context(&DenoisingContextInput { max_width: size, max_height: size, signal, ..Default::default() })
            .unwrap();
        Stage { host, ctx, frame, g, camera, images, gpu_scene, noisy, den, dn, next_frame: seed }
    }

    fn trace_common(&self) -> TraceCommon {
        self.images.trace_common(&self.camera)
    }

    fn denoising_common(&self) -> DenoisingCommon {
        self.images.denoising_common(&self.camera)
    }

    fn run(&mut self) {
        self.frame.set_frame_index(self.next_frame);
        self.next_frame += 1;
        run_frame(&self.host, &self.ctx, &mut self.frame).unwrap();
    }

    fn read(&self, img: &HostImage) -> Vec<[f32; 4]> {
        bytemuck::cast_slice(&self.host.read_image(img, GENERAL).unwrap()).to_vec()
    }

    fn channel(&self, img: &HostImage, c: usize) -> Vec<f32> {
        self.read(img).iter().map(|t| t[c]).collect()
    }

    fn finish(self) {
        self.ctx.destroy_denoising_context(self.dn).unwrap();
        for i in [self.noisy, self.den] {
            self.host.destroy_image(i);
        }
        self.images.destroy(&self.host);
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
    }
}

/// Per channel: (denoised / mean of the same raw frames - 1, denoised / converged - 1), over
/// the surface pixels, after `frames` frames; the converged reference averages `converged`.
fn bias(signal: SignalType, frames: u32, converged: u32) -> [(f64, f64); 3] {
    const W: u32 = 48;
    let (scene, colours, camera) = reference::coloured_room(true);
    let mut st = Stage::new(&scene, Some(&colours), camera, W, signal, SEEDS[0]);
    let mut common = st.trace_common();
    common.roughness.global_roughness = 0.5;
    let mut dc = st.denoising_common();
    dc.roughness = common.roughness;
    let sky = [0.1, 0.2, 0.3];
    let (mut all, mut first) = (vec![[0.0f64; 3]; (W * W) as usize], vec![[0.0f64; 3]; (W * W) as usize]);
    let mut out = Vec::new();
    for f in 0..converged {
        let (input, output, context) = (st.noisy.input(GENERAL), st.den.input(GENERAL), st.dn);
        if signal == SignalType::Specular {
            let t = TraceSpecularTask { common, output: input, ray_length: 100.0, miss_radiance: sky, ..Default::default() };
            st.frame.schedule_specular(&t).unwrap();
            if f < frames {
                st.frame.schedule_denoise_specular(&DenoiseSpecularTask { context, common: dc, input, output }).unwrap();
            }
        } else {
            let t = TraceDiffuseTask { common, output: input, ray_length: 100.0, miss_radiance: sky, ..Default::default() };
            st.frame.schedule_diffuse(&t).unwrap();
            if f < frames {
                st.frame.schedule_denoise_diffuse(&DenoiseDiffuseTask { context, common: dc, input, output }).unwrap();
            }
        }
        st.run();
        for (i, x) in st.read(&st.noisy).iter().enumerate() {
            for c in 0..3 {
                all[i][c] += x[c] as f64 / converged as f64;
                if f < frames {
                    first[i][c] += x[c] as f64 / frames as f64;
                }
            }
        }
        if f + 1 == frames {
            out = st.read(&st.den);
        }
    }
    let mut result = [(0.0, 0.0); 3];
    for (c, r) in result.iter_mut().enumerate() {
        let (mut d, mut same, mut conv) = (0.0f64, 0.0f64, 0.0f64);
        for i in (0..all.len()).filter(|&i| st.g.hit[i]) {
            d += out[i][c] as f64;
            same += first[i][c];
            conv += all[i][c];
        }
        *r = (d / same - 1.0, d / conv - 1.0);
    }
    st.finish();
    result
}

/// Diffuse GI and glossy reflections (roughness 0.5) in the coloured room, 1 ray per pixel,
/// 32 frames denoised: the image mean per channel within 1% of the same 32 raw frames' mean.
/// Against the 256-frame converged reference the raw 32-frame mean itself is off by up to
/// ~0.4% (sampling noise of 2,000 pixels x 32 rays), so that comparison gets 1.5%.
#[test]
fn gi_and_glossy_reflections_keep_their_mean() {
    for (what, signal) in [("diffuse GI", SignalType::Diffuse), ("glossy reflections", SignalType::Specular)] {
        let b = bias(signal, 32, 256);
        for (c, (same, converged)) in b.iter().enumerate() {
            eprintln!(
                "{what}, channel {c}: denoised vs its 32 raw frames {:+.2}%, vs the 256-frame reference {:+.2}%",
                same * 100.0,
                converged * 100.0
            );
            assert!(same.abs() <= 0.01, "{what} channel {c}: bias {:.2}% against its own frames", same * 100.0);
            assert!(converged.abs() <= 0.015, "{what} channel {c}: bias {:.2}% against the reference", converged * 100.0);
        }
    }
}

/// An occlusion signal: AO, or a sun's shadow.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Occlusion {
    Ao,
    Shadow(LightInfo),
}

impl Occlusion {
    fn signal(self) -> SignalType {
        match self {
            Occlusion::Ao => SignalType::DiffuseOcclusion,
            Occlusion::Shadow(_) => SignalType::Shadow,
        }
    }

    /// Where the trace writes visibility (the shadow's visible fraction is G).
    fn channel(self) -> usize {
        if self == Occlusion::Ao {
            0
        } else {
            1
        }
    }

    /// One frame traced at `rays` per pixel into the stage's noisy image, denoised or not.
    fn frame(self, st: &mut Stage, rays: u32, denoise: bool) {
        let (common, dc) = (st.trace_common(), st.denoising_common());
        let (input, output, context) = (st.noisy.input(GENERAL), st.den.input(GENERAL), st.dn);
        match self {
            Occlusion::Ao => {
                let t = TraceAmbientOcclusionTask {
                    common,
                    output: input,
                    ray_length: 1.0,
                    rays_per_pixel: rays,
                    ..Default::default()
                };
                st.frame.schedule_ambient_occlusion(&t).unwrap();
                if denoise {
                    let d = DenoiseDiffuseOcclusionTask { context, common: dc, input, output };
                    st.frame.schedule_denoise_diffuse_occlusion(&d).unwrap();
                }
            }
            Occlusion::Shadow(light) => {
                let t = TraceShadowTask { common, light, output: input, rays_per_pixel: rays, ..Default::default() };
                st.frame.schedule_shadow(&t).unwrap();
                if denoise {
                    st.frame.schedule_denoise_shadow(&DenoiseShadowTask { context, common: dc, light, input, output }).unwrap();
                }
            }
        }
        st.run();
    }

    /// The converged visibility: `frames` frames of 64 rays per pixel.
    fn converged(self, st: &mut Stage, frames: u32) -> Vec<f32> {
        let mut r = vec![0.0f32; st.g.depth.len()];
        for _ in 0..frames {
            self.frame(st, 64, false);
            for (r, v) in r.iter_mut().zip(st.channel(&st.noisy, self.channel())) {
                *r += v / frames as f32;
            }
        }
        r
    }
}

/// A sphere on a plane, 24 frames at x = -0.6, then moved to x = +0.9 for 12 frames: per frame
/// after the move, how much of the old contact AO (or shadow) the denoised image keeps where
/// the floor was occluded and now is open — (denoised - new) / (old - new), averaged over
/// that region; references: the SDK's own trace at 64 rays per pixel.
fn moving_object_residual(signal: Occlusion, seed: u64) -> Vec<f32> {
    use glam::{Affine3A, Vec3};
    const S: u32 = 64;
    let (mut scene, camera) = reference::sphere_on_plane();
    let at = |x: f32| Affine3A::from_translation(Vec3::new(x, 0.5, 0.0));
    scene.instances[1].transform = at(-0.6);
    let mut moved = scene.clone();
    moved.instances[1].transform = at(0.9);
    let gb = GBuffer::render(&Tracer::new(&moved), &camera, S, S);
    let mut st = Stage::new(&scene, None, camera, S, signal.signal(), seed);
    let old = signal.converged(&mut st, 1);
    for _ in 0..24 {
        signal.frame(&mut st, 1, true);
    }
    // The move: the instance, the TLAS, the G-buffer.
    let (handle, geometry) = (st.gpu_scene.instances[1], st.gpu_scene.geometries[1]);
    let input = InstanceInput { geometry, transform: at(0.9), ..Default::default() };
    st.frame.schedule_instance(&InstanceTask { handle, operation: InstanceOperation::Update, input }).unwrap();
    st.frame.schedule_bvh_build(&Default::default()).unwrap();
    st.run();
    let read_only = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    st.host.write_image(&st.images.depth, &gb.depth_bytes(), read_only).unwrap();
    st.host.write_image(&st.images.normals, &gb.normal_bytes_rgba32f(), read_only).unwrap();
    let new = signal.converged(&mut st, 1);
    let ga = &st.g;
    let region: Vec<usize> = (0..old.len())
        .filter(|&i| ga.hit[i] && gb.hit[i] && ga.instance[i] == 0 && gb.instance[i] == 0 && new[i] - old[i] > 0.25)
        .collect();
    assert!(region.len() > 30, "the move uncovers floor that was occluded ({} px)", region.len());
    let mut residual = Vec::new();
    for _ in 0..12 {
        signal.frame(&mut st, 1, true);
        // The shadow denoiser writes visibility in every channel; AO too.
        let d = st.channel(&st.den, 0);
        let (num, den): (f32, f32) =
            region.iter().map(|&i| (d[i] - new[i], old[i] - new[i])).fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        residual.push(num / den);
    }
    st.finish();
    residual
}

/// When an object moves away, its old contact AO and shadow leave the denoised image: at most
/// 10% of the old occlusion remains 4 frames later (the first generation kept 62%).
#[test]
fn a_moving_object_leaves_no_old_occlusion_behind() {
    let sun = LightInfo { direction: glam::Vec3::new(0.4, -1.0, -0.3), angular_extent: 0.1, ..Default::default() };
    for signal in [Occlusion::Ao, Occlusion::Shadow(sun)] {
        let r = mean_over_seeds(|k| moving_object_residual(signal, SEEDS[k as usize]));
        let shown: Vec<String> = r.iter().map(|v| format!("{:.0}%", v * 100.0)).collect();
        let name = if signal == Occlusion::Ao { "AO" } else { "shadow" };
        eprintln!("{name}: old occlusion kept, frames 1-12 after the move: {}", shown.join(" "));
        assert!(r[3] <= 0.10, "{name}: {:.0}% of the old occlusion kept 4 frames after the move", r[3] * 100.0);
    }
}

/// Mean absolute error of the raw last frame and of the denoised image against the converged
/// trace, per region of the converged shadow: (umbra < 0.02, lit > 0.98, penumbra between).
fn shadow_regions(angular_extent: f32, seed: u64) -> [(f32, f32, usize); 3] {
    const S: u32 = 64;
    let (scene, camera) = reference::sphere_on_plane();
    let sun = Occlusion::Shadow(LightInfo { direction: glam::Vec3::new(-0.5, -1.0, -0.3), angular_extent, ..Default::default() });
    let mut st = Stage::new(&scene, None, camera, S, SignalType::Shadow, seed);
    let reference = sun.converged(&mut st, 4);
    for _ in 0..32 {
        sun.frame(&mut st, 1, true);
    }
    let (raw, out) = (st.channel(&st.noisy, 1), st.channel(&st.den, 0));
    let mut regions = [(0.0f32, 0.0f32, 0usize); 3];
    for i in (0..reference.len()).filter(|&i| st.g.hit[i]) {
        let k = if reference[i] < 0.02 {
            0
        } else if reference[i] > 0.98 {
            1
        } else {
            2
        };
        regions[k].0 += (raw[i] - reference[i]).abs();
        regions[k].1 += (out[i] - reference[i]).abs();
        regions[k].2 += 1;
    }
    for r in regions.iter_mut() {
        r.0 /= r.2.max(1) as f32;
        r.1 /= r.2.max(1) as f32;
    }
    st.finish();
    regions
}

/// The sample's sun (0.03 rad) and a soft one (0.2 rad): after 32 frames the denoised shadow
/// is no worse than one raw frame in the umbra, in the light and in the penumbra.
#[test]
fn denoised_shadows_are_never_worse_than_a_raw_frame() {
    for extent in [0.03f32, 0.2] {
        let per_seed: Vec<_> = SEEDS.iter().map(|&s| shadow_regions(extent, s)).collect();
        for (k, name) in ["umbra", "lit", "penumbra"].iter().enumerate() {
            let mean = |f: fn(&(f32, f32, usize)) -> f32| per_seed.iter().map(|r| f(&r[k])).sum::<f32>() / SEEDS.len() as f32;
            let (raw, den, n) = (mean(|r| r.0), mean(|r| r.1), per_seed[0][k].2);
            eprintln!("sun {extent} rad, {name} ({n} px): mean |error| raw {raw:.4}, denoised {den:.4}");
            if n > 0 {
                assert!(den <= raw + 0.005, "sun {extent}: the denoised {name} is worse than a raw frame ({den} vs {raw})");
            }
        }
    }
}

/// Creases (where the room's walls meet its floor and ceiling): the denoised AO after 32
/// frames is not brighter than the converged trace by more than 1% there (before the crease
/// rule of denoise_atrous.comp the spatial filter lifted them by 6%).
#[test]
fn creases_keep_their_occlusion() {
    let per_seed: Vec<[f64; 3]> = SEEDS.iter().map(|&s| crease_bias(s)).collect();
    let [bias, vs_raw, pixels] = mean_over_seeds(|k| per_seed[k as usize].to_vec()).try_into().unwrap();
    eprintln!(
        "creases ({pixels:.0} px, converged AO < 0.75): denoised {:+.2}% against the converged trace, {:+.2}% against its 32 raw frames",
        bias * 100.0,
        vs_raw * 100.0
    );
    assert!(pixels > 100.0, "the room has creases ({pixels} px)");
    assert!(bias <= 0.01, "creases come out {:.2}% brighter than converged", bias * 100.0);
    assert!(vs_raw <= 0.01, "creases come out {:.2}% brighter than their frames", vs_raw * 100.0);
}

/// The mean, element by element, of `f(k)` for k = 0..SEEDS.len() (f(k) uses SEEDS[k] or
/// results made with it).
fn mean_over_seeds<T: Into<f64> + Copy>(mut f: impl FnMut(u64) -> Vec<T>) -> Vec<f64> {
    let runs: Vec<Vec<T>> = (0..SEEDS.len() as u64).map(&mut f).collect();
    (0..runs[0].len()).map(|i| runs.iter().map(|r| r[i].into()).sum::<f64>() / runs.len() as f64).collect()
}

/// The crease AO of the coloured room after 32 denoised 1-ray frames: (denoised / converged -
/// 1, denoised / the mean of its raw frames - 1, crease pixels), summed over the creases.
fn crease_bias(seed: u64) -> [f64; 3] {
    const S: u32 = 64;
    let (scene, _, camera) = reference::coloured_room(true);
    let mut st = Stage::new(&scene, None, camera, S, SignalType::DiffuseOcclusion, seed);
    // Two independent converged traces: one picks the crease pixels, the other is the
    // reference there (picking by the reference itself would favour pixels where its own noise
    // is low, and make any estimate look bright).
    let (selector, reference) = (Occlusion::Ao.converged(&mut st, 4), Occlusion::Ao.converged(&mut st, 4));
    let mut raw_mean = vec![0.0f32; reference.len()];
    for _ in 0..32 {
        Occlusion::Ao.frame(&mut st, 1, true);
        for (r, v) in raw_mean.iter_mut().zip(st.channel(&st.noisy, 0)) {
            *r += v / 32.0;
        }
    }
    let out = st.channel(&st.den, 0);
    let crease: Vec<usize> = (0..reference.len()).filter(|&i| st.g.hit[i] && selector[i] < 0.75).collect();
    let sum = |v: &[f32]| crease.iter().map(|&i| v[i] as f64).sum::<f64>();
    let (sum_d, sum_r, sum_raw) = (sum(&out), sum(&reference), sum(&raw_mean));
    let n = crease.len() as f64;
    st.finish();
    [sum_d / sum_r - 1.0, sum_d / sum_raw - 1.0, n]
}

/// The sky brightens 5x after 24 frames (a light switched on): per frame after the change, how
/// much of the old GI the denoised image keeps — (denoised - new) / (old - new) over the
/// surfaces, references at 64 rays per pixel.
fn gi_switch_residual(seed: u64) -> Vec<f32> {
    const S: u32 = 48;
    let (scene, colours, camera) = reference::coloured_room(true);
    let mut st = Stage::new(&scene, Some(&colours), camera, S, SignalType::Diffuse, seed);
    let trace = |st: &mut Stage, sky: [f32; 3], rays: u32, denoise: bool| {
        let (common, dc) = (st.trace_common(), st.denoising_common());
        let (input, output, context) = (st.noisy.input(GENERAL), st.den.input(GENERAL), st.dn);
        let t = TraceDiffuseTask {
            common,
            output: input,
            rays_per_pixel: rays,
            ray_length: 100.0,
            miss_radiance: sky,
            ..Default::default()
        };
        st.frame.schedule_diffuse(&t).unwrap();
        if denoise {
            st.frame.schedule_denoise_diffuse(&DenoiseDiffuseTask { context, common: dc, input, output }).unwrap();
        }
        st.run();
    };
    let (dim, bright) = ([0.2, 0.2, 0.2], [1.0, 1.0, 1.0]);
    trace(&mut st, dim, 64, false);
    let old = st.channel(&st.noisy, 1);
    trace(&mut st, bright, 64, false);
    let new = st.channel(&st.noisy, 1);
    for _ in 0..24 {
        trace(&mut st, dim, 1, true);
    }
    let region: Vec<usize> = (0..old.len()).filter(|&i| st.g.hit[i] && new[i] - old[i] > 0.05).collect();
    assert!(region.len() > 100, "the sky lights the room ({} px)", region.len());
    let mut residual = Vec::new();
    for _ in 0..12 {
        trace(&mut st, bright, 1, true);
        let d = st.channel(&st.den, 1);
        let (num, den): (f32, f32) =
            region.iter().map(|&i| (new[i] - d[i], new[i] - old[i])).fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        residual.push(num / den);
    }
    st.finish();
    residual
}

/// How fast denoised GI follows a light switched on. The first generation kept 87% of the old
/// lighting 4 frames later and 66% after 12; the anti-lag test (now on GI too) brings that to
/// 55% and 29% — the change is small against 1-ray noise in this room, where the sky is seen
/// by few rays. (No threshold in the issue; bounded here against regressions.)
#[test]
fn gi_follows_a_light_switched_on() {
    let r = mean_over_seeds(|k| gi_switch_residual(SEEDS[k as usize]));
    let shown: Vec<String> = r.iter().map(|v| format!("{:.0}%", v * 100.0)).collect();
    eprintln!("GI: old lighting kept, frames 1-12 after the sky brightened: {}", shown.join(" "));
    assert!(r[3] <= 0.65 && r[11] <= 0.35, "the old lighting lingers: {shown:?}");
}
