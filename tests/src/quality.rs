//! Denoiser image quality, measured against the SDK's own trace averaged over many frames (its
//! converged reference): the measurements behind the denoisers' CI thresholds
//! (tests/tests/denoise_quality.rs) and the `quality` program's table (docs/benchmarks.md).
//!
//! A [`Stage`] is a reference scene registered and built, its G-buffer uploaded, a noisy and a
//! denoised image and a denoising context; a [`Signal`] traces one kind of ray into it. Each
//! measurement runs on a fresh stage whose frame indices start at a seed: one realisation of
//! 1-ray noise moves these small-image figures by about a percent, so callers average over
//! [`SEEDS`].
use crate::host::{Host, HostImage};
use crate::reference::{self, Camera, GBuffer, Scene, Tracer};
use crate::sdk_scene::*;
use ash::vk;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;

pub const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

/// Seeds (first frame indices) a measurement is repeated with. (The crease bias read -0.3%
/// with one seed and +1.9% with another, as far apart as the thresholds they are held to.)
pub const SEEDS: [u64; 4] = [0, 1 << 20, 2 << 20, 3 << 20];

thread_local! {
    static HOST: std::rc::Rc<Host> =
        std::rc::Rc::new(Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)"));
}

/// One host (instance and device) per thread, for all its stages: each stage still makes its
/// own `ExecuteContext`. NVIDIA's driver (580) refuses vkCreateInstance with
/// INCOMPATIBLE_DRIVER after a few dozen instances in one process, which these measurements
/// (a fresh stage per seed) reached.
fn thread_host() -> std::rc::Rc<Host> {
    HOST.with(|h| h.clone())
}

/// A scene on the GPU with a G-buffer, noisy and denoised images, a denoising context.
pub struct Stage {
    /// This thread's host, shared by its stages (see `thread_host`).
    pub host: std::rc::Rc<Host>,
    pub ctx: ExecuteContext,
    pub frame: TaskContainer,
    pub g: GBuffer,
    pub camera: Camera,
    pub images: GBufferImages,
    pub gpu_scene: SceneOnGpu,
    pub noisy: HostImage,
    pub den: HostImage,
    pub dn: DenoisingContextHandle,
    /// The frame index of the next build: it seeds every ray (`set_frame_index`).
    pub next_frame: u64,
    /// Trace and denoise in checkerboard mode (`half_resolution_mode`). Default false.
    pub half_resolution: bool,
    /// The denoise tasks' settings. Default: the SDK's.
    pub settings: DenoiserSettings,
}

impl Stage {
    /// `colours`: each instance's cache colour (None: black). Panics where the device fails:
    /// a measurement without a device has nothing to say.
    pub fn new(scene: &Scene, colours: Option<&[[f32; 3]]>, camera: Camera, size: u32, signal: SignalType, seed: u64) -> Stage {
        let host = thread_host();
        let ctx = host.create_context(&InitSettings::default()).expect("context");
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
        let (next_frame, half_resolution, settings) = (seed, false, DenoiserSettings::default());
        Stage { host, ctx, frame, g, camera, images, gpu_scene, noisy, den, dn, next_frame, half_resolution, settings }
    }

    /// Replaces the denoising context with a fresh one of `method` (same signal and size).
    pub fn use_method(&mut self, method: DenoisingMethod, signal: SignalType) {
        self.ctx.destroy_denoising_context(self.dn).unwrap();
        let (w, h) = (self.g.width, self.g.height);
        let input = DenoisingContextInput { max_width: w, max_height: h, signal, method, ..Default::default() };
        self.dn = self.ctx.create_denoising_context(&input).unwrap();
    }

    pub fn trace_common(&self) -> TraceCommon {
        self.images.trace_common(&self.camera)
    }

    pub fn denoising_common(&self) -> DenoisingCommon {
        DenoisingCommon { settings: self.settings, ..self.images.denoising_common(&self.camera) }
    }

