//! Many shadowed lights by resampling: many-lights contexts (a light list on the GPU and one
//! view's resampling history) and `HrtTraceManyLightsTask` (see the Rust docs of
//! `hybrid_rt::types::many_lights`).
use crate::args::{get, get_mut, slice};
use crate::context::{context, schedule, HrtContext, HrtTaskContainer, HrtTaskKind};
use crate::denoise::{motion, motion_c, HrtMotionInput};
use crate::image::{image, image_c, HrtImageInput};
use crate::status::{guard, Failure, HrtStatus};
use crate::trace::{hrt_trace_common_default, light, trace_common, HrtLightInfo, HrtTraceCommon};
use hybrid_rt as rt;

/// Most lights a many-lights context holds.
pub const HRT_MAX_MANY_LIGHTS: u32 = 1 << 20;
/// Largest HrtManyLightsContextInput.max_width / max_height.
pub const HRT_MAX_MANY_LIGHTS_EXTENT: u32 = 16384;

pub const HRT_TASK_MANY_LIGHTS: HrtTaskKind = 18;

pub type HrtManyLightsContextHandle = u64;

/// One view's many-lights context (see the Rust docs of ManyLightsContextInput).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtManyLightsContextInput {
    /// Largest viewport right edge, 1..=HRT_MAX_MANY_LIGHTS_EXTENT.
    pub max_width: u32,
    /// Largest viewport bottom edge, 1..=HRT_MAX_MANY_LIGHTS_EXTENT.
    pub max_height: u32,
    /// Lights the list may hold, 1..=HRT_MAX_MANY_LIGHTS. Default 65536.
    pub max_lights: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtResamplingMode {
    /// Sample-count weights: fast, slightly dark where neighbours cannot see a light (default).
    HRT_RESAMPLING_BIASED = 0,
    /// Weights over the pixels that could have produced the sample (a shadow ray per neighbour).
    HRT_RESAMPLING_UNBIASED = 1,
    /// No resampling: lights drawn by power, a shadow ray each (the baseline).
    HRT_RESAMPLING_POWER_SAMPLING = 2,
}

/// How a task changes the context's light list.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtLightListOperation {
    /// The lights of the context's previous task (default).
    HRT_LIGHT_LIST_KEEP = 0,
    /// A new list: `lights[0..light_count]`.
    HRT_LIGHT_LIST_REPLACE = 1,
    /// Lights `first_light..first_light + light_count` overwritten (the list grows past its end).
    HRT_LIGHT_LIST_WRITE = 2,
}

/// Resampling settings (see the Rust docs of ManyLightsSettings for each default).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtManyLightsSettings {
    /// An HrtResamplingMode.
    pub mode: u32,
    pub initial_candidates: u32,
    pub spatial_samples: u32,
    pub spatial_radius: f32,
    pub max_history: u32,
    /// Biased mode: test the candidates' visibility (a ray a pixel more). Default false.
    pub candidate_visibility: bool,
}

/// Direct lighting from the context's lights by resampling (see the Rust docs of
/// TraceManyLightsTask): demodulated diffuse and specular, hit distance in A. The lights are
/// copied when the task is scheduled.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceManyLightsTask {
    pub context: HrtManyLightsContextHandle,
    pub common: HrtTraceCommon,
    /// Optional (image = VK_NULL_HANDLE: reproject with the cameras, static scenes only).
    pub motion: HrtMotionInput,
    /// An HrtLightListOperation. Default HRT_LIGHT_LIST_KEEP.
    pub light_operation: u32,
    /// HRT_LIGHT_LIST_WRITE: the first light written.
    pub first_light: u32,
    pub lights: *const HrtLightInfo,
    pub light_count: u32,
    /// RGBA16F or RGBA32F, GENERAL, STORAGE usage.
    pub diffuse_output: HrtImageInput,
    /// RGBA16F or RGBA32F, GENERAL, STORAGE usage.
    pub specular_output: HrtImageInput,
    /// Optional: RGB = a colour per chosen light, A = the reservoir's sample count.
    pub debug_output: HrtImageInput,
    pub settings: HrtManyLightsSettings,
    /// Default false.
    pub reset_history: bool,
}

