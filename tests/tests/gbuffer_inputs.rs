//! G-buffer conventions beyond the encodings (those are in ao.rs): the roughness remap and the
//! input mask, traced and denoised on lavapipe.
//!
//! Both are checked by equivalence on the GPU, which is exact: two contexts built the same way
//! give their tickets the same serials, so the same random numbers; a task given (image, remap)
//! and a task given the remapped image must then write the same bytes, and a masked task must
//! write what an unmasked one does everywhere but under the mask. The unremapped roughness
//! itself is tested against the reference in specular.rs and diffuse.rs.
mod common;
use ash::vk;
use common::*;
use glam::Vec3;
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostImage};
use hybrid_rt_testkit::reference::{coloured_room, Camera};
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 48;
const H: u32 = 48;
const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;
const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

/// The coloured room without its ceiling, registered, built (ticket 1), its G-buffer uploaded.
struct Room {
    host: Host,
    ctx: ExecuteContext,
    frame: TaskContainer,
    images: GBufferImages,
    gpu_scene: SceneOnGpu,
    camera: Camera,
    hit: Vec<bool>,
    owned: Vec<HostImage>,
}

impl Room {
    fn new() -> Room {
        let (host, ctx) = host_and_context(InitSettings::default());
        let (scene, colours, _) = coloured_room(false);
        let camera = Camera::look_at(Vec3::new(0.0, 1.6, 1.9), Vec3::new(0.0, 0.0, -0.8));
        let tracer = hybrid_rt_testkit::reference::Tracer::new(&scene);
        let g = hybrid_rt_testkit::reference::GBuffer::render(&tracer, &camera, W, H);
        let images = GBufferImages::upload(&host, &g).unwrap();
        let mut frame = ctx.create_task_container();
        let gpu_scene = SceneOnGpu::register_coloured(&host, &ctx, &mut frame, &scene, Default::default(), &colours).unwrap();
        frame.schedule_bvh_build(&Default::default()).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        Room { host, ctx, frame, images, gpu_scene, camera, hit: g.hit, owned: Vec::new() }
    }

    /// A sampled RGBA32F image holding `texels`, freed by `finish`.
    fn input(&mut self, texels: &[[f32; 4]]) -> ImageInput {
        let img = self
            .host
            .image_with_data(
                vk::Format::R32G32B32A32_SFLOAT,
                W,
                H,
                vk::ImageUsageFlags::SAMPLED,
                bytemuck::cast_slice(texels),
                READ,
            )
            .unwrap();
        let input = img.input(READ);
        self.owned.push(img);
        input
    }

    /// A cleared RGBA32F storage image (also sampled, to feed a denoiser), freed by `finish`.
    fn target(&mut self) -> (ImageInput, usize) {
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
        let img = self.host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, usage, GENERAL).unwrap();
        let input = img.input(GENERAL);
        self.owned.push(img);
        (input, self.owned.len() - 1)
    }

    fn read(&self, index: usize) -> Vec<[f32; 4]> {
        bytemuck::cast_slice(&self.host.read_image(&self.owned[index], GENERAL).unwrap()).to_vec()
    }

    fn run(&mut self) {
        run_frame(&self.host, &self.ctx, &mut self.frame).unwrap();
    }

    fn finish(self) {
        for i in self.owned {
            self.host.destroy_image(i);
        }
        self.images.destroy(&self.host);
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
    }
}

fn max_abs_diff(a: &[[f32; 4]], b: &[[f32; 4]], keep: impl Fn(usize) -> bool) -> f32 {
    a.iter()
        .zip(b)
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .flat_map(|(_, (x, y))| (0..4).map(move |c| (x[c] - y[c]).abs()))
        .fold(0.0, f32::max)
}

/// Roughness in four vertical bands, in G (R holds a decoy).
fn bands(values: [f32; 4]) -> Vec<[f32; 4]> {
    (0..W * H).map(|i| [0.95, values[((i % W) * 4 / W) as usize], 0.0, 0.0]).collect()
}