    /// Builds and runs the scheduled tasks as the next frame.
    pub fn run(&mut self) {
        self.frame.set_frame_index(self.next_frame);
        self.next_frame += 1;
        run_frame(&self.host, &self.ctx, &mut self.frame).unwrap();
    }

    pub fn read(&self, img: &HostImage) -> Vec<[f32; 4]> {
        bytemuck::cast_slice(&self.host.read_image(img, GENERAL).unwrap()).to_vec()
    }

    pub fn channel(&self, img: &HostImage, c: usize) -> Vec<f32> {
        self.read(img).iter().map(|t| t[c]).collect()
    }

    /// Moves the camera: a new G-buffer from the CPU tracer, uploaded in place (the denoiser
    /// reprojects with the previous frame's camera).
    pub fn move_camera(&mut self, scene: &Scene, camera: Camera) {
        let (w, h) = (self.g.width, self.g.height);
        self.g = GBuffer::render(&Tracer::new(scene), &camera, w, h);
        self.camera = camera;
        self.host.write_image(&self.images.depth, &self.g.depth_bytes(), READ).unwrap();
        self.host.write_image(&self.images.normals, &self.g.normal_bytes_rgba32f(), READ).unwrap();
    }

    /// Destroys what the stage made; the caller checks the validation layer's findings.
    pub fn finish(self) {
        let Stage { host, ctx, dn, noisy, den, images, gpu_scene, .. } = self;
        ctx.destroy_denoising_context(dn).unwrap();
        for i in [noisy, den] {
            host.destroy_image(i);
        }
        images.destroy(&host);
        gpu_scene.destroy(&host);
        // The context before the device it was made on (which this thread keeps).
        drop(ctx);
        drop(host);
    }
}

/// What is traced and denoised.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Signal {
    /// Ambient occlusion, 1 m rays.
    Ao,
    /// One light's shadow.
    Shadow(LightInfo),
    /// Diffuse GI from the instances' cache colours and a uniform sky.
    Diffuse { sky: [f32; 3] },
    /// Reflections at a global roughness, under a uniform sky.
    Specular { sky: [f32; 3], roughness: f32 },
}

impl Signal {
    pub fn signal_type(self) -> SignalType {
        match self {
            Signal::Ao => SignalType::DiffuseOcclusion,
            Signal::Shadow(_) => SignalType::Shadow,
            Signal::Diffuse { .. } => SignalType::Diffuse,
            Signal::Specular { .. } => SignalType::Specular,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Signal::Ao => "AO",
            Signal::Shadow(_) => "shadow",
            Signal::Diffuse { .. } => "diffuse GI",
            Signal::Specular { .. } => "glossy reflections",
        }
    }

