//! The sample's deferred direct lighting, a compute pass over its G-buffer: the sun and a point
//! light (their visibility from the SDK's shadow tasks, denoised), a glTF file's own lights
//! (shaded unshadowed, summed, and multiplied by the visibility the SDK's multi-light shadow
//! task weighs by each light's unshadowed irradiance: Kickstart RT's way of shadowing many
//! lights with one denoised image) and an ambient term. Its output is the "rasterized lit
//! frame" the engine hands the SDK for light injection and as the direct-lighting input of GI
//! and reflections.
use crate::gpu::{spirv, ComputePass};
use crate::raster::Targets;
use ash::vk;
use glam::{Mat4, Vec3};
use hybrid_rt::{LightInfo, LightType, MAX_SHADOW_LIGHTS};
use hybrid_rt_host::scene::Camera;
use hybrid_rt_host::{Host, HostImage, HostResult};

pub const LIT_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// The lights of the scene.
#[derive(Clone, Copy, Debug)]
pub struct Lights {
    /// Direction towards the sun, and its irradiance at normal incidence.
    pub sun_direction: Vec3,
    pub sun_intensity: f32,
    pub point_position: Vec3,
    /// Point light: irradiance = intensity / d².
    pub point_intensity: f32,
    pub ambient: f32,
}

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct LightingGpu {
    clip_to_world: [f32; 16],
    sun: [f32; 4],
    point: [f32; 4],
    ambient: [f32; 4],
    /// How many of `lights` are used.
    counts: [u32; 4],
    lights: [FileLightGpu; MAX_SHADOW_LIGHTS],
}

/// A file light as the shader takes it (std140, 64 bytes): see shaders/sample/lighting.comp.
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct FileLightGpu {
    /// xyz, type (0 directional, 1 point, 2 spot).
    position: [f32; 4],
    /// The direction the light travels, range (0: unlimited).
    direction: [f32; 4],
    /// Colour x intensity, cos of the outer cone.
    radiance: [f32; 4],
    /// cos of the inner cone.
    cone: [f32; 4],
}

impl FileLightGpu {
    fn of(l: &LightInfo) -> FileLightGpu {
        let kind = match l.light_type {
            LightType::Point => 1.0,
            LightType::Spot => 2.0,
            _ => 0.0,
        };
        let c = l.color.map(|c| c * l.intensity);
        FileLightGpu {
            position: l.position.extend(kind).to_array(),
            direction: l.direction.normalize_or(Vec3::NEG_Y).extend(l.range).to_array(),
            radiance: [c[0], c[1], c[2], l.outer_cone.cos()],
            cone: [l.inner_cone.cos(), 0.0, 0.0, 0.0],
        }
    }
}

/// Where the lighting pass reads each light's visibility: images of the SDK's shadow tasks.
#[derive(Clone, Copy)]
pub struct Visibility<'a> {
    pub sun: &'a HostImage,
    pub point: &'a HostImage,
    /// The file's lights (`file_lights` of `record`): the multi-light trace's weighted mean
    /// visibility in R, raw (`packed`) or denoised. None where there are none.
    pub file_lights: Option<&'a HostImage>,
    pub layout: vk::ImageLayout,
    /// Denoised shadows hold the visibility in every channel (`false`); a raw
    /// `TraceShadowTask` output in G (`true`).
    pub raw_trace: bool,
}

impl<'a> Visibility<'a> {
    /// Both lights' visibility from one image (e.g. a scene with one shadowed light).
    pub fn same(image: &'a HostImage, layout: vk::ImageLayout) -> Visibility<'a> {
        Visibility { sun: image, point: image, file_lights: None, layout, raw_trace: false }
    }
}

pub struct LightingPass(ComputePass);

impl LightingPass {
    pub fn new(host: &Host) -> HostResult<LightingPass> {
        Ok(LightingPass(ComputePass::new(host, spirv::LIGHTING_COMP, 7, 1)?))
    }

    /// A lit image for `targets` (STORAGE for this pass, SAMPLED for the SDK), in GENERAL.
    pub fn lit_image(host: &Host, targets: &Targets) -> HostResult<HostImage> {
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        host.image_cleared(LIT_FORMAT, targets.width, targets.height, usage, vk::ImageLayout::GENERAL)
    }

    /// Lights the G-buffer into `lit` (GENERAL). `slot`: a frame-in-flight index (its
    /// constants are rewritten; give each view of a frame its own). `file_lights` (at most
    /// `MAX_SHADOW_LIGHTS`; more are left out) are shaded with `visibility.file_lights`.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        host: &Host,
        cmd: vk::CommandBuffer,
        slot: usize,
        targets: &Targets,
        camera: &Camera,
        lights: &Lights,
        file_lights: &[LightInfo],
        visibility: Visibility,
        lit: &HostImage,
    ) -> HostResult<()> {
        let aspect = targets.width as f32 / targets.height as f32;
        let clip_to_world: Mat4 = (camera.view_to_clip(aspect) * camera.world_to_view()).inverse();
        let mut c = LightingGpu {
            clip_to_world: clip_to_world.to_cols_array(),
            sun: lights.sun_direction.normalize().extend(lights.sun_intensity).to_array(),
            point: lights.point_position.extend(lights.point_intensity).to_array(),
            ambient: [lights.ambient, targets.width as f32, targets.height as f32, if visibility.raw_trace { 1.0 } else { 0.0 }],
            counts: [0; 4],
            lights: [FileLightGpu::default(); MAX_SHADOW_LIGHTS],
        };
        if visibility.file_lights.is_some() {
            let used = file_lights.len().min(MAX_SHADOW_LIGHTS);
            c.counts[0] = used as u32;
            for (gpu, l) in c.lights.iter_mut().zip(file_lights) {
                *gpu = FileLightGpu::of(l);
            }
        }
        let read = crate::raster::READ;
        let sampled = [
            (&targets.depth, read),
            (&targets.normal_roughness, read),
            (&targets.albedo_metalness, read),
            (visibility.sun, visibility.layout),
            (visibility.point, visibility.layout),
            (&targets.emissive, read),
            // (Any image where there are no file lights: the shader does not read it.)
            (visibility.file_lights.unwrap_or(visibility.sun), visibility.layout),
        ];
        self.0.dispatch(host, cmd, slot, &sampled, &[lit], bytemuck::bytes_of(&c), targets.width, targets.height)
    }

    pub fn destroy(self, host: &Host) {
        self.0.destroy(host)
    }
}