/// Kickstart RT's roughness rule (its RemapRoughness and LoadRoughness), on the CPU:
/// `r = global * dot(texel, mask)`, then `clamp(r * multiplier + min, min, max)`.
fn kickstart_roughness(texel: [f32; 4], r: &RoughnessInput) -> f32 {
    let dot: f32 = (0..4).map(|c| texel[c] * r.channel_mask[c]).sum();
    (r.global_roughness * dot * r.roughness_multiplier + r.min_roughness).clamp(r.min_roughness, r.max_roughness)
}

/// The remap, as Kickstart RT computes it: the raw bands 0.05, 0.15, 0.25, 0.45 under global 4,
/// multiplier 0.5 and [0.2, 0.6] are 0.3, 0.5 (lifted by the minimum), 0.6 and 0.6 (clamped) —
/// each exact in f32 (the scalings are powers of two), so the remapped trace and the trace of
/// the image remapped on the CPU agree to the bit in the specular trace, the Disney diffuse
/// trace and the specular denoiser.
#[test]
fn the_roughness_remap_is_kickstart_rts_in_every_pass_that_reads_roughness() {
    let remap = |image| RoughnessInput {
        image,
        channel_mask: [0.0, 1.0, 0.0, 0.0],
        global_roughness: 4.0,
        roughness_multiplier: 0.5,
        min_roughness: 0.2,
        max_roughness: 0.6,
    };
    let plain = |image| RoughnessInput { image, channel_mask: [0.0, 1.0, 0.0, 0.0], ..Default::default() };
    let raw = [0.05, 0.15, 0.25, 0.45];
    let rule = remap(ImageInput::default());
    let remapped = raw.map(|v| kickstart_roughness([0.95, v, 0.0, 0.0], &rule));
    assert_eq!(remapped, [0.3, 0.5, 0.6, 0.6], "Kickstart RT's rule on the CPU");
    let mut images = Vec::new();
    for (raw, rule) in [
        (raw, remap as fn(ImageInput) -> RoughnessInput),
        (remapped, plain as fn(ImageInput) -> RoughnessInput),
        (raw, plain as fn(ImageInput) -> RoughnessInput),
    ] {
        let mut room = Room::new();
        let roughness = rule(room.input(&bands(raw)));
        let mut common = room.images.trace_common(&room.camera);
        common.roughness = roughness;
        let (spec_out, spec_i) = room.target();
        let (diff_out, diff_i) = room.target();
        let (den_out, den_i) = room.target();
        room.frame
            .schedule_specular(&TraceSpecularTask {
                common,
                output: spec_out,
                rays_per_pixel: 8,
                ray_length: 100.0,
                miss_radiance: [0.1, 0.2, 0.3],
                ..Default::default()
            })
            .unwrap();
        room.frame
            .schedule_diffuse(&TraceDiffuseTask {
                common,
                output: diff_out,
                rays_per_pixel: 4,
                ray_length: 100.0,
                brdf: DiffuseBrdfType::NormalizedDisney,
                ..Default::default()
            })
            .unwrap();
        let context = room
            .ctx
            .create_denoising_context(&DenoisingContextInput {
                max_width: W,
                max_height: H,
                signal: SignalType::Specular,
                ..Default::default()
            })
            .unwrap();
        let mut dc = room.images.denoising_common(&room.camera);
        dc.roughness = roughness;
        room.frame
            .schedule_denoise_specular(&DenoiseSpecularTask { context, common: dc, input: spec_out, output: den_out })
            .unwrap();
        room.run();
        images.push([room.read(spec_i), room.read(diff_i), room.read(den_i)]);
        room.ctx.destroy_denoising_context(context).unwrap();
        room.finish();
    }
    let all = |_| true;
    for (k, what) in ["specular trace", "Disney diffuse trace", "specular denoiser"].iter().enumerate() {
        let same = max_abs_diff(&images[0][k], &images[1][k], all);
        let unremapped = max_abs_diff(&images[0][k], &images[2][k], all);
        eprintln!("{what}: remapped vs remapped image {same:.2e}, vs the raw roughness {unremapped:.3}");
        assert!(same <= 1e-6, "{what}: the remap must equal the remapped image ({same})");
        assert!(unremapped > 1e-2, "{what}: the remap must change the image ({unremapped})");
    }
}

