//! Denoising: denoising contexts (the history a signal's denoiser keeps between frames) and
//! the six denoise tasks (see the Rust docs of `hybrid_rt::types::denoise`). Four tasks share
//! one struct, `HrtDenoiseTask` (context, common, input, output); each has its own schedule
//! function.
use crate::args::{get, get_mut};
use crate::context::{context, schedule, HrtContext, HrtTaskContainer, HrtTaskKind};
use crate::image::{image, image_c, HrtImageInput};
use crate::status::{guard, Failure, HrtStatus};
use crate::trace::{
    camera, camera_c, depth, half_resolution_mode, hrt_trace_common_default, hrt_trace_shadow_task_default, light, normals,
    roughness, viewport, HrtCamera, HrtDepthInput, HrtLightInfo, HrtNormalInput, HrtRoughnessInput, HrtViewport,
};
use hybrid_rt as rt;

/// Largest HrtDenoisingContextInput.max_width / max_height.
pub const HRT_MAX_DENOISING_EXTENT: u32 = 16384;

pub const HRT_TASK_DENOISE_SPECULAR: HrtTaskKind = 11;
pub const HRT_TASK_DENOISE_DIFFUSE: HrtTaskKind = 12;
pub const HRT_TASK_DENOISE_SPECULAR_AND_DIFFUSE: HrtTaskKind = 13;
pub const HRT_TASK_DENOISE_DIFFUSE_OCCLUSION: HrtTaskKind = 14;
pub const HRT_TASK_DENOISE_SHADOW: HrtTaskKind = 15;
pub const HRT_TASK_DENOISE_MULTI_SHADOW: HrtTaskKind = 16;