    /// One frame traced at `rays` per pixel into the stage's noisy image, denoised or not.
    pub fn frame(self, st: &mut Stage, rays: u32, denoise: bool) {
        let (mut common, mut dc) = (st.trace_common(), st.denoising_common());
        let mode = if st.half_resolution { HalfResolutionMode::Checkerboard } else { HalfResolutionMode::Off };
        common.half_resolution_mode = mode;
        dc.half_resolution_mode = mode;
        let (input, output, context) = (st.noisy.input(GENERAL), st.den.input(GENERAL), st.dn);
        let f = &mut st.frame;
        match self {
            Signal::Ao => {
                let t = TraceAmbientOcclusionTask {
                    common,
                    output: input,
                    ray_length: 1.0,
                    rays_per_pixel: rays,
                    ..Default::default()
                };
                f.schedule_ambient_occlusion(&t).unwrap();
                if denoise {
                    f.schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask { context, common: dc, input, output })
                        .unwrap();
                }
            }
            Signal::Shadow(light) => {
                f.schedule_shadow(&TraceShadowTask { common, light, output: input, rays_per_pixel: rays, ..Default::default() })
                    .unwrap();
                if denoise {
                    f.schedule_denoise_shadow(&DenoiseShadowTask { context, common: dc, light, input, output }).unwrap();
                }
            }
            Signal::Diffuse { sky } => {
                let t = TraceDiffuseTask {
                    common,
                    output: input,
                    rays_per_pixel: rays,
                    ray_length: 100.0,
                    miss_radiance: sky,
                    ..Default::default()
                };
                f.schedule_diffuse(&t).unwrap();
                if denoise {
                    f.schedule_denoise_diffuse(&DenoiseDiffuseTask { context, common: dc, input, output }).unwrap();
                }
            }
            Signal::Specular { sky, roughness } => {
                common.roughness.global_roughness = roughness;
                dc.roughness = common.roughness;
                let t = TraceSpecularTask {
                    common,
                    output: input,
                    rays_per_pixel: rays,
                    ray_length: 100.0,
                    miss_radiance: sky,
                    ..Default::default()
                };
                f.schedule_specular(&t).unwrap();
                if denoise {
                    f.schedule_denoise_specular(&DenoiseSpecularTask { context, common: dc, input, output }).unwrap();
                }
            }
        }
        st.run();
    }

    /// This frame's traced signal, RGB per pixel (occlusion: its visibility in every channel).
    pub fn noisy(self, st: &Stage) -> Vec<[f32; 3]> {
        // AO writes visibility to R, the shadow trace its visible fraction to G.
        let c = if matches!(self, Signal::Shadow(_)) { 1 } else { 0 };
        st.read(&st.noisy)
            .iter()
            .map(|t| if matches!(self, Signal::Ao | Signal::Shadow(_)) { [t[c]; 3] } else { [t[0], t[1], t[2]] })
            .collect()
    }

    /// The denoised image, RGB per pixel (the occlusion denoisers write every channel).
    pub fn denoised(self, st: &Stage) -> Vec<[f32; 3]> {
        st.read(&st.den).iter().map(|t| [t[0], t[1], t[2]]).collect()
    }

    /// The converged signal: `frames` frames of 64 rays per pixel.
    pub fn converged(self, st: &mut Stage, frames: u32) -> Vec<[f32; 3]> {
        let mut r = vec![[0.0f32; 3]; st.g.depth.len()];
        for _ in 0..frames {
            self.frame(st, 64, false);
            for (r, v) in r.iter_mut().zip(self.noisy(st)) {
                for c in 0..3 {
                    r[c] += v[c] / frames as f32;
                }
            }
        }
        r
    }
}

/// Relative RMSE of `x` against `reference` over the pixels of `mask`, all channels.
pub fn relative_rmse(x: &[[f32; 3]], reference: &[[f32; 3]], mask: &[bool]) -> f64 {
    let flat = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    let mask3: Vec<bool> = mask.iter().flat_map(|m| [*m; 3]).collect();
    crate::stats::relative_rmse(&flat(x), &flat(reference), &mask3) as f64
}

/// Sum over the pixels of `mask`, per channel.
fn channel_sums(x: &[[f32; 3]], mask: &[bool]) -> [f64; 3] {
    let mut s = [0.0; 3];
    for (v, _) in x.iter().zip(mask).filter(|(_, m)| **m) {
        for c in 0..3 {
            s[c] += v[c] as f64;
        }
    }
    s
}

/// The mean, element by element, of `f(seed)` over [`SEEDS`].
pub fn mean_over_seeds<T: Into<f64> + Copy>(mut f: impl FnMut(u64) -> Vec<T>) -> Vec<f64> {
    let runs: Vec<Vec<T>> = SEEDS.iter().map(|&s| f(s)).collect();
    (0..runs[0].len()).map(|i| runs.iter().map(|r| r[i].into()).sum::<f64>() / runs.len() as f64).collect()
}

/// The coloured room with a ceiling: the scene of the bias, crease and GI measurements.
pub fn room() -> (Scene, Vec<[f32; 3]>, Camera) {
    reference::coloured_room(true)
}

/// Per channel: (denoised / mean of the same raw frames - 1, denoised / converged - 1), over
/// the surface pixels of the coloured room, after `frames` frames; the converged reference
/// averages `converged` raw frames.
pub fn bias(signal: Signal, frames: u32, converged: u32, seed: u64) -> [(f64, f64); 3] {
    let (scene, colours, camera) = room();
    bias_in((&scene, &colours, camera), signal, frames, converged, seed)
}

