//! The direct-lighting caches: their layout on a geometry (`HrtSurfelSettings`), injecting a
//! lit view into them, clearing an instance's cache, transferring cached lighting between
//! instances, and their memory (one instance's bytes, the report under the budget).
//! Relighting the caches from lights is in `relight`.
use crate::args::{get_mut, pick};
use crate::context::{context, schedule, HrtContext, HrtTaskContainer, HrtTaskKind};
use crate::image::{image, image_c, HrtImageInput};
use crate::scene::HrtInstanceHandle;
use crate::status::{guard, Failure, HrtStatus};
use crate::trace::{camera, depth, hrt_trace_common_default, viewport, HrtCamera, HrtDepthInput, HrtViewport};
use hybrid_rt as rt;

/// Largest HrtSurfelSettings.tile_resolution_limit.
pub const HRT_MAX_TILE_RESOLUTION: u32 = 256;

pub const HRT_TASK_DIRECT_LIGHTING_INJECTION: HrtTaskKind = 4;
pub const HRT_TASK_CACHE_UPDATE: HrtTaskKind = 5;
pub const HRT_TASK_CACHE_TRANSFER: HrtTaskKind = 6;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtSurfelType {
    HRT_SURFEL_MESH_COLORS = 0,
    HRT_SURFEL_TILES = 1,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtSurfelSettings {
    /// An HrtSurfelType. Default HRT_SURFEL_MESH_COLORS.
    pub surfel_type: u32,
    /// Default 1.0.
    pub tile_unit_length: f32,
    /// Default 64.
    pub tile_resolution_limit: u32,
    /// Tiles only: one sample per triangle (direct tile mapping). Default false.
    pub force_direct_tile_mapping: bool,
    /// Tiles only: map directly when triangles > threshold x samples. Default 0.7.
    pub direct_tile_mapping_threshold: f32,
}

/// Bakes a lit view into the direct-lighting caches (see the Rust docs of
/// DirectLightingInjectionTask).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDirectLightingInjectionTask {
    pub depth: HrtDepthInput,
    /// The lit frame (RGB radiance), read-only layout, SAMPLED usage.
    pub lit: HrtImageInput,
    pub viewport: HrtViewport,
    pub camera: HrtCamera,
    /// Frames of the running average, >= 1. Default 200.
    pub average_window: f32,
    /// Inject one pixel of every stride x stride block, a different one each frame (1..=16).
    /// Default 1: every pixel.
    pub injection_resolution_stride: u32,
    /// Default false. Injection traces with the ray-tracing pipeline only: true is refused
    /// (HRT_ERROR_INVALID_INPUT).
    pub use_inline_rt: bool,
}

/// Copies one instance's cached lighting onto another covering the same surface (LODs).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDirectLightTransferTask {
    pub source: HrtInstanceHandle,
    pub target: HrtInstanceHandle,
    /// World-space distance the two surfaces may be apart (> 0). Default 0.1.
    pub max_distance: f32,
    /// Default true.
    pub enable_bilinear_sampling: bool,
}

/// Resets an instance's cache to its initial colour.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtClearCacheTask {
    pub instance: HrtInstanceHandle,
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

pub(crate) fn surfels(s: &HrtSurfelSettings) -> Result<rt::SurfelSettings, Failure> {
    Ok(rt::SurfelSettings {
        surfel_type: pick("HrtSurfelSettings.surfel_type", s.surfel_type, &[rt::SurfelType::MeshColors, rt::SurfelType::Tiles])?,
        tile_unit_length: s.tile_unit_length,
        tile_resolution_limit: s.tile_resolution_limit,
        force_direct_tile_mapping: s.force_direct_tile_mapping,
        direct_tile_mapping_threshold: s.direct_tile_mapping_threshold,
    })
}

pub(crate) fn surfels_c(s: &rt::SurfelSettings) -> HrtSurfelSettings {
    HrtSurfelSettings {
        surfel_type: s.surfel_type as u32,
        tile_unit_length: s.tile_unit_length,
        tile_resolution_limit: s.tile_resolution_limit,
        force_direct_tile_mapping: s.force_direct_tile_mapping,
        direct_tile_mapping_threshold: s.direct_tile_mapping_threshold,
    }
}

fn injection_task(t: &HrtDirectLightingInjectionTask) -> Result<rt::DirectLightingInjectionTask, Failure> {
    Ok(rt::DirectLightingInjectionTask {
        depth: depth(&t.depth)?,
        lit: image(&t.lit),
        viewport: viewport(&t.viewport),
        camera: camera(&t.camera),
        average_window: t.average_window,
        injection_resolution_stride: t.injection_resolution_stride,
        use_inline_rt: t.use_inline_rt,
    })
}

#[no_mangle]
pub extern "C" fn hrt_direct_lighting_injection_task_default() -> HrtDirectLightingInjectionTask {
    let d = rt::DirectLightingInjectionTask::default();
    let c = hrt_trace_common_default();
    HrtDirectLightingInjectionTask {
        depth: c.depth,
        lit: image_c(&d.lit),
        viewport: c.viewport,
        camera: c.camera,
        average_window: d.average_window,
        injection_resolution_stride: d.injection_resolution_stride,
        use_inline_rt: d.use_inline_rt,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_direct_lighting_injection(
    container: *mut HrtTaskContainer,
    task: *const HrtDirectLightingInjectionTask,
) -> HrtStatus {
    schedule(container, task, injection_task, rt::TaskContainer::schedule_direct_lighting_injection)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_clear_cache(container: *mut HrtTaskContainer, task: *const HrtClearCacheTask) -> HrtStatus {
    schedule(
        container,
        task,
        |t| Ok(rt::ClearCacheTask { instance: rt::InstanceHandle(t.instance) }),
        rt::TaskContainer::schedule_clear_cache,
    )
}

#[no_mangle]
pub extern "C" fn hrt_direct_light_transfer_task_default() -> HrtDirectLightTransferTask {
    let d = rt::DirectLightTransferTask::default();
    HrtDirectLightTransferTask {
        source: 0,
        target: 0,
        max_distance: d.max_distance,
        enable_bilinear_sampling: d.enable_bilinear_sampling,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_direct_light_transfer(
    container: *mut HrtTaskContainer,
    task: *const HrtDirectLightTransferTask,
) -> HrtStatus {
    schedule(
        container,
        task,
        |t| {
            Ok(rt::DirectLightTransferTask {
                source: rt::InstanceHandle(t.source),
                target: rt::InstanceHandle(t.target),
                max_distance: t.max_distance,
                enable_bilinear_sampling: t.enable_bilinear_sampling,
            })
        },
        rt::TaskContainer::schedule_direct_light_transfer,
    )
}

/// Bytes of an instance's direct-lighting cache (0 until allocated, one recording after the
/// ticket that registered its geometry came back).
#[no_mangle]
pub unsafe extern "C" fn hrt_instance_cache_bytes(
    ctx: *const HrtContext,
    instance: HrtInstanceHandle,
    bytes: *mut u64,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        *get_mut(bytes, "bytes")? = c.ctx.instance_cache_bytes(rt::InstanceHandle(instance))?;
        Ok(())
    })
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
        assert_eq!(super::HRT_MAX_TILE_RESOLUTION, hybrid_rt::MAX_TILE_RESOLUTION);
    }
}
