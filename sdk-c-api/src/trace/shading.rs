//! Shading traces that read the direct-lighting caches: diffuse GI and specular reflections,
//! the environment map both see where rays miss, and hit lighting for smooth reflections.
use super::{hrt_trace_common_default, lights, trace_common, HrtLightInfo, HrtTraceCommon};
use crate::args::pick;
use crate::context::{schedule, HrtTaskContainer, HrtTaskKind};
use crate::image::{image, image_c, HrtImageInput};
use crate::status::{Failure, HrtStatus};
use hybrid_rt as rt;

/// Most gather rays per hit of HrtHitLighting.
pub const HRT_MAX_HIT_GATHER_RAYS: u32 = 8;

pub const HRT_TASK_DIFFUSE: HrtTaskKind = 8;
pub const HRT_TASK_SPECULAR: HrtTaskKind = 9;

/// Diffuse GI shaded from the cache: RGB = mean incoming radiance (E/pi, multiply by albedo),
/// A = mean hit distance.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceDiffuseTask {
    pub common: HrtTraceCommon,
    /// GENERAL layout, STORAGE usage, RGBA16F or RGBA32F.
    pub output: HrtImageInput,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// Default 1000.
    pub ray_length: f32,
    /// Radiance of rays that hit nothing. Default black.
    pub miss_radiance: [f32; 3],
    /// An HrtDiffuseBrdfType. Default HRT_DIFFUSE_LAMBERTIAN.
    pub brdf: u32,
    /// Optional (environment.image = VK_NULL_HANDLE: none): what misses see.
    pub environment: HrtEnvironmentInput,
}

/// A lat-long environment map for rays that miss (see the Rust docs of EnvironmentInput):
/// u = 0.5 + atan2(d.x, -d.z) / 2pi, v = acos(d.y) / pi, bilinear, u wraps.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtEnvironmentInput {
    /// Any size, SAMPLED usage, a read-only layout.
    pub image: HrtImageInput,
    /// Column-major rotation: the map's frame in world space. Default identity.
    pub rotation: [f32; 9],
    /// Default 1.
    pub intensity: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDiffuseBrdfType {
    HRT_DIFFUSE_LAMBERTIAN = 0,
    HRT_DIFFUSE_NORMALIZED_DISNEY = 1,
}

/// Specular reflections shaded from the cache (see the Rust docs of TraceSpecularTask).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceSpecularTask {
    pub common: HrtTraceCommon,
    /// GENERAL layout, STORAGE usage, RGBA16F or RGBA32F.
    pub output: HrtImageInput,
    /// 1..=64 (mirrors trace one). Default 1.
    pub rays_per_pixel: u32,
    /// Default 1000.
    pub ray_length: f32,
    /// Default black.
    pub miss_radiance: [f32; 3],
    /// Largest luminance of one sample; 0 = off (default).
    pub firefly_clamp: f32,
    /// Optional (image = VK_NULL_HANDLE for none): the output without the specular colour.
    pub demodulated_output: HrtImageInput,
    /// Optional (environment.image = VK_NULL_HANDLE: none): what misses see.
    pub environment: HrtEnvironmentInput,
    /// Optional hit lighting for smooth pixels (hit_lighting.light_count = 0: off, default).
    pub hit_lighting: HrtHitLighting,
}

/// Hit lighting (see the Rust docs of HitLighting): hits of pixels with roughness up to
/// max_roughness are shaded from these lights with shadow rays (HrtInstanceInput.albedo x
/// irradiance + emission) plus an indirect part from the caches (an HrtHitIndirect). The
/// lights are copied when the task is scheduled.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtHitLighting {
    pub lights: *const HrtLightInfo,
    /// 0..=HRT_MAX_SHADOW_LIGHTS (0: off). Default 0.
    pub light_count: u32,
    /// 0..=1. Default 0.1.
    pub max_roughness: f32,
    /// An HrtHitIndirect. Default HRT_HIT_INDIRECT_CACHE_RESIDUAL.
    pub indirect: u32,
    /// Gather rays per hit with HRT_HIT_INDIRECT_GATHER, 1..=HRT_MAX_HIT_GATHER_RAYS. Default 1.
    pub gather_rays: u32,
}

/// HrtHitLighting.indirect (see the Rust docs of HitIndirect).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtHitIndirect {
    /// The cache sample less the listed lights' direct light there (no noise). Default.
    HRT_HIT_INDIRECT_CACHE_RESIDUAL = 0,
    /// gather_rays cosine rays reading the caches (noisy).
    HRT_HIT_INDIRECT_GATHER = 1,
    /// Direct light and emission only.
    HRT_HIT_INDIRECT_NONE = 2,
}