/// `bias` on another scene: its instances' cache colours and camera.
pub fn bias_in(
    (scene, colours, camera): (&Scene, &[[f32; 3]], Camera),
    signal: Signal,
    frames: u32,
    converged: u32,
    seed: u64,
) -> [(f64, f64); 3] {
    const W: u32 = 48;
    let mut st = Stage::new(scene, Some(colours), camera, W, signal.signal_type(), seed);
    let n = (W * W) as usize;
    let (mut all, mut first) = (vec![[0.0f32; 3]; n], vec![[0.0f32; 3]; n]);
    let mut out = Vec::new();
    for f in 0..converged {
        signal.frame(&mut st, 1, f < frames);
        for (i, x) in signal.noisy(&st).iter().enumerate() {
            for c in 0..3 {
                all[i][c] += x[c] / converged as f32;
                if f < frames {
                    first[i][c] += x[c] / frames as f32;
                }
            }
        }
        if f + 1 == frames {
            out = signal.denoised(&st);
        }
    }
    let (d, same, conv) = (channel_sums(&out, &st.g.hit), channel_sums(&first, &st.g.hit), channel_sums(&all, &st.g.hit));
    st.finish();
    [0, 1, 2].map(|c| (d[c] / same[c] - 1.0, d[c] / conv[c] - 1.0))
}

/// A sphere on a plane, 24 frames at x = -0.6, then moved to x = +0.9 for 12 frames: per frame
/// after the move, how much of the old contact AO (or shadow) the denoised image keeps where
/// the floor was occluded and now is open — (denoised - new) / (old - new), averaged over
/// that region; references: the SDK's own trace at 64 rays per pixel.
pub fn moving_object_residual(signal: Signal, seed: u64) -> Vec<f32> {
    const S: u32 = 64;
    let (mut scene, camera) = reference::sphere_on_plane();
    let at = |x: f32| Affine3A::from_translation(Vec3::new(x, 0.5, 0.0));
    scene.instances[1].transform = at(-0.6);
    let mut moved = scene.clone();
    moved.instances[1].transform = at(0.9);
    let gb = GBuffer::render(&Tracer::new(&moved), &camera, S, S);
    let mut st = Stage::new(&scene, None, camera, S, signal.signal_type(), seed);
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
    st.host.write_image(&st.images.depth, &gb.depth_bytes(), READ).unwrap();
    st.host.write_image(&st.images.normals, &gb.normal_bytes_rgba32f(), READ).unwrap();
    let new = signal.converged(&mut st, 1);
    let ga = &st.g;
    let region: Vec<usize> = (0..old.len())
        .filter(|&i| ga.hit[i] && gb.hit[i] && ga.instance[i] == 0 && gb.instance[i] == 0 && new[i][0] - old[i][0] > 0.25)
        .collect();
    assert!(region.len() > 30, "the move uncovers floor that was occluded ({} px)", region.len());
    let residual = old_share_kept(&mut st, signal, &region, (&old, &new), 0);
    st.finish();
    residual
}

