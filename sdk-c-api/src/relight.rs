//! Cache relighting in C (see the Rust docs of `hybrid_rt::RelightCacheTask`): the engine's
//! lights light the cache samples no camera has injected.
use crate::status::{guard, HrtStatus};
use crate::types::{light, HrtLightInfo};
use crate::{container_mut, get, slice, HrtTaskContainer};
use hybrid_rt as rt;

/// Lights cache samples no camera has injected from the engine's lights, with shadow rays:
/// albedo (HrtInstanceInput.albedo) x the lights' irradiance (intensity x color; directional:
/// irradiance at normal incidence, point/spot: / d²). The lights are copied when the task is
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
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        let lights = slice(t.lights, t.light_count, "task->lights")?;
        Ok(c.inner.schedule_cache_relight(&rt::RelightCacheTask {
            lights: lights.iter().map(light).collect::<Result<_, _>>()?,
            max_samples: t.max_samples,
            history_frames: t.history_frames,
            bounce: t.bounce,
            sky: t.sky,
        })?)
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_limit_is_the_sdk_one() {
        assert_eq!(crate::HRT_MAX_RELIGHT_SAMPLES, hybrid_rt::MAX_RELIGHT_SAMPLES);
    }
}
