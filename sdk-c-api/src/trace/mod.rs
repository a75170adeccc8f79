//! Tracing against the G-buffer: `HrtTraceCommon` (the G-buffer, the camera and the options
//! every trace shares) and its parts, which the denoisers and cache injection read too, and
//! ambient occlusion. Shadows and lights are in `shadow`, diffuse GI and specular reflections
//! in `shading`.
//!
//! Matrices are column-major float[16] (as GLSL and glam).
mod shading;
mod shadow;

use crate::args::pick;
use crate::context::{schedule, HrtTaskContainer, HrtTaskKind};
use crate::image::{image, image_c, HrtImageInput};
use crate::status::{Failure, HrtStatus};
use hybrid_rt as rt;
pub use shading::*;
pub use shadow::*;

pub const HRT_TASK_AMBIENT_OCCLUSION: HrtTaskKind = 1;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDepthType {
    HRT_DEPTH_CLIP_SPACE = 0,
    HRT_DEPTH_WORLD_POSITION = 1,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtNormalType {
    HRT_NORMAL_RGB_VECTOR = 0,
    HRT_NORMAL_RGB_NORMALIZED_VECTOR = 1,
    HRT_NORMAL_RG_OCTAHEDRON = 2,
    HRT_NORMAL_BA_OCTAHEDRON = 3,
    HRT_NORMAL_RG_NORMALIZED_OCTAHEDRON = 4,
    HRT_NORMAL_BA_NORMALIZED_OCTAHEDRON = 5,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtNormalSpace {
    HRT_NORMAL_SPACE_WORLD = 0,
    HRT_NORMAL_SPACE_VIEW = 1,
    /// HrtNormalInput.normal_to_world takes decoded normals to world space.
    HRT_NORMAL_SPACE_CUSTOM = 2,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtRayOffsetType {
    HRT_RAY_OFFSET_DISABLED = 0,
    HRT_RAY_OFFSET_WORLD_POSITION = 1,
    HRT_RAY_OFFSET_CAMERA_DISTANCE = 2,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDepthInput {
    pub image: HrtImageInput,
    /// An HrtDepthType. Default HRT_DEPTH_CLIP_SPACE.
    pub depth_type: u32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtNormalInput {
    pub image: HrtImageInput,
    /// An HrtNormalType. Default HRT_NORMAL_RGB_NORMALIZED_VECTOR.
    pub normal_type: u32,
    /// An HrtNormalSpace. Default HRT_NORMAL_SPACE_WORLD.
    pub space: u32,
    /// HRT_NORMAL_SPACE_CUSTOM: column-major 3x3 to world space. Default identity.
    pub normal_to_world: [f32; 9],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtViewport {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    /// 0 and 0 mean 0..1.
    pub min_depth: f32,
    pub max_depth: f32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtCamera {
    /// Column-major.
    pub world_to_view: [f32; 16],
    /// Column-major, Vulkan clip space (y down, depth 0..1, standard or reversed).
    pub view_to_clip: [f32; 16],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtRayOffset {
    /// An HrtRayOffsetType. Default HRT_RAY_OFFSET_CAMERA_DISTANCE.
    pub offset_type: u32,
    pub world_threshold: f32,
    pub world_float_scale: f32,
    pub world_int_scale: f32,
    pub cam_constant: f32,
    pub cam_linear: f32,
    pub cam_quadratic: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDebugOutput {
    HRT_DEBUG_DEFAULT = 0,
    HRT_DEBUG_DIRECT_LIGHTING_CACHE = 1,
    HRT_DEBUG_RANDOM_TILE_COLOR = 2,
    HRT_DEBUG_RANDOM_MESH_COLOR = 3,
    HRT_DEBUG_HIT_T = 4,
    HRT_DEBUG_BARYCENTRICS = 5,
}

/// Checkerboard tracing (`HalfResolutionMode`): half the pixels per ticket, alternating with
/// the frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtHalfResolutionMode {
    /// Every pixel.
    HRT_HALF_RESOLUTION_OFF = 0,
    /// The pixels where x + y + frame is even.
    HRT_HALF_RESOLUTION_CHECKERBOARD = 1,
    /// The pixels where x + y + frame is odd.
    HRT_HALF_RESOLUTION_CHECKERBOARD_INVERTED = 2,
}

/// The rays' random numbers (`RandomNumbers`): the default, or white or blue noise for
/// image-quality comparisons.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtRandomNumbers {
    /// Per-pixel low-discrepancy sequences across frames, what the denoisers are tuned for.
    HRT_RANDOM_NUMBERS_DEFAULT = 0,
    /// Independent for every pixel, frame and ray (Kickstart RT's XORShift).
    HRT_RANDOM_NUMBERS_WHITE_NOISE = 1,
    /// A blue-noise tile shifted per frame (Kickstart RT's BlueNoiseTexture).
    HRT_RANDOM_NUMBERS_BLUE_NOISE = 2,
}

/// An HrtHalfResolutionMode read from the field `what`.
pub(crate) fn half_resolution_mode(what: &str, v: u32) -> Result<rt::HalfResolutionMode, Failure> {
    use rt::HalfResolutionMode as M;
    pick(what, v, &[M::Off, M::Checkerboard, M::CheckerboardInverted])
}

/// Roughness, Kickstart RT's rule: r = global_roughness * dot(texel, channel_mask) with an
/// image (image != 0), global_roughness without; then
/// clamp(r * roughness_multiplier + min_roughness, min_roughness, max_roughness).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtRoughnessInput {
    /// Optional (image = VK_NULL_HANDLE for none).
    pub image: HrtImageInput,
    /// Default {1, 0, 0, 0}.
    pub channel_mask: [f32; 4],
    /// Scales the image's roughness (or is the roughness, without an image). Default 1.0.
    pub global_roughness: f32,
    /// The remap's multiplier. Default 1.0.
    pub roughness_multiplier: f32,
    /// The remap's offset and lower clamp. Default 0.
    pub min_roughness: f32,
    /// Default 1.
    pub max_roughness: f32,
}

/// Specular colour: global_metalness * image.rgb (image != 0), global_metalness without.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtSpecularInput {
    pub image: HrtImageInput,
    /// Default 1.0.
    pub global_metalness: f32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceCommon {
    pub depth: HrtDepthInput,
    pub normals: HrtNormalInput,
    pub viewport: HrtViewport,
    pub camera: HrtCamera,
    pub ray_offset: HrtRayOffset,
    pub roughness: HrtRoughnessInput,
    pub specular: HrtSpecularInput,
    /// Optional (image = VK_NULL_HANDLE for none): pixels with R >= 0.5 are excluded from the
    /// trace (written as background). Any unorm, snorm, sRGB or float colour format the device
    /// can sample; integer and depth/stencil formats give HRT_ERROR_UNSUPPORTED_FORMAT.
    pub input_mask: HrtImageInput,
    /// Optional lit frame (image = VK_NULL_HANDLE for none): secondary hits on screen take
    /// its radiance, others the cache's.
    pub direct_lighting: HrtImageInput,
    /// Default false.
    pub use_inline_rt: bool,
    /// Interpolate mesh-colors caches. Default true.
    pub enable_bilinear_sampling: bool,
    /// An HrtDebugOutput. Default HRT_DEBUG_DEFAULT.
    pub debug_output: u32,
    /// An HrtHalfResolutionMode: checkerboard tracing, half the pixels per ticket,
    /// alternating. Default HRT_HALF_RESOLUTION_OFF.
    pub half_resolution_mode: u32,
    /// An HrtRandomNumbers. Default HRT_RANDOM_NUMBERS_DEFAULT.
    pub random_numbers: u32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceAmbientOcclusionTask {
    pub common: HrtTraceCommon,
    /// GENERAL layout, STORAGE usage.
    pub output: HrtImageInput,
    /// Default 1.0.
    pub ray_length: f32,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// > 0. Default 1.0.
    pub falloff_power: f32,
}

// ---------------------------------------------------------------- conversions

pub(crate) fn depth(d: &HrtDepthInput) -> Result<rt::DepthInput, Failure> {
    Ok(rt::DepthInput {
        image: image(&d.image),
        depth_type: pick("HrtDepthInput.depth_type", d.depth_type, &[rt::DepthType::ClipSpace, rt::DepthType::WorldPosition])?,
    })
}

pub(crate) fn normals(n: &HrtNormalInput) -> Result<rt::NormalInput, Failure> {
    use rt::NormalType as N;
    Ok(rt::NormalInput {
        image: image(&n.image),
        normal_type: pick(
            "HrtNormalInput.normal_type",
            n.normal_type,
            &[
                N::RgbVector,
                N::RgbNormalizedVector,
                N::RgOctahedron,
                N::BaOctahedron,
                N::RgNormalizedOctahedron,
                N::BaNormalizedOctahedron,
            ],
        )?,
        space: pick("HrtNormalInput.space", n.space, &[rt::NormalSpace::World, rt::NormalSpace::View, rt::NormalSpace::Custom])?,
        normal_to_world: glam::Mat3::from_cols_array(&n.normal_to_world),
    })
}

pub(crate) fn viewport(v: &HrtViewport) -> rt::Viewport {
    rt::Viewport { x: v.x, y: v.y, width: v.width, height: v.height, min_depth: v.min_depth, max_depth: v.max_depth }
}

pub(crate) fn camera(c: &HrtCamera) -> rt::Camera {
    rt::Camera {
        world_to_view: glam::Mat4::from_cols_array(&c.world_to_view),
        view_to_clip: glam::Mat4::from_cols_array(&c.view_to_clip),
    }
}

pub(crate) fn camera_c(c: &rt::Camera) -> HrtCamera {
    HrtCamera { world_to_view: c.world_to_view.to_cols_array(), view_to_clip: c.view_to_clip.to_cols_array() }
}

pub(crate) fn roughness(r: &HrtRoughnessInput) -> rt::RoughnessInput {
    rt::RoughnessInput {
        image: image(&r.image),
        channel_mask: r.channel_mask,
        global_roughness: r.global_roughness,
        roughness_multiplier: r.roughness_multiplier,
        min_roughness: r.min_roughness,
        max_roughness: r.max_roughness,
    }
}

pub(crate) fn trace_common(c: &HrtTraceCommon) -> Result<rt::TraceCommon, Failure> {
    let o = &c.ray_offset;
    Ok(rt::TraceCommon {
        depth: depth(&c.depth)?,
        normals: normals(&c.normals)?,
        viewport: viewport(&c.viewport),
        camera: camera(&c.camera),
        ray_offset: rt::RayOffset {
            offset_type: pick(
                "HrtRayOffset.offset_type",
                o.offset_type,
                &[rt::RayOffsetType::Disabled, rt::RayOffsetType::WorldPosition, rt::RayOffsetType::CameraDistance],
            )?,
            world_threshold: o.world_threshold,
            world_float_scale: o.world_float_scale,
            world_int_scale: o.world_int_scale,
            cam_constant: o.cam_constant,
            cam_linear: o.cam_linear,
            cam_quadratic: o.cam_quadratic,
        },
        roughness: roughness(&c.roughness),
        specular: rt::SpecularInput { image: image(&c.specular.image), global_metalness: c.specular.global_metalness },
        input_mask: image(&c.input_mask),
        direct_lighting: image(&c.direct_lighting),
        use_inline_rt: c.use_inline_rt,
        enable_bilinear_sampling: c.enable_bilinear_sampling,
        debug_output: pick(
            "HrtTraceCommon.debug_output",
            c.debug_output,
            &[
                rt::DebugOutput::Default,
                rt::DebugOutput::DirectLightingCache,
                rt::DebugOutput::RandomTileColor,
                rt::DebugOutput::RandomMeshColor,
                rt::DebugOutput::HitT,
                rt::DebugOutput::Barycentrics,
            ],
        )?,
        half_resolution_mode: half_resolution_mode("HrtTraceCommon.half_resolution_mode", c.half_resolution_mode)?,
        random_numbers: pick(
            "HrtTraceCommon.random_numbers",
            c.random_numbers,
            &[rt::RandomNumbers::Default, rt::RandomNumbers::WhiteNoise, rt::RandomNumbers::BlueNoise],
        )?,
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_common_default() -> HrtTraceCommon {
    let d = rt::TraceCommon::default();
    let o = &d.ray_offset;
    HrtTraceCommon {
        depth: HrtDepthInput { image: image_c(&d.depth.image), depth_type: d.depth.depth_type as u32 },
        normals: HrtNormalInput {
            image: image_c(&d.normals.image),
            normal_type: d.normals.normal_type as u32,
            space: d.normals.space as u32,
            normal_to_world: d.normals.normal_to_world.to_cols_array(),
        },
        viewport: HrtViewport { x: 0, y: 0, width: 0, height: 0, min_depth: 0.0, max_depth: 0.0 },
        camera: HrtCamera {
            world_to_view: d.camera.world_to_view.to_cols_array(),
            view_to_clip: d.camera.view_to_clip.to_cols_array(),
        },
        ray_offset: HrtRayOffset {
            offset_type: o.offset_type as u32,
            world_threshold: o.world_threshold,
            world_float_scale: o.world_float_scale,
            world_int_scale: o.world_int_scale,
            cam_constant: o.cam_constant,
            cam_linear: o.cam_linear,
            cam_quadratic: o.cam_quadratic,
        },
        roughness: HrtRoughnessInput {
            image: image_c(&d.roughness.image),
            channel_mask: d.roughness.channel_mask,
            global_roughness: d.roughness.global_roughness,
            roughness_multiplier: d.roughness.roughness_multiplier,
            min_roughness: d.roughness.min_roughness,
            max_roughness: d.roughness.max_roughness,
        },
        specular: HrtSpecularInput { image: image_c(&d.specular.image), global_metalness: d.specular.global_metalness },
        input_mask: image_c(&d.input_mask),
        direct_lighting: image_c(&d.direct_lighting),
        use_inline_rt: d.use_inline_rt,
        enable_bilinear_sampling: d.enable_bilinear_sampling,
        debug_output: d.debug_output as u32,
        half_resolution_mode: d.half_resolution_mode as u32,
        random_numbers: d.random_numbers as u32,
    }
}

fn ao_task(t: &HrtTraceAmbientOcclusionTask) -> Result<rt::TraceAmbientOcclusionTask, Failure> {
    Ok(rt::TraceAmbientOcclusionTask {
        common: trace_common(&t.common)?,
        output: image(&t.output),
        ray_length: t.ray_length,
        rays_per_pixel: t.rays_per_pixel,
        falloff_power: t.falloff_power,
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_ambient_occlusion_task_default() -> HrtTraceAmbientOcclusionTask {
    let d = rt::TraceAmbientOcclusionTask::default();
    HrtTraceAmbientOcclusionTask {
        common: hrt_trace_common_default(),
        output: image_c(&d.output),
        ray_length: d.ray_length,
        rays_per_pixel: d.rays_per_pixel,
        falloff_power: d.falloff_power,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_ambient_occlusion(
    container: *mut HrtTaskContainer,
    task: *const HrtTraceAmbientOcclusionTask,
) -> HrtStatus {
    schedule(container, task, ao_task, rt::TaskContainer::schedule_ambient_occlusion)
}