/// An object sliding over a static floor: a 0.4 m cube on the plane of
/// [`reference::sphere_on_plane`], moving 2.6 pixels a frame (at 64x64) after 16 still
/// frames. After 12 frames of sliding, for each `lag` frames back: the share of the change
/// between the converged image `lag` frames ago and now that the denoised image still misses,
/// over the floor pixels whose converged value changed by more than 0.2 (each pixel's shortfall
/// counted in the direction of its change) — 1 while the old contact AO or shadow lingers, 0
/// once the image has caught up. Then, last, the price: the mean absolute error of the denoised
/// image against the converged one over the changed pixels of the first lag. `settings`: the
/// denoise tasks'.
pub fn sliding_object_residual(signal: Signal, seed: u64, lags: &[usize], settings: DenoiserSettings) -> Vec<f32> {
    const S: u32 = 64;
    const STILL: usize = 16;
    const SLIDING: usize = 12;
    // 2.6 px a frame: the camera sees ~3 m across 64 px at the cube's distance (60° fov).
    const STEP: f32 = 0.12;
    let (mut scene, camera) = reference::sphere_on_plane();
    let cube = scene.add_mesh(reference::Mesh::cuboid(Vec3::splat(0.2)));
    scene.instances[1].transform = Affine3A::from_translation(Vec3::new(0.0, -10.0, 0.0)); // the sphere, out of sight
    let at = |k: usize| Affine3A::from_translation(Vec3::new(-0.8 + STEP * k as f32, 0.2, 0.3));
    scene.add_instance(cube, at(0));
    let mut st = Stage::new(&scene, None, camera, S, signal.signal_type(), seed);
    st.settings = settings;
    // Moves the cube to its place in frame k: instance, TLAS, G-buffer; returns that G-buffer.
    let place = |st: &mut Stage, k: usize| -> GBuffer {
        let mut moved = scene.clone();
        moved.instances[2].transform = at(k);
        let gb = GBuffer::render(&Tracer::new(&moved), &camera, S, S);
        let (handle, geometry) = (st.gpu_scene.instances[2], st.gpu_scene.geometries[2]);
        let input = InstanceInput { geometry, transform: at(k), ..Default::default() };
        st.frame.schedule_instance(&InstanceTask { handle, operation: InstanceOperation::Update, input }).unwrap();
        st.frame.schedule_bvh_build(&Default::default()).unwrap();
        st.run();
        st.host.write_image(&st.images.depth, &gb.depth_bytes(), READ).unwrap();
        st.host.write_image(&st.images.normals, &gb.normal_bytes_rgba32f(), READ).unwrap();
        st.g = gb.clone();
        gb
    };
    for _ in 0..STILL {
        signal.frame(&mut st, 1, true);
    }
    let mut last = st.g.clone();
    for k in 1..=SLIDING {
        last = place(&mut st, k);
        signal.frame(&mut st, 1, true);
    }
    let denoised = signal.denoised(&st);
    let new = signal.converged(&mut st, 4);
    let mut error = None;
    let mut residuals: Vec<f32> = lags
        .iter()
        .map(|&lag| {
            let then = place(&mut st, SLIDING - lag);
            let old = signal.converged(&mut st, 4);
            let (mut num, mut den, mut abs, mut n) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
            for i in 0..old.len() {
                let change = new[i][0] - old[i][0];
                let floor = last.hit[i] && then.hit[i] && last.instance[i] == 0 && then.instance[i] == 0;
                if floor && change.abs() > 0.2 {
                    num += (new[i][0] - denoised[i][0]) * change.signum();
                    den += change.abs();
                    abs += (new[i][0] - denoised[i][0]).abs();
                    n += 1.0;
                }
            }
            assert!(den > 0.0, "the sliding cube changes some floor pixels by more than 0.2");
            error.get_or_insert(abs / n);
            num / den
        })
        .collect();
    residuals.extend(error);
    st.finish();
    residuals
}

/// Per frame of 12 denoised 1-ray frames of `signal`, how much of the change from `old` to
/// `new` (converged images) is still missing over `region`, channel `c`: (new - denoised) /
/// (new - old), summed over the region — 1 while the old image lingers, 0 once it is gone.
fn old_share_kept(
    st: &mut Stage,
    signal: Signal,
    region: &[usize],
    (old, new): (&[[f32; 3]], &[[f32; 3]]),
    c: usize,
) -> Vec<f32> {
    (0..12)
        .map(|_| {
            signal.frame(st, 1, true);
            let d = signal.denoised(st);
            let (num, den) =
                region.iter().fold((0.0f32, 0.0f32), |a, &i| (a.0 + new[i][c] - d[i][c], a.1 + new[i][c] - old[i][c]));
            num / den
        })
        .collect()
}

/// The penumbra regions of a shadow: umbra (converged < 0.02), lit (> 0.98), penumbra between.
pub const REGIONS: [&str; 3] = ["umbra", "lit", "penumbra"];

