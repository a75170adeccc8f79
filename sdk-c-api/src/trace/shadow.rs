//! Lights and the shadow traces: `HrtLightInfo` (which relighting, hit lighting and the
//! shadow denoiser take too), one light's shadow and up to HRT_MAX_SHADOW_LIGHTS lights'
//! shadows in one pass.
use super::{hrt_trace_common_default, trace_common, HrtTraceCommon};
use crate::args::{pick, slice};
use crate::context::{schedule, HrtTaskContainer, HrtTaskKind};
use crate::image::{image, image_c, HrtImageInput};
use crate::status::{Failure, HrtStatus};
use hybrid_rt as rt;

/// Most lights one HrtTraceMultiShadowTask traces.
pub const HRT_MAX_SHADOW_LIGHTS: u32 = 32;
/// Most per-light outputs of one HrtTraceMultiShadowTask.
pub const HRT_MAX_LIGHT_OUTPUTS: u32 = 4;

pub const HRT_TASK_SHADOW: HrtTaskKind = 7;
pub const HRT_TASK_MULTI_SHADOW: HrtTaskKind = 10;
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtLightType {
    HRT_LIGHT_DIRECTIONAL = 0,
    HRT_LIGHT_POINT = 1,
    HRT_LIGHT_SPOT = 2,
}

/// A light (see the Rust docs of LightInfo).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtLightInfo {
    /// An HrtLightType. Default HRT_LIGHT_DIRECTIONAL.
    pub light_type: u32,
    pub position: [f32; 3],
    /// The direction the light travels. Default (0, -1, 0).
    pub direction: [f32; 3],
    /// Directional: apparent diameter in radians. Default 0 (hard).
    pub angular_extent: f32,
    /// Point/spot: emitter radius. Default 0 (hard).
    pub radius: f32,
    /// Spot: full strength inside this half-angle (radians). Default 0.5.
    pub inner_cone: f32,
    /// Spot: unlit outside this half-angle (< pi/2). Default 0.6.
    pub outer_cone: f32,
    /// Point/spot: influence ends at this distance; 0 = unlimited (default).
    pub range: f32,
    /// Weight in the multi-light mean (>= 0); HrtRelightCacheTask's brightness. Default 1.
    pub intensity: f32,
    /// Linear RGB (each >= 0), used by HrtRelightCacheTask. Default white.
    pub color: [f32; 3],
}

/// One light of an HrtTraceMultiShadowTask written on its own, in HrtTraceShadowTask's output
/// format (for a DenoiseShadow task).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtLightShadowOutput {
    /// Index into the task's lights.
    pub light: u32,
    pub output: HrtImageInput,
}

/// Shadows from one light: R = closest occluder distance, negative where visible; G (if
/// present) = fraction of rays that reached the light.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceShadowTask {
    pub common: HrtTraceCommon,
    pub light: HrtLightInfo,
    /// GENERAL layout, STORAGE usage, a float format.
    pub output: HrtImageInput,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// Stop at the first occluder found (R is then an occluder's distance, >= the closest).
    /// Default false.
    pub first_hit: bool,
    /// Occluders farther than this from the surface do not shadow it (world units, > 0).
    /// Default unlimited (INFINITY).
    pub max_ray_length: f32,
}

/// Shadows from 1..=16 lights in one pass (see the Rust docs of TraceMultiShadowTask): the
/// lights are copied when the task is scheduled.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceMultiShadowTask {
    pub common: HrtTraceCommon,
    pub lights: *const HrtLightInfo,
    pub light_count: u32,
    /// R32_UINT (<= 4 lights) or R32G32B32A32_UINT: 8 bits of visible fraction per light, lights 0..16.
    pub visibility: HrtImageInput,
    /// Lights 16..32, the same way (image = VK_NULL_HANDLE with 16 lights or fewer).
    pub visibility_high: HrtImageInput,
    /// RGBA16F/32F for the multi-shadow denoiser: irradiance-weighted visibility, ...
    pub packed: HrtImageInput,
    /// The first light_output_count entries: lights written on their own.
    pub light_outputs: [HrtLightShadowOutput; 4],
    /// 0..=HRT_MAX_LIGHT_OUTPUTS. Default 0.
    pub light_output_count: u32,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// First-hit traversal (see HrtTraceShadowTask). Default false.
    pub first_hit: bool,
    /// As HrtTraceShadowTask's, for every light. Default unlimited (INFINITY).
    pub max_ray_length: f32,
}