pub type HrtDenoisingContextHandle = u64;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDenoisingMethod {
    /// Temporal accumulation with reprojection, then spatial filtering (default).
    HRT_DENOISING_TEMPORAL = 0,
    /// This frame only, no history (debugging).
    HRT_DENOISING_SPATIAL_ONLY = 1,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtSignalType {
    HRT_SIGNAL_SPECULAR = 0,
    HRT_SIGNAL_DIFFUSE = 1,
    HRT_SIGNAL_SPECULAR_AND_DIFFUSE = 2,
    HRT_SIGNAL_DIFFUSE_OCCLUSION = 3,
    HRT_SIGNAL_SHADOW = 4,
    HRT_SIGNAL_MULTI_SHADOW = 5,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDenoisingContextInput {
    /// 1..=HRT_MAX_DENOISING_EXTENT each.
    pub max_width: u32,
    pub max_height: u32,
    /// An HrtDenoisingMethod. Default HRT_DENOISING_TEMPORAL.
    pub method: u32,
    /// An HrtSignalType. Default HRT_SIGNAL_DIFFUSE.
    pub signal: u32,
    /// The camera view it denoises (default 0: none). Contexts created with the same nonzero
    /// view id share the denoiser's guide (this and the last frame's normal and view distance,
    /// 16 bytes a pixel); they must have one size, and one view's denoise tasks in a container
    /// must read one depth, normals, input mask, viewport and camera.
    pub view_id: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtMotionType {
    /// RG = screen-space motion in pixels (default).
    HRT_MOTION_RG_VIEW_SPACE = 0,
    /// RG = motion in normalized device coordinates.
    HRT_MOTION_RG_CLIP_SPACE = 1,
    /// RGB = world-space motion.
    HRT_MOTION_RGB_WORLD_SPACE = 2,
}

/// Motion vectors: after `scale`, previous − current. image = VK_NULL_HANDLE: reproject with
/// the cameras (static scenes only).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtMotionInput {
    pub image: HrtImageInput,
    /// An HrtMotionType.
    pub motion_type: u32,
    /// Default {1, 1, 1}.
    pub scale: [f32; 3],
}

/// Tuning (see the Rust docs of DenoiserSettings for each default).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDenoiserSettings {
    pub max_history_frames: u32,
    pub fast_history_frames: u32,
    pub history_clamp_sigma: f32,
    pub spatial_passes: u32,
    pub luminance_sigma: f32,
    pub normal_power: f32,
    pub plane_distance_sigma: f32,
    pub anti_firefly: bool,
    pub max_shadow_blur_radius: f32,
    /// Default true (see DenoiserSettings::anti_lag).
    pub anti_lag: bool,
    /// World units; 0 turns it off. Default 0.5 (see DenoiserSettings::moving_object_reach).
    pub moving_object_reach: f32,
    /// 0..=32; default 0 (see DenoiserSettings::fresh_history_taps).
    pub fresh_history_taps: u32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDenoisingCommon {
    pub depth: HrtDepthInput,
    pub normals: HrtNormalInput,
    pub roughness: HrtRoughnessInput,
    /// Optional: the traces' input mask (R >= 0.5: left out of filtering and history).
    pub input_mask: HrtImageInput,
    pub motion: HrtMotionInput,
    pub viewport: HrtViewport,
    pub camera: HrtCamera,
    /// false (default): the camera of the context's previous task.
    pub has_previous_camera: bool,
    pub previous_camera: HrtCamera,
    /// Pixels; default {0, 0}.
    pub camera_jitter: [f32; 2],
    /// The HrtHalfResolutionMode the trace ran with in the same container. Default
    /// HRT_HALF_RESOLUTION_OFF.
    pub half_resolution_mode: u32,
    /// Default false.
    pub reset_history: bool,
    pub settings: HrtDenoiserSettings,
}

/// DenoiseSpecular / DenoiseDiffuse / DenoiseDiffuseOcclusion / DenoiseMultiShadow.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDenoiseTask {
    pub context: HrtDenoisingContextHandle,
    pub common: HrtDenoisingCommon,
    /// The trace task's output (GENERAL or read-only layout, SAMPLED usage).
    pub input: HrtImageInput,
    /// GENERAL layout, STORAGE usage; may be the input image.
    pub output: HrtImageInput,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDenoiseShadowTask {
    pub context: HrtDenoisingContextHandle,
    pub common: HrtDenoisingCommon,
    /// The light that was traced.
    pub light: HrtLightInfo,
    pub input: HrtImageInput,
    pub output: HrtImageInput,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDenoiseSpecularAndDiffuseTask {
    pub context: HrtDenoisingContextHandle,
    pub common: HrtDenoisingCommon,
    pub input_specular: HrtImageInput,
    pub input_diffuse: HrtImageInput,
    pub output_specular: HrtImageInput,
    pub output_diffuse: HrtImageInput,
}

/// Motion vectors as the SDK takes them (the denoisers' and the many-lights task's).
pub(crate) fn motion(m: &HrtMotionInput) -> Result<rt::MotionInput, Failure> {
    let motion_type = match m.motion_type {
        0 => rt::MotionType::RgViewSpace,
        1 => rt::MotionType::RgClipSpace,
        2 => rt::MotionType::RgbWorldSpace,
        v => return Err(Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid HrtMotionInput.motion_type: {v}"))),
    };
    Ok(rt::MotionInput { image: image(&m.image), motion_type, scale: m.scale })
}

pub(crate) fn motion_c(m: &rt::MotionInput) -> HrtMotionInput {
    HrtMotionInput { image: image_c(&m.image), motion_type: m.motion_type as u32, scale: m.scale }
}

fn common(c: &HrtDenoisingCommon) -> Result<rt::DenoisingCommon, Failure> {
    // The G-buffer fields convert as a trace task's do (and in its order).
    let (depth, normals) = (depth(&c.depth)?, normals(&c.normals)?);
    let s = &c.settings;
    Ok(rt::DenoisingCommon {
        depth,
        normals,
        roughness: roughness(&c.roughness),
        input_mask: image(&c.input_mask),
        motion: motion(&c.motion)?,
        viewport: viewport(&c.viewport),
        camera: camera(&c.camera),
        previous_camera: c.has_previous_camera.then(|| camera(&c.previous_camera)),
        camera_jitter: c.camera_jitter,
        half_resolution_mode: half_resolution_mode("HrtDenoisingCommon.half_resolution_mode", c.half_resolution_mode)?,
        reset_history: c.reset_history,
        settings: rt::DenoiserSettings {
            max_history_frames: s.max_history_frames,
            fast_history_frames: s.fast_history_frames,
            history_clamp_sigma: s.history_clamp_sigma,
            spatial_passes: s.spatial_passes,
            luminance_sigma: s.luminance_sigma,
            normal_power: s.normal_power,
            plane_distance_sigma: s.plane_distance_sigma,
            anti_firefly: s.anti_firefly,
            max_shadow_blur_radius: s.max_shadow_blur_radius,
            anti_lag: s.anti_lag,
            moving_object_reach: s.moving_object_reach,
            fresh_history_taps: s.fresh_history_taps,
        },
    })
}

#[no_mangle]
pub extern "C" fn hrt_denoising_common_default() -> HrtDenoisingCommon {
    let d = rt::DenoisingCommon::default();
    let t = hrt_trace_common_default();
    let s = d.settings;
    HrtDenoisingCommon {
        depth: t.depth,
        normals: t.normals,
        roughness: t.roughness,
        input_mask: t.input_mask,
        motion: motion_c(&d.motion),
        viewport: t.viewport,
        camera: t.camera,
        has_previous_camera: false,
        previous_camera: camera_c(&d.camera),
        camera_jitter: d.camera_jitter,
        half_resolution_mode: d.half_resolution_mode as u32,
        reset_history: d.reset_history,
        settings: HrtDenoiserSettings {
            max_history_frames: s.max_history_frames,
            fast_history_frames: s.fast_history_frames,
            history_clamp_sigma: s.history_clamp_sigma,
            spatial_passes: s.spatial_passes,
            luminance_sigma: s.luminance_sigma,
            normal_power: s.normal_power,
            plane_distance_sigma: s.plane_distance_sigma,
            anti_firefly: s.anti_firefly,
            max_shadow_blur_radius: s.max_shadow_blur_radius,
            anti_lag: s.anti_lag,
            moving_object_reach: s.moving_object_reach,
            fresh_history_taps: s.fresh_history_taps,
        },
    }
}

#[no_mangle]
pub extern "C" fn hrt_denoising_context_input_default() -> HrtDenoisingContextInput {
    let d = rt::DenoisingContextInput::default();
    HrtDenoisingContextInput {
        max_width: d.max_width,
        max_height: d.max_height,
        method: d.method as u32,
        signal: d.signal as u32,
        view_id: d.view_id,
    }
}

/// Creates a denoising context (its history images are allocated now).
#[no_mangle]
pub unsafe extern "C" fn hrt_create_denoising_context(
    ctx: *mut HrtContext,
    input: *const HrtDenoisingContextInput,
    out: *mut HrtDenoisingContextHandle,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let i = get(input, "input")?;
        let out = get_mut(out, "out")?;
        let method = match i.method {
            0 => rt::DenoisingMethod::Temporal,
            1 => rt::DenoisingMethod::SpatialOnly,
            v => {
                return Err(Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid HrtDenoisingContextInput.method: {v}")))
            }
        };
        use rt::SignalType as S;
        let signal = *[S::Specular, S::Diffuse, S::SpecularAndDiffuse, S::DiffuseOcclusion, S::Shadow, S::MultiShadow]
            .get(i.signal as usize)
            .ok_or_else(|| {
                Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid HrtDenoisingContextInput.signal: {}", i.signal))
            })?;
        let h = c.ctx.create_denoising_context(&rt::DenoisingContextInput {
            max_width: i.max_width,
            max_height: i.max_height,
            method,
            signal,
            view_id: i.view_id,
        })?;
        *out = h.0;
        Ok(())
    })
}

/// Destroys a denoising context; its images are freed once the tickets issued so far return.
#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_denoising_context(ctx: *mut HrtContext, handle: HrtDenoisingContextHandle) -> HrtStatus {
    guard(|| Ok(context(ctx)?.ctx.destroy_denoising_context(rt::DenoisingContextHandle(handle))?))
}

/// Destroys every denoising context of the context.
#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_all_denoising_context_handles(ctx: *mut HrtContext) -> HrtStatus {
    guard(|| {
        context(ctx)?.ctx.destroy_all_denoising_context_handles();
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn hrt_denoise_task_default() -> HrtDenoiseTask {
    let out = image_c(&rt::DenoiseDiffuseTask::default().output);
    HrtDenoiseTask { context: 0, common: hrt_denoising_common_default(), input: out, output: out }
}

#[no_mangle]
pub extern "C" fn hrt_denoise_shadow_task_default() -> HrtDenoiseShadowTask {
    let t = hrt_denoise_task_default();
    HrtDenoiseShadowTask {
        context: 0,
        common: t.common,
        light: hrt_trace_shadow_task_default().light,
        input: t.input,
        output: t.output,
    }
}

#[no_mangle]
pub extern "C" fn hrt_denoise_specular_and_diffuse_task_default() -> HrtDenoiseSpecularAndDiffuseTask {
    let t = hrt_denoise_task_default();
    HrtDenoiseSpecularAndDiffuseTask {
        context: 0,
        common: t.common,
        input_specular: t.input,
        input_diffuse: t.input,
        output_specular: t.output,
        output_diffuse: t.output,
    }
}

/// Converts an HrtDenoiseTask with `make` and schedules it with `schedule`.
fn schedule_plain<T>(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseTask,
    make: impl FnOnce(rt::DenoisingContextHandle, rt::DenoisingCommon, rt::ImageInput, rt::ImageInput) -> T,
    schedule_task: impl FnOnce(&mut rt::TaskContainer, &T) -> rt::Result<()>,
) -> HrtStatus {
    schedule(
        container,
        task,
        |t| Ok(make(rt::DenoisingContextHandle(t.context), common(&t.common)?, image(&t.input), image(&t.output))),
        schedule_task,
    )
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_denoise_specular(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseTask,
) -> HrtStatus {
    schedule_plain(
        container,
        task,
        |context, common, input, output| rt::DenoiseSpecularTask { context, common, input, output },
        |c, t| c.schedule_denoise_specular(t),
    )
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_denoise_diffuse(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseTask,
) -> HrtStatus {
    schedule_plain(
        container,
        task,
        |context, common, input, output| rt::DenoiseDiffuseTask { context, common, input, output },
        |c, t| c.schedule_denoise_diffuse(t),
    )
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_denoise_diffuse_occlusion(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseTask,
) -> HrtStatus {
    schedule_plain(
        container,
        task,
        |context, common, input, output| rt::DenoiseDiffuseOcclusionTask { context, common, input, output },
        |c, t| c.schedule_denoise_diffuse_occlusion(t),
    )
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_denoise_multi_shadow(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseTask,
) -> HrtStatus {
    schedule_plain(
        container,
        task,
        |context, common, input, output| rt::DenoiseMultiShadowTask { context, common, input, output },
        |c, t| c.schedule_denoise_multi_shadow(t),
    )
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_denoise_shadow(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseShadowTask,
) -> HrtStatus {
    schedule(
        container,
        task,
        |t| {
            Ok(rt::DenoiseShadowTask {
                context: rt::DenoisingContextHandle(t.context),
                common: common(&t.common)?,
                light: light(&t.light)?,
                input: image(&t.input),
                output: image(&t.output),
            })
        },
        rt::TaskContainer::schedule_denoise_shadow,
    )
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_denoise_specular_and_diffuse(
    container: *mut HrtTaskContainer,
    task: *const HrtDenoiseSpecularAndDiffuseTask,
) -> HrtStatus {
    schedule(
        container,
        task,
        |t| {
            Ok(rt::DenoiseSpecularAndDiffuseTask {
                context: rt::DenoisingContextHandle(t.context),
                common: common(&t.common)?,
                input_specular: image(&t.input_specular),
                input_diffuse: image(&t.input_diffuse),
                output_specular: image(&t.output_specular),
                output_diffuse: image(&t.output_diffuse),
            })
        },
        rt::TaskContainer::schedule_denoise_specular_and_diffuse,
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_limit_is_the_sdk_one() {
        assert_eq!(super::HRT_MAX_DENOISING_EXTENT, hybrid_rt::MAX_DENOISING_EXTENT);
    }
}