/// Pixels the mask covers: the left third (a UI panel) and a block at the bottom right (a
/// first-person hand).
fn masked(i: usize) -> bool {
    let (x, y) = (i as u32 % W, i as u32 / W);
    x < W / 3 || (x >= 3 * W / 4 && y >= 2 * H / 3)
}

fn mask_image(room: &mut Room) -> ImageInput {
    let texels: Vec<u8> = (0..(W * H) as usize).map(|i| if masked(i) { 255 } else { 0 }).collect();
    mask_image_of(room, vk::Format::R8_UNORM, &texels)
}

/// The mask in `format`, its texels given as bytes.
fn mask_image_of(room: &mut Room, format: vk::Format, texels: &[u8]) -> ImageInput {
    let img = room.host.image_with_data(format, W, H, vk::ImageUsageFlags::SAMPLED, texels, READ).unwrap();
    let input = img.input(READ);
    room.owned.push(img);
    input
}

/// Any colour format a float sampler reads is a mask: sRGB, 16-bit unorm and snorm masks
/// exclude exactly the pixels an R8_UNORM mask does. An integer format is refused with an
/// error naming the field.
#[test]
fn every_float_readable_format_is_a_mask() {
    let mut room = Room::new();
    let texels = |masked_texel: &[u8], clear_texel: &[u8]| -> Vec<u8> {
        (0..(W * H) as usize).flat_map(|i| if masked(i) { masked_texel.to_vec() } else { clear_texel.to_vec() }).collect()
    };
    let one16 = 65535u16.to_le_bytes();
    let masks = [
        (vk::Format::R8_UNORM, texels(&[255], &[0])),
        (vk::Format::R8G8B8A8_SRGB, texels(&[255, 0, 0, 255], &[0, 0, 0, 255])),
        (
            vk::Format::R16G16B16A16_UNORM,
            texels(&[one16, [0; 2], [0; 2], one16].concat(), &[[0; 2], [0; 2], [0; 2], one16].concat()),
        ),
        (vk::Format::R8_SNORM, texels(&[127], &[0])),
    ];
    let mut outputs = Vec::new();
    for (format, texels) in &masks {
        let mut common = room.images.trace_common(&room.camera);
        common.input_mask = mask_image_of(&mut room, *format, texels);
        let (ao, ao_i) = room.target();
        let task = TraceAmbientOcclusionTask { common, output: ao, ray_length: 1.0, rays_per_pixel: 2, ..Default::default() };
        room.frame.schedule_ambient_occlusion(&task).unwrap();
        outputs.push((*format, ao_i));
    }
    let mut refused = room.images.trace_common(&room.camera);
    refused.input_mask = mask_image_of(&mut room, vk::Format::R8_UINT, &texels(&[1], &[0]));
    let (ao, _) = room.target();
    let e = room
        .frame
        .schedule_ambient_occlusion(&TraceAmbientOcclusionTask { common: refused, output: ao, ..Default::default() })
        .unwrap_err();
    assert!(matches!(e, Error::UnsupportedFormat { what: "TraceCommon.input_mask.format", .. }), "{e}");
    room.run();
    let reference = room.read(outputs[0].1);
    let covered = (0..reference.len()).filter(|&i| masked(i) && room.hit[i]).count();
    assert!(covered > 200, "the mask covers surfaces ({covered} px)");
    for (format, index) in &outputs[1..] {
        let image = room.read(*index);
        let differ = (0..image.len()).filter(|&i| image[i][0] != reference[i][0]).count();
        assert_eq!(differ, 0, "{format:?}: {differ} pixels differ from the R8_UNORM mask's");
    }
    room.finish();
}

