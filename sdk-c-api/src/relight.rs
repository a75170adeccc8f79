//! The direct-lighting cache's own C entry points: relighting (see the Rust docs of
//! `hybrid_rt::RelightCacheTask`) and the cache's memory under its budget (`CacheReport`).
use crate::status::{guard, HrtStatus};
use crate::types::{light, HrtLightInfo};
use crate::{container_mut, context, get, get_mut, slice, HrtContext, HrtTaskContainer};
use hybrid_rt as rt;

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

/// The direct-lighting caches' memory under HrtInitSettings.cache_budget_bytes.
#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct HrtCacheReport {
    /// Bytes of the caches held now.
    pub resident_bytes: u64,
    /// The budget (0: none).
    pub budget_bytes: u64,
    /// Placed instances without a cache (evicted, or waiting for room): they read as their
    /// initial colour until used.
    pub waiting_instances: u32,
    /// Caches evicted since the context was made, and their bytes.
    pub evictions: u64,
    pub evicted_bytes: u64,
    /// Geometry bytes copied to the host to size surfel layouts (0 unless a mesh was too big
    /// for the GPU layout passes).
    pub geometry_readback_bytes: u64,
}

/// # Safety
/// `ctx` from hrt_context_create; `out` writable.
#[no_mangle]
pub unsafe extern "C" fn hrt_cache_report(ctx: *const HrtContext, out: *mut HrtCacheReport) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let r = c.ctx.cache_report();
        *get_mut(out, "out")? = HrtCacheReport {
            resident_bytes: r.resident_bytes,
            budget_bytes: r.budget_bytes,
            waiting_instances: r.waiting_instances,
            evictions: r.evictions,
            evicted_bytes: r.evicted_bytes,
            geometry_readback_bytes: r.geometry_readback_bytes,
        };
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_limit_is_the_sdk_one() {
        assert_eq!(crate::HRT_MAX_RELIGHT_SAMPLES, hybrid_rt::MAX_RELIGHT_SAMPLES);
        assert_eq!(crate::HRT_MAX_HIT_GATHER_RAYS, hybrid_rt::MAX_HIT_GATHER_RAYS);
        assert_eq!(crate::HRT_MAX_ALBEDO_TEXTURE_SIZE, hybrid_rt::MAX_ALBEDO_TEXTURE_SIZE);
    }
}
