//! The scene: geometry and instance handles and their debug names, instance (TLAS) tasks, the
//! BVH build task and what the acceleration structures hold. Geometry (BLAS) tasks and build
//! hints are in `geometry`; a geometry's surfel settings, which shape its instances'
//! direct-lighting caches, are in `cache`.
//!
//! Transforms are row-major 3x4 float[12] (as VkTransformMatrixKHR).
mod geometry;

use crate::args::{pick, slice, string_arg};
use crate::context::{context, schedule, HrtContext, HrtTaskContainer, HrtTaskKind};
use crate::status::{guard, null, Failure, HrtStatus};
pub use geometry::*;
use hybrid_rt as rt;
use std::ffi::c_char;

pub type HrtGeometryHandle = u64;
pub type HrtInstanceHandle = u64;

/// All BVH work of the ticket.
pub const HRT_TASK_BVH: HrtTaskKind = 0;
/// Inside HRT_TASK_BVH: batched BLAS builds, refits and compactions.
pub const HRT_TASK_BLAS_BUILD: HrtTaskKind = 2;
/// Inside HRT_TASK_BVH: the TLAS build.
pub const HRT_TASK_TLAS_BUILD: HrtTaskKind = 3;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtInstanceOperation {
    HRT_INSTANCE_REGISTER = 0,
    HRT_INSTANCE_UPDATE = 1,
    HRT_INSTANCE_REMOVE = 2,
}