fn environment(e: &HrtEnvironmentInput) -> rt::EnvironmentInput {
    rt::EnvironmentInput { image: image(&e.image), rotation: glam::Mat3::from_cols_array(&e.rotation), intensity: e.intensity }
}

fn environment_c(e: &rt::EnvironmentInput) -> HrtEnvironmentInput {
    HrtEnvironmentInput { image: image_c(&e.image), rotation: e.rotation.to_cols_array(), intensity: e.intensity }
}

#[no_mangle]
pub extern "C" fn hrt_trace_diffuse_task_default() -> HrtTraceDiffuseTask {
    let d = rt::TraceDiffuseTask::default();
    HrtTraceDiffuseTask {
        common: hrt_trace_common_default(),
        output: image_c(&d.output),
        rays_per_pixel: d.rays_per_pixel,
        ray_length: d.ray_length,
        miss_radiance: d.miss_radiance,
        brdf: d.brdf as u32,
        environment: environment_c(&d.environment),
    }
}

fn diffuse_task(t: &HrtTraceDiffuseTask) -> Result<rt::TraceDiffuseTask, Failure> {
    Ok(rt::TraceDiffuseTask {
        common: trace_common(&t.common)?,
        output: image(&t.output),
        rays_per_pixel: t.rays_per_pixel,
        ray_length: t.ray_length,
        miss_radiance: t.miss_radiance,
        brdf: match t.brdf {
            0 => rt::DiffuseBrdfType::Lambertian,
            1 => rt::DiffuseBrdfType::NormalizedDisney,
            v => return Err(Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid HrtTraceDiffuseTask.brdf: {v}"))),
        },
        environment: environment(&t.environment),
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_diffuse(container: *mut HrtTaskContainer, task: *const HrtTraceDiffuseTask) -> HrtStatus {
    schedule(container, task, diffuse_task, rt::TaskContainer::schedule_diffuse)
}

#[no_mangle]
pub extern "C" fn hrt_trace_specular_task_default() -> HrtTraceSpecularTask {
    let d = rt::TraceSpecularTask::default();
    HrtTraceSpecularTask {
        common: hrt_trace_common_default(),
        output: image_c(&d.output),
        rays_per_pixel: d.rays_per_pixel,
        ray_length: d.ray_length,
        miss_radiance: d.miss_radiance,
        firefly_clamp: d.firefly_clamp,
        demodulated_output: image_c(&d.demodulated_output),
        environment: environment_c(&d.environment),
        hit_lighting: HrtHitLighting {
            lights: std::ptr::null(),
            light_count: 0,
            max_roughness: d.hit_lighting.max_roughness,
            indirect: d.hit_lighting.indirect as u32,
            gather_rays: d.hit_lighting.gather_rays,
        },
    }
}

fn specular_task(t: &HrtTraceSpecularTask) -> Result<rt::TraceSpecularTask, Failure> {
    let h = &t.hit_lighting;
    Ok(rt::TraceSpecularTask {
        common: trace_common(&t.common)?,
        output: image(&t.output),
        rays_per_pixel: t.rays_per_pixel,
        ray_length: t.ray_length,
        miss_radiance: t.miss_radiance,
        firefly_clamp: t.firefly_clamp,
        demodulated_output: image(&t.demodulated_output),
        environment: environment(&t.environment),
        hit_lighting: rt::HitLighting {
            lights: lights(h.lights, h.light_count, "task->hit_lighting.lights")?,
            max_roughness: h.max_roughness,
            indirect: pick(
                "HrtHitLighting.indirect",
                h.indirect,
                &[rt::HitIndirect::CacheResidual, rt::HitIndirect::Gather, rt::HitIndirect::None],
            )?,
            gather_rays: h.gather_rays,
        },
    })
}

/// # Safety
/// `container` from hrt_create_task_container; `task` valid, its `hit_lighting.lights`
/// `hit_lighting.light_count` long (or null with a count of 0).
#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_specular(container: *mut HrtTaskContainer, task: *const HrtTraceSpecularTask) -> HrtStatus {
    schedule(container, task, specular_task, rt::TaskContainer::schedule_specular)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_limit_is_the_sdk_one() {
        assert_eq!(super::HRT_MAX_HIT_GATHER_RAYS, hybrid_rt::MAX_HIT_GATHER_RAYS);
    }
}