fn settings(s: &HrtManyLightsSettings) -> Result<rt::ManyLightsSettings, Failure> {
    use rt::ResamplingMode as M;
    let mode = *[M::Biased, M::Unbiased, M::PowerSampling]
        .get(s.mode as usize)
        .ok_or_else(|| Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid HrtManyLightsSettings.mode: {}", s.mode)))?;
    Ok(rt::ManyLightsSettings {
        mode,
        initial_candidates: s.initial_candidates,
        spatial_samples: s.spatial_samples,
        spatial_radius: s.spatial_radius,
        max_history: s.max_history,
        candidate_visibility: s.candidate_visibility,
    })
}

fn many_lights_task(t: &HrtTraceManyLightsTask) -> Result<rt::TraceManyLightsTask, Failure> {
    let lights =
        || -> Result<Vec<rt::LightInfo>, Failure> { slice(t.lights, t.light_count, "task->lights")?.iter().map(light).collect() };
    let update = match t.light_operation {
        0 => rt::LightListUpdate::Keep,
        1 => rt::LightListUpdate::Replace(lights()?),
        2 => rt::LightListUpdate::Write { first: t.first_light, lights: lights()? },
        v => {
            return Err(Failure(
                HrtStatus::HRT_ERROR_INVALID_INPUT,
                format!("invalid HrtTraceManyLightsTask.light_operation: {v}"),
            ))
        }
    };
    Ok(rt::TraceManyLightsTask {
        context: rt::ManyLightsContextHandle(t.context),
        common: trace_common(&t.common)?,
        motion: motion(&t.motion)?,
        lights: update,
        diffuse_output: image(&t.diffuse_output),
        specular_output: image(&t.specular_output),
        debug_output: image(&t.debug_output),
        settings: settings(&t.settings)?,
        reset_history: t.reset_history,
    })
}

#[no_mangle]
pub extern "C" fn hrt_many_lights_context_input_default() -> HrtManyLightsContextInput {
    let d = rt::ManyLightsContextInput::default();
    HrtManyLightsContextInput { max_width: d.max_width, max_height: d.max_height, max_lights: d.max_lights }
}

/// Creates a many-lights context (its light list and history are allocated now).
#[no_mangle]
pub unsafe extern "C" fn hrt_create_many_lights_context(
    ctx: *mut HrtContext,
    input: *const HrtManyLightsContextInput,
    out: *mut HrtManyLightsContextHandle,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let i = get(input, "input")?;
        let out = get_mut(out, "out")?;
        let h = c.ctx.create_many_lights_context(&rt::ManyLightsContextInput {
            max_width: i.max_width,
            max_height: i.max_height,
            max_lights: i.max_lights,
        })?;
        *out = h.0;
        Ok(())
    })
}

/// Destroys a many-lights context; its buffers are freed once the tickets issued so far return.
#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_many_lights_context(ctx: *mut HrtContext, handle: HrtManyLightsContextHandle) -> HrtStatus {
    guard(|| Ok(context(ctx)?.ctx.destroy_many_lights_context(rt::ManyLightsContextHandle(handle))?))
}

#[no_mangle]
pub extern "C" fn hrt_trace_many_lights_task_default() -> HrtTraceManyLightsTask {
    let d = rt::TraceManyLightsTask::default();
    let s = d.settings;
    HrtTraceManyLightsTask {
        context: d.context.0,
        common: hrt_trace_common_default(),
        motion: motion_c(&d.motion),
        light_operation: HrtLightListOperation::HRT_LIGHT_LIST_KEEP as u32,
        first_light: 0,
        lights: std::ptr::null(),
        light_count: 0,
        diffuse_output: image_c(&d.diffuse_output),
        specular_output: image_c(&d.specular_output),
        debug_output: image_c(&d.debug_output),
        settings: HrtManyLightsSettings {
            mode: s.mode as u32,
            initial_candidates: s.initial_candidates,
            spatial_samples: s.spatial_samples,
            spatial_radius: s.spatial_radius,
            max_history: s.max_history,
            candidate_visibility: s.candidate_visibility,
        },
        reset_history: d.reset_history,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_many_lights(
    container: *mut HrtTaskContainer,
    task: *const HrtTraceManyLightsTask,
) -> HrtStatus {
    schedule(container, task, many_lights_task, rt::TaskContainer::schedule_many_lights)
}

#[cfg(test)]
mod tests {
    /// The C constants are the Rust SDK's limits.
    #[test]
    fn limits_match_the_sdk() {
        assert_eq!(super::HRT_MAX_MANY_LIGHTS, hybrid_rt::MAX_MANY_LIGHTS);
        assert_eq!(super::HRT_MAX_MANY_LIGHTS_EXTENT, hybrid_rt::MAX_MANY_LIGHTS_EXTENT);
    }
}