pub(crate) fn light(l: &HrtLightInfo) -> Result<rt::LightInfo, Failure> {
    Ok(rt::LightInfo {
        light_type: pick(
            "HrtLightInfo.light_type",
            l.light_type,
            &[rt::LightType::Directional, rt::LightType::Point, rt::LightType::Spot],
        )?,
        position: glam::Vec3::from_array(l.position),
        direction: glam::Vec3::from_array(l.direction),
        angular_extent: l.angular_extent,
        radius: l.radius,
        inner_cone: l.inner_cone,
        outer_cone: l.outer_cone,
        range: l.range,
        intensity: l.intensity,
        color: l.color,
    })
}

/// `n` lights at `p` (`what` names the field in the NULL message).
pub(crate) fn lights(p: *const HrtLightInfo, n: u32, what: &str) -> Result<Vec<rt::LightInfo>, Failure> {
    slice(p, n, what)?.iter().map(light).collect()
}

pub(crate) fn light_c(l: &rt::LightInfo) -> HrtLightInfo {
    HrtLightInfo {
        light_type: l.light_type as u32,
        position: l.position.to_array(),
        direction: l.direction.to_array(),
        angular_extent: l.angular_extent,
        radius: l.radius,
        inner_cone: l.inner_cone,
        outer_cone: l.outer_cone,
        range: l.range,
        intensity: l.intensity,
        color: l.color,
    }
}

fn shadow_task(t: &HrtTraceShadowTask) -> Result<rt::TraceShadowTask, Failure> {
    Ok(rt::TraceShadowTask {
        common: trace_common(&t.common)?,
        light: light(&t.light)?,
        output: image(&t.output),
        rays_per_pixel: t.rays_per_pixel,
        first_hit: t.first_hit,
        max_ray_length: t.max_ray_length,
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_shadow_task_default() -> HrtTraceShadowTask {
    let d = rt::TraceShadowTask::default();
    HrtTraceShadowTask {
        common: hrt_trace_common_default(),
        light: light_c(&d.light),
        output: image_c(&d.output),
        rays_per_pixel: d.rays_per_pixel,
        first_hit: d.first_hit,
        max_ray_length: d.max_ray_length,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_shadow(container: *mut HrtTaskContainer, task: *const HrtTraceShadowTask) -> HrtStatus {
    schedule(container, task, shadow_task, rt::TaskContainer::schedule_shadow)
}

fn multi_shadow_task(t: &HrtTraceMultiShadowTask) -> Result<rt::TraceMultiShadowTask, Failure> {
    let lights = slice(t.lights, t.light_count, "task->lights")?;
    Ok(rt::TraceMultiShadowTask {
        common: trace_common(&t.common)?,
        lights: lights.iter().map(light).collect::<Result<_, _>>()?,
        visibility: image(&t.visibility),
        visibility_high: image(&t.visibility_high),
        packed: image(&t.packed),
        light_outputs: {
            let n = t.light_output_count as usize;
            if n > t.light_outputs.len() {
                return Err(Failure(
                    HrtStatus::HRT_ERROR_INVALID_INPUT,
                    format!("light_output_count {n}: at most {}", t.light_outputs.len()),
                ));
            }
            t.light_outputs[..n].iter().map(|o| rt::LightShadowOutput { light: o.light, output: image(&o.output) }).collect()
        },
        rays_per_pixel: t.rays_per_pixel,
        first_hit: t.first_hit,
        max_ray_length: t.max_ray_length,
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_multi_shadow_task_default() -> HrtTraceMultiShadowTask {
    let d = rt::TraceMultiShadowTask::default();
    let out = image_c(&d.visibility);
    HrtTraceMultiShadowTask {
        common: hrt_trace_common_default(),
        lights: std::ptr::null(),
        light_count: 0,
        visibility: out,
        // A read-only layout, unlike the SDK's default (the field is optional).
        visibility_high: image_c(&rt::ImageInput::default()),
        packed: image_c(&d.packed),
        light_outputs: [HrtLightShadowOutput { light: 0, output: out }; 4],
        light_output_count: 0,
        rays_per_pixel: d.rays_per_pixel,
        first_hit: d.first_hit,
        max_ray_length: d.max_ray_length,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_multi_shadow(
    container: *mut HrtTaskContainer,
    task: *const HrtTraceMultiShadowTask,
) -> HrtStatus {
    schedule(container, task, multi_shadow_task, rt::TaskContainer::schedule_multi_shadow)
}

#[cfg(test)]
mod tests {
    /// The C constants are the Rust SDK's limits.
    #[test]
    fn limits_match_the_sdk() {
        assert_eq!(super::HRT_MAX_SHADOW_LIGHTS as usize, hybrid_rt::MAX_SHADOW_LIGHTS);
        assert_eq!(super::HRT_MAX_LIGHT_OUTPUTS as usize, hybrid_rt::MAX_LIGHT_OUTPUTS);
    }
}