/// Every trace task, given the mask, writes its background value under it and exactly what it
/// writes without the mask everywhere else (both in one ticket, so the same random numbers).
#[test]
fn the_input_mask_excludes_pixels_from_every_trace() {
    let mut room = Room::new();
    let mask = mask_image(&mut room);
    let sun = LightInfo { light_type: LightType::Directional, direction: Vec3::new(-0.3, -1.0, -0.4), ..Default::default() };
    let point = LightInfo { light_type: LightType::Point, position: Vec3::new(0.5, 1.2, 0.2), radius: 0.1, ..Default::default() };
    // (name, output slots [unmasked, masked], background value, channels compared)
    let mut runs: Vec<(&str, [usize; 2], [f32; 4], usize)> = Vec::new();
    for with_mask in [false, true] {
        let mut common = room.images.trace_common(&room.camera);
        if with_mask {
            common.input_mask = mask;
        }
        let (ao, ao_i) = room.target();
        room.frame
            .schedule_ambient_occlusion(&TraceAmbientOcclusionTask {
                common,
                output: ao,
                ray_length: 1.0,
                rays_per_pixel: 4,
                ..Default::default()
            })
            .unwrap();
        let (sh, sh_i) = room.target();
        room.frame
            .schedule_shadow(&TraceShadowTask { common, light: sun, output: sh, rays_per_pixel: 2, ..Default::default() })
            .unwrap();
        let (di, di_i) = room.target();
        room.frame
            .schedule_diffuse(&TraceDiffuseTask {
                common,
                output: di,
                rays_per_pixel: 2,
                ray_length: 100.0,
                ..Default::default()
            })
            .unwrap();
        let mut glossy = common;
        glossy.roughness.global_roughness = 0.4;
        let (sp, sp_i) = room.target();
        room.frame
            .schedule_specular(&TraceSpecularTask {
                common: glossy,
                output: sp,
                rays_per_pixel: 2,
                ray_length: 100.0,
                miss_radiance: [0.2; 3],
                ..Default::default()
            })
            .unwrap();
        let (packed, packed_i) = room.target();
        let vis = room.host.image_cleared(vk::Format::R32_UINT, W, H, vk::ImageUsageFlags::STORAGE, GENERAL).unwrap();
        room.frame
            .schedule_multi_shadow(&TraceMultiShadowTask {
                common,
                lights: vec![sun, point],
                visibility: vis.input(GENERAL),
                packed,
                rays_per_pixel: 2,
                ..Default::default()
            })
            .unwrap();
        room.owned.push(vis);
        let m = with_mask as usize;
        let slots = [
            ("ambient occlusion", ao_i, [1.0, 1.0, 1.0, 1.0], 1),
            ("shadow", sh_i, [-1.0, 1.0, 0.0, 0.0], 2),
            ("diffuse GI", di_i, [0.0; 4], 4),
            ("specular", sp_i, [0.0; 4], 4),
            ("multi-light shadow (packed)", packed_i, [1.0, -1.0, 0.0, 0.0], 2),
        ];
        for (k, (name, slot, background, channels)) in slots.into_iter().enumerate() {
            if m == 0 {
                runs.push((name, [slot, 0], background, channels));
            } else {
                runs[k].1[1] = slot;
            }
        }
    }
    room.run();
    let covered = (0..(W * H) as usize).filter(|&i| masked(i) && room.hit[i]).count();
    assert!(covered > 200, "the mask covers surfaces ({covered} px)");
    for (name, [plain, with_mask], background, channels) in runs {
        let (a, b) = (room.read(plain), room.read(with_mask));
        let keep = |i: usize| !masked(i);
        let outside = a
            .iter()
            .zip(&b)
            .enumerate()
            .filter(|(i, _)| keep(*i))
            .flat_map(|(_, (x, y))| (0..channels).map(move |c| (x[c] - y[c]).abs()))
            .fold(0.0f32, f32::max);
        let under: Vec<usize> = (0..b.len()).filter(|&i| masked(i)).collect();
        let wrong = under.iter().filter(|&&i| (0..channels).any(|c| b[i][c] != background[c])).count();
        let changed = under.iter().filter(|&&i| room.hit[i] && (0..channels).any(|c| a[i][c] != background[c])).count();
        eprintln!("{name}: outside the mask max |diff| {outside:.1e}; under it {wrong} of {} not background ({changed} surface pixels were not before)", under.len());
        assert!(outside == 0.0, "{name}: pixels outside the mask change ({outside})");
        assert_eq!(wrong, 0, "{name}: masked pixels hold the background value");
        assert!(changed > 50, "{name}: the mask must have covered traced surfaces ({changed})");
    }
    room.finish();
}