/// Bits of HrtInstanceInput::mask.
pub const HRT_MASK_REFLECTIONS: u32 = 1;
pub const HRT_MASK_DIFFUSE_GI: u32 = 2;
pub const HRT_MASK_AMBIENT_OCCLUSION: u32 = 4;
pub const HRT_MASK_SHADOWS: u32 = 8;
pub const HRT_MASK_LIGHT_INJECTION: u32 = 16;
pub const HRT_MASK_ALL: u32 = 31;

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtInstanceInput {
    pub geometry: HrtGeometryHandle,
    /// Object to world, row-major 3x4. Default identity.
    pub transform: [f32; 12],
    /// HRT_MASK_* bits. Default HRT_MASK_ALL.
    pub mask: u32,
    /// Default black.
    pub initial_tile_color: [f32; 3],
    /// Diffuse albedo for HrtRelightCacheTask and hit lighting (each 0..=1). Default 0.5 grey.
    pub albedo: [f32; 3],
    /// Emitted radiance relighting and hit lighting add (each finite, >= 0). Default black.
    pub emission: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtInstanceTask {
    pub handle: HrtInstanceHandle,
    /// An HrtInstanceOperation.
    pub operation: u32,
    pub input: HrtInstanceInput,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtBvhBuildTask {
    /// Default 4.
    pub max_blas_build_count: u32,
    /// Times in a row a TLAS may be refit instead of rebuilt when only instance transforms
    /// changed. Default 0: always rebuilt.
    pub tlas_max_refits: u32,
}

fn instance_task(t: &HrtInstanceTask) -> Result<rt::InstanceTask, Failure> {
    if t.input.mask > HRT_MASK_ALL {
        return Err(Failure(
            HrtStatus::HRT_ERROR_INVALID_INPUT,
            format!("invalid HrtInstanceInput.mask: {:#x} has bits outside HRT_MASK_ALL", t.input.mask),
        ));
    }
    let transform = affine(&t.input.transform);
    Ok(rt::InstanceTask {
        handle: rt::InstanceHandle(t.handle),
        operation: pick(
            "HrtInstanceTask.operation",
            t.operation,
            &[rt::InstanceOperation::Register, rt::InstanceOperation::Update, rt::InstanceOperation::Remove],
        )?,
        input: rt::InstanceInput {
            geometry: rt::GeometryHandle(t.input.geometry),
            transform,
            mask: rt::InstanceInclusionMask::from_bits_truncate(t.input.mask as u8),
            initial_tile_color: t.input.initial_tile_color,
            albedo: t.input.albedo,
            emission: t.input.emission,
        },
    })
}

#[no_mangle]
pub extern "C" fn hrt_instance_task_default() -> HrtInstanceTask {
    let d = rt::InstanceInput::default();
    HrtInstanceTask {
        handle: 0,
        operation: rt::InstanceOperation::Register as u32,
        input: HrtInstanceInput {
            geometry: 0,
            transform: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            mask: d.mask.bits() as u32,
            initial_tile_color: d.initial_tile_color,
            albedo: d.albedo,
            emission: d.emission,
        },
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_instance(container: *mut HrtTaskContainer, task: *const HrtInstanceTask) -> HrtStatus {
    schedule(container, task, instance_task, rt::TaskContainer::schedule_instance)
}

#[no_mangle]
pub extern "C" fn hrt_bvh_build_task_default() -> HrtBvhBuildTask {
    let d = rt::BvhBuildTask::default();
    HrtBvhBuildTask { max_blas_build_count: d.max_blas_build_count, tlas_max_refits: d.tlas_max_refits }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_bvh_build(container: *mut HrtTaskContainer, task: *const HrtBvhBuildTask) -> HrtStatus {
    schedule(
        container,
        task,
        |t| Ok(rt::BvhBuildTask { max_blas_build_count: t.max_blas_build_count, tlas_max_refits: t.tlas_max_refits }),
        rt::TaskContainer::schedule_bvh_build,
    )
}

/// Writes `count` new handles to `out` (which may be NULL when `count` is 0).
unsafe fn create_handles<H>(
    ctx: *mut HrtContext,
    count: u32,
    out: *mut u64,
    create: impl FnOnce(&rt::ExecuteContext, usize) -> Vec<H>,
    raw: impl Fn(H) -> u64,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        if count > 0 && out.is_null() {
            return Err(null("out"));
        }
        for (i, h) in create(&c.ctx, count as usize).into_iter().enumerate() {
            unsafe { *out.add(i) = raw(h) };
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_create_geometry_handles(ctx: *mut HrtContext, count: u32, out: *mut HrtGeometryHandle) -> HrtStatus {
    create_handles(ctx, count, out, rt::ExecuteContext::create_geometry_handles, |h| h.0)
}

/// Destroys the `count` handles at `handles` (which may be NULL when `count` is 0).
unsafe fn destroy_handles<H>(
    ctx: *mut HrtContext,
    handles: *const u64,
    count: u32,
    handle: impl Fn(u64) -> H,
    destroy: impl FnOnce(&rt::ExecuteContext, &[H]) -> rt::Result<()>,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let hs: Vec<H> = slice(handles, count, "handles")?.iter().map(|&h| handle(h)).collect();
        Ok(destroy(&c.ctx, &hs)?)
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_geometry_handles(
    ctx: *mut HrtContext,
    handles: *const HrtGeometryHandle,
    count: u32,
) -> HrtStatus {
    destroy_handles(ctx, handles, count, rt::GeometryHandle, rt::ExecuteContext::destroy_geometry_handles)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_create_instance_handles(ctx: *mut HrtContext, count: u32, out: *mut HrtInstanceHandle) -> HrtStatus {
    create_handles(ctx, count, out, rt::ExecuteContext::create_instance_handles, |h| h.0)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_instance_handles(
    ctx: *mut HrtContext,
    handles: *const HrtInstanceHandle,
    count: u32,
) -> HrtStatus {
    destroy_handles(ctx, handles, count, rt::InstanceHandle, rt::ExecuteContext::destroy_instance_handles)
}

/// One new geometry handle (`hrt_create_geometry_handles` with a count of 1).
#[no_mangle]
pub unsafe extern "C" fn hrt_create_geometry_handle(ctx: *mut HrtContext, out: *mut HrtGeometryHandle) -> HrtStatus {
    create_handles(ctx, 1, out, rt::ExecuteContext::create_geometry_handles, |h| h.0)
}

/// One new instance handle (`hrt_create_instance_handles` with a count of 1).
#[no_mangle]
pub unsafe extern "C" fn hrt_create_instance_handle(ctx: *mut HrtContext, out: *mut HrtInstanceHandle) -> HrtStatus {
    create_handles(ctx, 1, out, rt::ExecuteContext::create_instance_handles, |h| h.0)
}

/// Destroys one geometry (`hrt_destroy_geometry_handles` with a count of 1).
#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_geometry_handle(ctx: *mut HrtContext, handle: HrtGeometryHandle) -> HrtStatus {
    destroy_handles(ctx, &handle, 1, rt::GeometryHandle, rt::ExecuteContext::destroy_geometry_handles)
}

/// Destroys one instance (`hrt_destroy_instance_handles` with a count of 1).
#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_instance_handle(ctx: *mut HrtContext, handle: HrtInstanceHandle) -> HrtStatus {
    destroy_handles(ctx, &handle, 1, rt::InstanceHandle, rt::ExecuteContext::destroy_instance_handles)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_all_instance_handles(ctx: *mut HrtContext) -> HrtStatus {
    guard(|| {
        context(ctx)?.ctx.destroy_all_instance_handles();
        Ok(())
    })
}

/// Destroys every geometry, all-or-nothing: HRT_ERROR_GEOMETRY_IN_USE while an instance still
/// places one (destroy the instances first).
#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_all_geometry_handles(ctx: *mut HrtContext) -> HrtStatus {
    guard(|| Ok(context(ctx)?.ctx.destroy_all_geometry_handles()?))
}

/// Gives a geometry a debug name (NUL-terminated, copied): quoted in errors and log messages,
/// and the Vulkan name of its BLAS and copy when debug_utils is on.
#[no_mangle]
pub unsafe extern "C" fn hrt_set_geometry_name(
    ctx: *const HrtContext,
    geometry: HrtGeometryHandle,
    name: *const c_char,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        Ok(c.ctx.set_geometry_name(rt::GeometryHandle(geometry), &string_arg(name, "name")?)?)
    })
}

/// Gives an instance a debug name (NUL-terminated, copied), quoted in errors and log messages.
#[no_mangle]
pub unsafe extern "C" fn hrt_set_instance_name(
    ctx: *const HrtContext,
    instance: HrtInstanceHandle,
    name: *const c_char,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        Ok(c.ctx.set_instance_name(rt::InstanceHandle(instance), &string_arg(name, "name")?)?)
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_pending_blas_builds(ctx: *const HrtContext) -> u32 {
    context(ctx).map_or(0, |c| c.ctx.pending_blas_builds() as u32)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_tlas_instance_count(ctx: *const HrtContext) -> u32 {
    context(ctx).map_or(0, |c| c.ctx.tlas_instance_count() as u32)
}