/// Mean absolute error of the raw last frame and of the denoised image against the converged
/// trace after 32 frames, per region of the converged shadow of a sun of `angular_extent` over
/// a sphere on a plane: (raw, denoised, pixels). `pan`: metres the camera moves sideways each
/// frame (0: still; 0.013 is about a quarter of a pixel, so every frame's history is
/// resampled between texels).
pub fn shadow_regions(angular_extent: f32, pan: f32, seed: u64) -> [(f32, f32, usize); 3] {
    const S: u32 = 64;
    let (scene, camera) = reference::sphere_on_plane();
    let sun = Signal::Shadow(LightInfo { direction: Vec3::new(-0.5, -1.0, -0.3), angular_extent, ..Default::default() });
    let mut st = Stage::new(&scene, None, camera, S, SignalType::Shadow, seed);
    for f in 0..32 {
        if pan != 0.0 {
            let shift = Vec3::new(pan * f as f32, 0.0, 0.0);
            st.move_camera(&scene, Camera { eye: camera.eye + shift, target: camera.target + shift, ..camera });
        }
        sun.frame(&mut st, 1, true);
    }
    let (raw, out) = (sun.noisy(&st), sun.denoised(&st));
    let reference = sun.converged(&mut st, 4);
    let mut regions = [(0.0f32, 0.0f32, 0usize); 3];
    for i in (0..reference.len()).filter(|&i| st.g.hit[i]) {
        let r = reference[i][0];
        let k = if r < 0.02 {
            0
        } else if r > 0.98 {
            1
        } else {
            2
        };
        regions[k].0 += (raw[i][0] - r).abs();
        regions[k].1 += (out[i][0] - r).abs();
        regions[k].2 += 1;
    }
    for r in regions.iter_mut() {
        r.0 /= r.2.max(1) as f32;
        r.1 /= r.2.max(1) as f32;
    }
    st.finish();
    regions
}

/// The crease AO of the coloured room after 32 denoised 1-ray frames: (denoised / converged -
/// 1, denoised / the mean of its raw frames - 1, crease pixels), summed over the creases
/// (converged AO < 0.75).
pub fn crease_bias(seed: u64) -> [f64; 3] {
    const S: u32 = 64;
    let (scene, _, camera) = room();
    let mut st = Stage::new(&scene, None, camera, S, SignalType::DiffuseOcclusion, seed);
    // Two independent converged traces: one picks the crease pixels, the other is the
    // reference there (picking by the reference itself would favour pixels where its own noise
    // is low, and make any estimate look bright).
    let (selector, reference) = (Signal::Ao.converged(&mut st, 4), Signal::Ao.converged(&mut st, 4));
    let mut raw_mean = vec![0.0f32; reference.len()];
    for _ in 0..32 {
        Signal::Ao.frame(&mut st, 1, true);
        for (r, v) in raw_mean.iter_mut().zip(Signal::Ao.noisy(&st)) {
            *r += v[0] / 32.0;
        }
    }
    let out = Signal::Ao.denoised(&st);
    let crease: Vec<usize> = (0..reference.len()).filter(|&i| st.g.hit[i] && selector[i][0] < 0.75).collect();
    let sum = |f: &dyn Fn(usize) -> f32| crease.iter().map(|&i| f(i) as f64).sum::<f64>();
    let (sum_d, sum_r, sum_raw) = (sum(&|i| out[i][0]), sum(&|i| reference[i][0]), sum(&|i| raw_mean[i]));
    let n = crease.len() as f64;
    st.finish();
    [sum_d / sum_r - 1.0, sum_d / sum_raw - 1.0, n]
}

