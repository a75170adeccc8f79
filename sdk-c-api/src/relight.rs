//! Relighting the direct-lighting caches from the engine's lights (see the Rust docs of
//! `hybrid_rt::RelightCacheTask`): the task, its default and its schedule function.
use crate::context::{schedule, HrtTaskContainer, HrtTaskKind};
use crate::status::HrtStatus;
use crate::trace::{lights, HrtLightInfo};
use hybrid_rt as rt;

/// Most samples one HrtRelightCacheTask may take.
pub const HRT_MAX_RELIGHT_SAMPLES: u32 = 1 << 24;

pub const HRT_TASK_CACHE_RELIGHT: HrtTaskKind = 17;

/// Lights cache samples no camera has injected from the engine's lights, with shadow rays:
/// albedo (HrtInstanceInput.albedo x the geometry's colors and albedo_texture, where given) x
/// the lights' irradiance (intensity x color; directional: irradiance at normal incidence,
/// point/spot: / d²) + HrtInstanceInput.emission. The lights are copied when the task is
/// scheduled.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtRelightCacheTask {
    pub lights: *const HrtLightInfo,
    /// 1..=HRT_MAX_SHADOW_LIGHTS.
    pub light_count: u32,
    /// Samples relit per build, at most (1..=HRT_MAX_RELIGHT_SAMPLES). Default 65536.
    pub max_samples: u32,
    /// Frames a relit sample's average runs over (1..=1024). Default 16.
    pub history_frames: u32,
    /// Gather one diffuse bounce from the caches (multi-bounce over builds). Default false.
    pub bounce: bool,
    /// Radiance of bounce rays that leave the scene (each >= 0). Default black.
    pub sky: [f32; 3],
}

#[no_mangle]
pub extern "C" fn hrt_relight_cache_task_default() -> HrtRelightCacheTask {
    let d = rt::RelightCacheTask::default();
    HrtRelightCacheTask {
        lights: std::ptr::null(),
        light_count: 0,
        max_samples: d.max_samples,
        history_frames: d.history_frames,
        bounce: d.bounce,
        sky: d.sky,
    }
}

/// # Safety
/// `container` from hrt_create_task_container; `task` valid, its `lights` `light_count` long.
#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_cache_relight(
    container: *mut HrtTaskContainer,
    task: *const HrtRelightCacheTask,
) -> HrtStatus {
    schedule(
        container,
        task,
        |t| {
            Ok(rt::RelightCacheTask {
                lights: lights(t.lights, t.light_count, "task->lights")?,
                max_samples: t.max_samples,
                history_frames: t.history_frames,
                bounce: t.bounce,
                sky: t.sky,
            })
        },
        rt::TaskContainer::schedule_cache_relight,
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_limit_is_the_sdk_one() {
        assert_eq!(super::HRT_MAX_RELIGHT_SAMPLES, hybrid_rt::MAX_RELIGHT_SAMPLES);
    }
}