/// The denoiser leaves masked pixels out: whatever they hold cannot reach the pixels outside
/// (as neighbours or as history), and they pass their input through. Checked over 4 frames
/// with two inputs that differ only under the mask; without the mask the same inputs bleed
/// (a little: the luminance stop already keeps most of a 0-or-1 outlier out, ~0.009 here).
#[test]
fn the_input_mask_keeps_masked_pixels_out_of_the_denoiser() {
    let mut room = Room::new();
    let mask = mask_image(&mut room);
    // A noisy AO-like signal outside the mask (a fixed pattern: PCG of the pixel index).
    let noise = |i: usize| {
        let mut v = (i as u32).wrapping_mul(747796405).wrapping_add(2891336453);
        v = ((v >> ((v >> 28) + 4)) ^ v).wrapping_mul(277803737);
        0.4 + 0.5 * ((v >> 8) as f32 / 16777216.0)
    };
    let signal = |garbage: f32| -> Vec<[f32; 4]> {
        (0..(W * H) as usize).map(|i| if masked(i) { [garbage; 4] } else { [noise(i); 4] }).collect()
    };
    let inputs = [room.input(&signal(0.0)), room.input(&signal(1.0))];
    // (input, masked?) -> output slot
    let mut tasks = Vec::new();
    for with_mask in [true, false] {
        for input in inputs {
            let context = room
                .ctx
                .create_denoising_context(&DenoisingContextInput {
                    max_width: W,
                    max_height: H,
                    signal: SignalType::DiffuseOcclusion,
                    ..Default::default()
                })
                .unwrap();
            let mut common = room.images.denoising_common(&room.camera);
            if with_mask {
                common.input_mask = mask;
            }
            let (output, slot) = room.target();
            tasks.push((DenoiseDiffuseOcclusionTask { context, common, input, output }, slot));
        }
    }
    for _ in 0..4 {
        for (t, _) in &tasks {
            room.frame.schedule_denoise_diffuse_occlusion(t).unwrap();
        }
        room.run();
    }
    let out: Vec<Vec<[f32; 4]>> = tasks.iter().map(|(_, s)| room.read(*s)).collect();
    let outside = |i: usize| !masked(i);
    let masked_diff = max_abs_diff(&out[0], &out[1], outside);
    let unmasked_diff = max_abs_diff(&out[2], &out[3], outside);
    eprintln!("outside the mask, garbage 0 vs 1 under it: masked {masked_diff:.1e}, unmasked {unmasked_diff:.3}");
    assert!(masked_diff == 0.0, "masked pixels reach the others ({masked_diff})");
    assert!(unmasked_diff > 1e-3, "without the mask the garbage bleeds (the test must be able to fail): {unmasked_diff}");
    for (k, garbage) in [(0, 0.0f32), (1, 1.0)] {
        let passed = (0..out[k].len()).filter(|&i| masked(i)).all(|i| out[k][i][0] == garbage);
        assert!(passed, "masked pixels pass their input through");
    }
    for (t, _) in tasks {
        room.ctx.destroy_denoising_context(t.context).unwrap();
    }
    room.finish();
}