/// The sky brightens 5x after 24 frames (a light switched on): per frame after the change, how
/// much of the old GI the denoised image keeps — (new - denoised) / (new - old) over the
/// surfaces, green channel, references at 64 rays per pixel.
pub fn gi_switch_residual(seed: u64) -> Vec<f32> {
    const S: u32 = 48;
    let (scene, colours, camera) = room();
    let (dim, bright) = (Signal::Diffuse { sky: [0.2; 3] }, Signal::Diffuse { sky: [1.0; 3] });
    let mut st = Stage::new(&scene, Some(&colours), camera, S, SignalType::Diffuse, seed);
    dim.frame(&mut st, 64, false);
    let old = dim.noisy(&st);
    bright.frame(&mut st, 64, false);
    let new = bright.noisy(&st);
    for _ in 0..24 {
        dim.frame(&mut st, 1, true);
    }
    let region: Vec<usize> = (0..old.len()).filter(|&i| st.g.hit[i] && new[i][1] - old[i][1] > 0.05).collect();
    assert!(region.len() > 100, "the sky lights the room ({} px)", region.len());
    let residual = old_share_kept(&mut st, bright, &region, (&old, &new), 1);
    st.finish();
    residual
}

/// A signal's convergence on a static view: relative RMSE of the raw frame and of the denoised
/// image after each of `checkpoints` frames, the bias (denoised / converged - 1, mean over
/// channels) and the flicker (mean |change| of the denoised image over the last frame, relative
/// to the converged mean) at the last, over `mask` (None: every surface pixel).
pub struct Convergence {
    pub raw: Vec<f64>,
    pub denoised: Vec<f64>,
    /// Shadows: the same errors over the penumbra only (0.02 < converged < 0.98).
    pub raw_penumbra: Vec<f64>,
    pub denoised_penumbra: Vec<f64>,
    pub bias: f64,
    pub flicker: f64,
    /// The last raw frame, the last denoised image, the converged reference (for pictures).
    pub images: [Vec<[f32; 3]>; 3],
}

pub fn convergence(
    st: &mut Stage,
    signal: Signal,
    checkpoints: &[u32],
    converged_frames: u32,
    mask: Option<&[bool]>,
) -> Convergence {
    // The reference traces every pixel, whatever the stage's checkerboard mode.
    let half = std::mem::replace(&mut st.half_resolution, false);
    let reference = signal.converged(st, converged_frames);
    st.half_resolution = half;
    let mask: Vec<bool> = mask.map_or_else(|| st.g.hit.clone(), |m| m.to_vec());
    let penumbra: Vec<bool> = mask.iter().zip(&reference).map(|(m, r)| *m && r[0] > 0.02 && r[0] < 0.98).collect();
    let shadow = matches!(signal, Signal::Shadow(_));
    let last = *checkpoints.iter().max().unwrap_or(&1);
    let (mut raw, mut denoised, mut previous) = (Vec::new(), Vec::new(), Vec::<[f32; 3]>::new());
    let (mut raw_penumbra, mut denoised_penumbra) = (Vec::new(), Vec::new());
    let (mut bias, mut flicker, mut images) = (0.0, 0.0, [Vec::new(), Vec::new(), Vec::new()]);
    for f in 1..=last {
        signal.frame(st, 1, true);
        let (n, d) = (signal.noisy(st), signal.denoised(st));
        if checkpoints.contains(&f) {
            raw.push(relative_rmse(&n, &reference, &mask));
            denoised.push(relative_rmse(&d, &reference, &mask));
            if shadow {
                raw_penumbra.push(relative_rmse(&n, &reference, &penumbra));
                denoised_penumbra.push(relative_rmse(&d, &reference, &penumbra));
            }
        }
        if f == last {
            let (sd, sr) = (channel_sums(&d, &mask), channel_sums(&reference, &mask));
            bias = (0..3).map(|c| sd[c] / sr[c].max(1e-12) - 1.0).sum::<f64>() / 3.0;
            let change: f64 = d
                .iter()
                .zip(&previous)
                .zip(&mask)
                .filter(|(_, m)| **m)
                .map(|((a, b), _)| (0..3).map(|c| (a[c] - b[c]).abs() as f64).sum::<f64>())
                .sum();
            flicker = change / sr.iter().sum::<f64>().max(1e-12);
            images = [n, d.clone(), reference.clone()];
        }
        previous = d;
    }
    Convergence { raw, denoised, raw_penumbra, denoised_penumbra, bias, flicker, images }
}
