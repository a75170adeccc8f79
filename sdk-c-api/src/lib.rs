//! The C ABI of hybrid-rt. The header `include/hybrid_rt.h` is generated from this crate by
//! cbindgen (`HRT_BLESS=1 cargo test -p hybrid-rt-c header` rewrites it; the same test fails
//! when it is stale).
//!
//! Conventions: every function returns an `HrtStatus` (or a plain value that cannot fail);
//! output goes through pointers; a NULL required pointer is `HRT_ERROR_NULL_POINTER`; on error
//! `hrt_last_error_message` holds a message for the calling thread. No panic crosses this
//! boundary. Contexts and containers are opaque pointers; geometry and instance handles and
//! tickets are 64-bit integers that the SDK checks (stale, foreign, returned twice).
#![allow(non_camel_case_types, clippy::missing_safety_doc)]
mod denoise;
mod live;
mod log_bridge;
mod relight;
mod status;
mod types;

use ash::vk;
use ash::vk::Handle;
pub use denoise::*;
use hybrid_rt as rt;
pub use log_bridge::{HrtLogCallback, HrtLogSeverity};
pub use status::HrtStatus;
use status::{guard, null, Failure};
use std::ffi::{c_char, c_void, CStr};
pub use types::*;

/// The API version this header describes: (major << 22) | (minor << 12) | patch.
pub const HRT_API_VERSION: u32 = 1 << 12; // (major 0 << 22) | (minor 1 << 12) | patch 0

/// Most lights one HrtTraceMultiShadowTask traces.
pub const HRT_MAX_SHADOW_LIGHTS: u32 = 32;
/// Most per-light outputs of one HrtTraceMultiShadowTask.
pub const HRT_MAX_LIGHT_OUTPUTS: u32 = 4;
/// The most texels a side of a geometry's copy of its albedo texture (HrtGeometryInput.albedo_texture).
pub const HRT_MAX_ALBEDO_TEXTURE_SIZE: u32 = 256;
/// Most gather rays per hit of HrtHitLighting.
pub const HRT_MAX_HIT_GATHER_RAYS: u32 = 8;
/// Most samples one HrtRelightCacheTask may take.
pub const HRT_MAX_RELIGHT_SAMPLES: u32 = 1 << 24;
/// Largest HrtSurfelSettings.tile_resolution_limit.
pub const HRT_MAX_TILE_RESOLUTION: u32 = 256;
/// Largest HrtDenoisingContextInput.max_width / max_height.
pub const HRT_MAX_DENOISING_EXTENT: u32 = 16384;

/// Opaque context. Thread-safe: any call from any thread, except that hrt_context_destroy
/// must not race another call on it or its containers.
pub struct HrtContext {
    pub(crate) ctx: rt::ExecuteContext,
    // Keeps the loader library alive when the SDK loaded it itself.
    _entry: ash::Entry,
}

/// Opaque task container: used by one thread at a time (fill on one, build on any).
pub struct HrtTaskContainer {
    pub(crate) inner: rt::TaskContainer,
}

/// A live context (see `live`): NULL is HRT_ERROR_NULL_POINTER, a destroyed or foreign pointer
/// HRT_ERROR_INVALID_HANDLE.
pub(crate) fn context<'a>(p: *const HrtContext) -> Result<&'a HrtContext, Failure> {
    live::check(p, live::Kind::Context, "ctx")?;
    // SAFETY: registered pointers come from Box::into_raw and are live until destroyed.
    Ok(unsafe { &*p })
}

/// A live task container (see `context`).
pub(crate) fn container_mut<'a>(p: *mut HrtTaskContainer) -> Result<&'a mut HrtTaskContainer, Failure> {
    live::check(p, live::Kind::Container, "container")?;
    // SAFETY: as for `context`; a container is filled on one thread at a time (the header says).
    Ok(unsafe { &mut *p })
}

pub(crate) fn get<'a, T>(p: *const T, what: &str) -> Result<&'a T, Failure> {
    // SAFETY: the caller passes a valid pointer or NULL (checked).
    unsafe { p.as_ref() }.ok_or_else(|| null(what))
}

pub(crate) fn get_mut<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Failure> {
    unsafe { p.as_mut() }.ok_or_else(|| null(what))
}

fn slice<'a, T>(p: *const T, n: u32, what: &str) -> Result<&'a [T], Failure> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: the caller promises `n` readable elements.
    Ok(unsafe { std::slice::from_raw_parts(p, n as usize) })
}

/// Writes the library version.
#[no_mangle]
pub unsafe extern "C" fn hrt_version(major: *mut u32, minor: *mut u32, patch: *mut u32) {
    let (a, b, c) = rt::VERSION;
    unsafe {
        if let Some(m) = major.as_mut() {
            *m = a;
        }
        if let Some(m) = minor.as_mut() {
            *m = b;
        }
        if let Some(m) = patch.as_mut() {
            *m = c;
        }
    }
}

/// The calling thread's last error message (NUL-terminated, truncated to `capacity`).
/// Returns the full length in bytes, without the NUL.
#[no_mangle]
pub unsafe extern "C" fn hrt_last_error_message(buffer: *mut c_char, capacity: u32) -> u32 {
    let msg = status::last_error();
    if !buffer.is_null() && capacity > 0 {
        let n = msg.len().min(capacity as usize - 1);
        unsafe {
            std::ptr::copy_nonoverlapping(msg.as_ptr() as *const c_char, buffer, n);
            *buffer.add(n) = 0;
        }
    }
    msg.len() as u32
}

/// Routes the SDK's diagnostics to `callback` for messages at or above `min_severity`
/// (NULL removes it). Returns false if another logger of the Rust `log` crate already owns
/// the process.
#[no_mangle]
pub unsafe extern "C" fn hrt_set_log_callback(
    callback: HrtLogCallback,
    min_severity: HrtLogSeverity,
    user_data: *mut c_void,
) -> bool {
    std::panic::catch_unwind(|| log_bridge::install(callback, min_severity, user_data)).unwrap_or(false)
}

/// Opaque: the feature structs the SDK needs enabled (`DeviceFeatures`). One thread at a time.
pub struct HrtDeviceFeatures {
    inner: rt::DeviceFeatures,
}

/// The SDK's device features (rayQuery too when `ray_query`), to enable with
/// hrt_device_features_merge (into your own chain) or hrt_device_features_chain (as the
/// whole chain). Keep it alive until hrt_context_create has returned, then destroy it.
#[no_mangle]
pub extern "C" fn hrt_device_features_create(ray_query: bool) -> *mut HrtDeviceFeatures {
    Box::into_raw(Box::new(HrtDeviceFeatures { inner: rt::DeviceFeatures::required(ray_query) }))
}

/// Enables the SDK's features in your chain headed by `features2`: switched on in the structs
/// your chain already has (your own VkPhysicalDeviceVulkan13Features, say), the missing ones
/// appended from `features` (which must stay alive while the chain is used). Never adds a
/// second struct of a type the chain holds. Then pass `features2` as VkDeviceCreateInfo::pNext
/// and HrtContextDesc::enabled_features.
#[no_mangle]
pub unsafe extern "C" fn hrt_device_features_merge(features: *mut HrtDeviceFeatures, features2: *mut c_void) -> HrtStatus {
    guard(|| {
        let f = get_mut(features, "features")?;
        let chain = get_mut(features2 as *mut vk::PhysicalDeviceFeatures2<'static>, "features2")?;
        if chain.s_type != vk::StructureType::PHYSICAL_DEVICE_FEATURES_2 {
            return Err(Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, "features2 is not a VkPhysicalDeviceFeatures2".into()));
        }
        // SAFETY: the caller passes a valid chain (header) and keeps `features` alive.
        f.inner.merge_into(chain);
        Ok(())
    })
}

/// All the SDK's features as one chain (VkPhysicalDeviceFeatures2 first), for an engine with
/// no chain of its own: VkDeviceCreateInfo::pNext and HrtContextDesc::enabled_features.
#[no_mangle]
pub unsafe extern "C" fn hrt_device_features_chain(features: *mut HrtDeviceFeatures) -> *const c_void {
    match features.as_mut() {
        Some(f) => {
            let _ = f.inner.push_to(vk::DeviceCreateInfo::default());
            f.inner.chain()
        }
        None => std::ptr::null(),
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_device_features_destroy(features: *mut HrtDeviceFeatures) {
    if !features.is_null() {
        drop(Box::from_raw(features));
    }
}

/// The device extensions the SDK needs (static strings). Enable all of them, plus
/// VK_KHR_ray_query where the device has it (`hrt_optional_device_extensions`), and these
/// features: bufferDeviceAddress (1.2), synchronization2 and maintenance4 (1.3), accelerationStructure,
/// rayTracingPipeline, shaderStorageImageWriteWithoutFormat (and rayQuery if enabled).
#[no_mangle]
pub unsafe extern "C" fn hrt_required_device_extensions(names: *mut *const *const c_char, count: *mut u32) {
    static NAMES: std::sync::OnceLock<Vec<usize>> = std::sync::OnceLock::new();
    let v = NAMES.get_or_init(|| rt::REQUIRED_DEVICE_EXTENSIONS.iter().map(|n| n.as_ptr() as usize).collect());
    unsafe {
        if let Some(n) = names.as_mut() {
            *n = v.as_ptr() as *const *const c_char;
        }
        if let Some(c) = count.as_mut() {
            *c = v.len() as u32;
        }
    }
}

/// Optional extensions (VK_KHR_ray_query), same form as hrt_required_device_extensions.
#[no_mangle]
pub unsafe extern "C" fn hrt_optional_device_extensions(names: *mut *const *const c_char, count: *mut u32) {
    static NAMES: std::sync::OnceLock<Vec<usize>> = std::sync::OnceLock::new();
    let v = NAMES.get_or_init(|| rt::OPTIONAL_DEVICE_EXTENSIONS.iter().map(|n| n.as_ptr() as usize).collect());
    unsafe {
        if let Some(n) = names.as_mut() {
            *n = v.as_ptr() as *const *const c_char;
        }
        if let Some(c) = count.as_mut() {
            *c = v.len() as u32;
        }
    }
}

unsafe fn entry_from(get_instance_proc_addr: PFN_vkGetInstanceProcAddr) -> Result<ash::Entry, Failure> {
    if get_instance_proc_addr.is_null() {
        ash::Entry::load().map_err(|e| Failure(HrtStatus::HRT_ERROR_VULKAN, format!("cannot load libvulkan: {e}")))
    } else {
        let f: vk::PFN_vkGetInstanceProcAddr = std::mem::transmute(get_instance_proc_addr);
        Ok(ash::Entry::from_static_fn(ash::StaticFn { get_instance_proc_addr: f }))
    }
}

/// Whether a physical device has what the SDK needs. `missing` (optional) receives a
/// comma-separated list of what is missing, NUL-terminated and truncated to its capacity.
#[no_mangle]
pub unsafe extern "C" fn hrt_query_device_support(
    get_instance_proc_addr: PFN_vkGetInstanceProcAddr,
    instance: VkInstance,
    physical_device: VkPhysicalDevice,
    supported: *mut bool,
    ray_query: *mut bool,
    missing: *mut c_char,
    missing_capacity: u32,
) -> HrtStatus {
    guard(|| {
        if instance.is_null() || physical_device.is_null() {
            return Err(null("instance or physical_device"));
        }
        let entry = entry_from(get_instance_proc_addr)?;
        let inst = ash::Instance::load(entry.static_fn(), vk::Instance::from_raw(instance as u64));
        let s = rt::query_device_support(&inst, vk::PhysicalDevice::from_raw(physical_device as u64));
        *get_mut(supported, "supported")? = s.supported;
        if let Some(r) = ray_query.as_mut() {
            *r = s.ray_query;
        }
        if !missing.is_null() && missing_capacity > 0 {
            let text = s.missing.join(", ");
            let n = text.len().min(missing_capacity as usize - 1);
            std::ptr::copy_nonoverlapping(text.as_ptr() as *const c_char, missing, n);
            *missing.add(n) = 0;
        }
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn hrt_init_settings_default() -> HrtInitSettings {
    rt::InitSettings::default().into()
}

/// Creates a context from the engine's device. Checks `desc->api_version` against the
/// library, and the device against the SDK's needs (HRT_ERROR_MISSING_DEVICE_SUPPORT names
/// what is missing).
#[no_mangle]
pub unsafe extern "C" fn hrt_context_create(desc: *const HrtContextDesc, out: *mut *mut HrtContext) -> HrtStatus {
    guard(|| {
        let desc = get(desc, "desc")?;
        let out = get_mut(out, "out")?;
        *out = std::ptr::null_mut();
        if desc.api_version != HRT_API_VERSION {
            return Err(Failure(
                HrtStatus::HRT_ERROR_VERSION_MISMATCH,
                format!("header API version {:#x}, library {:#x}", desc.api_version, HRT_API_VERSION),
            ));
        }
        if desc.instance.is_null() || desc.physical_device.is_null() || desc.device.is_null() {
            return Err(null("desc->instance, physical_device or device"));
        }
        let names = slice(desc.enabled_extensions, desc.enabled_extension_count, "desc->enabled_extensions")?;
        let mut exts: Vec<&CStr> = Vec::with_capacity(names.len());
        for &n in names {
            if n.is_null() {
                return Err(null("an enabled extension name"));
            }
            exts.push(CStr::from_ptr(n));
        }
        let entry = entry_from(desc.get_instance_proc_addr)?;
        let instance = ash::Instance::load(entry.static_fn(), vk::Instance::from_raw(desc.instance as u64));
        let device = ash::Device::load(instance.fp_v1_0(), vk::Device::from_raw(desc.device as u64));
        // SAFETY: the caller promises (header) that the handles are valid and belong together,
        // and that the device was created with these extensions and this feature chain.
        let ctx = rt::ExecuteContext::new(
            &rt::DeviceDesc::new(
                &entry,
                &instance,
                vk::PhysicalDevice::from_raw(desc.physical_device as u64),
                &device,
                &exts,
                desc.instance_api_version,
                desc.enabled_features,
            )
            .with_debug_utils(desc.debug_utils),
            &(&desc.settings).into(),
        )?;
        let p = Box::into_raw(Box::new(HrtContext { ctx, _entry: entry }));
        live::register(p, live::Kind::Context);
        *out = p;
        Ok(())
    })
}

/// Destroys a context (NULL is ignored: HRT_OK). While the GPU may still run one of its
/// tickets' command buffers it refuses with HRT_ERROR_TICKETS_IN_FLIGHT and the context stays
/// valid: wait for the fences, hand the tickets back, destroy again. Destroy containers first
/// or after, in any order. Destroying it twice, or any call on it afterwards, is
/// HRT_ERROR_INVALID_HANDLE.
#[no_mangle]
pub unsafe extern "C" fn hrt_context_destroy(ctx: *mut HrtContext) -> HrtStatus {
    if ctx.is_null() {
        return HrtStatus::HRT_OK;
    }
    guard(|| {
        // Refused while the GPU may still run a ticket: the context stays valid.
        let serials = context(ctx)?.ctx.unfinished_tickets();
        if !serials.is_empty() {
            return Err(rt::Error::TicketsInFlight { serials }.into());
        }
        live::unregister(ctx, live::Kind::Context, "ctx")?;
        drop(Box::from_raw(ctx));
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_supports_inline_rt(ctx: *const HrtContext) -> bool {
    context(ctx).is_ok_and(|c| c.ctx.supports_inline_rt())
}

#[no_mangle]
pub unsafe extern "C" fn hrt_create_geometry_handles(ctx: *mut HrtContext, count: u32, out: *mut HrtGeometryHandle) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        if count > 0 && out.is_null() {
            return Err(null("out"));
        }
        for (i, h) in c.ctx.create_geometry_handles(count as usize).into_iter().enumerate() {
            *out.add(i) = h.0;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_geometry_handles(
    ctx: *mut HrtContext,
    handles: *const HrtGeometryHandle,
    count: u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let hs: Vec<rt::GeometryHandle> = slice(handles, count, "handles")?.iter().map(|&h| rt::GeometryHandle(h)).collect();
        Ok(c.ctx.destroy_geometry_handles(&hs)?)
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_create_instance_handles(ctx: *mut HrtContext, count: u32, out: *mut HrtInstanceHandle) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        if count > 0 && out.is_null() {
            return Err(null("out"));
        }
        for (i, h) in c.ctx.create_instance_handles(count as usize).into_iter().enumerate() {
            *out.add(i) = h.0;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_instance_handles(
    ctx: *mut HrtContext,
    handles: *const HrtInstanceHandle,
    count: u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let hs: Vec<rt::InstanceHandle> = slice(handles, count, "handles")?.iter().map(|&h| rt::InstanceHandle(h)).collect();
        Ok(c.ctx.destroy_instance_handles(&hs)?)
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_destroy_all_instance_handles(ctx: *mut HrtContext) -> HrtStatus {
    guard(|| {
        context(ctx)?.ctx.destroy_all_instance_handles();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_task_container_create(ctx: *mut HrtContext, out: *mut *mut HrtTaskContainer) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let out = get_mut(out, "out")?;
        let p = Box::into_raw(Box::new(HrtTaskContainer { inner: c.ctx.create_task_container() }));
        live::register(p, live::Kind::Container);
        *out = p;
        Ok(())
    })
}

/// Destroys a container (NULL is ignored: HRT_OK); twice is HRT_ERROR_INVALID_HANDLE.
#[no_mangle]
pub unsafe extern "C" fn hrt_task_container_destroy(container: *mut HrtTaskContainer) -> HrtStatus {
    if container.is_null() {
        return HrtStatus::HRT_OK;
    }
    guard(|| {
        live::unregister(container, live::Kind::Container, "container")?;
        drop(Box::from_raw(container));
        Ok(())
    })
}

/// Tasks scheduled and not yet built.
#[no_mangle]
pub unsafe extern "C" fn hrt_task_container_len(container: *const HrtTaskContainer) -> u32 {
    container_mut(container.cast_mut()).map_or(0, |c| c.inner.len() as u32)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_task_container_clear(container: *mut HrtTaskContainer) {
    if let Ok(c) = container_mut(container) {
        c.inner.clear();
    }
}

/// The frame number of the next build of `container`: it seeds the random sequences and picks
/// the checkerboard half (same index + same inputs = same image). Applies to the next
/// successful build only; without it the ticket serial is used.
#[no_mangle]
pub unsafe extern "C" fn hrt_task_container_set_frame_index(container: *mut HrtTaskContainer, frame_index: u64) -> HrtStatus {
    guard(|| {
        container_mut(container)?.inner.set_frame_index(frame_index);
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn hrt_geometry_task_default() -> HrtGeometryTask {
    types::geometry_task_default()
}

/// A part for HrtGeometryInput.extra_components with the defaults (identity, all vertices).
#[no_mangle]
pub extern "C" fn hrt_geometry_component_default() -> HrtGeometryComponent {
    types::geometry_component_default()
}

/// The VkBuildAccelerationStructureFlagsKHR a BLAS of `build_hint` (an HrtBuildHint) is built
/// with (see the Rust docs of BuildHint::build_flags): for static or `allow_update` geometry,
/// and for HRT_BUILD_HINT_FAST_THEN_TRACE's first build.
///
/// # Safety
/// `flags` points to writable memory.
#[no_mangle]
pub unsafe extern "C" fn hrt_build_hint_flags(
    build_hint: u32,
    allow_update: bool,
    first_build: bool,
    flags: *mut u32,
) -> HrtStatus {
    guard(|| {
        let out = get_mut(flags, "flags")?;
        let hint = types::build_hint(build_hint)?;
        *out = hint.build_flags(allow_update, first_build).as_raw();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_geometry(container: *mut HrtTaskContainer, task: *const HrtGeometryTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        // SAFETY: the header says extra_components points to extra_component_count parts.
        Ok(c.inner.schedule_geometry(&unsafe { types::geometry_task(get(task, "task")?) }?)?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_instance_task_default() -> HrtInstanceTask {
    types::instance_task_default()
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_instance(container: *mut HrtTaskContainer, task: *const HrtInstanceTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        Ok(c.inner.schedule_instance(&types::instance_task(get(task, "task")?)?)?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_bvh_build_task_default() -> HrtBvhBuildTask {
    HrtBvhBuildTask { max_blas_build_count: rt::BvhBuildTask::default().max_blas_build_count }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_bvh_build(container: *mut HrtTaskContainer, task: *const HrtBvhBuildTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        Ok(c.inner.schedule_bvh_build(&rt::BvhBuildTask { max_blas_build_count: t.max_blas_build_count })?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_common_default() -> HrtTraceCommon {
    types::trace_common_default()
}

#[no_mangle]
pub extern "C" fn hrt_trace_ambient_occlusion_task_default() -> HrtTraceAmbientOcclusionTask {
    types::ao_task_default()
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_ambient_occlusion(
    container: *mut HrtTaskContainer,
    task: *const HrtTraceAmbientOcclusionTask,
) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        Ok(c.inner.schedule_ambient_occlusion(&types::ao_task(get(task, "task")?)?)?)
    })
}

/// Records the container into `command_buffer` (begun by the engine, which also ends, submits
/// and waits for it) and writes a ticket. On success the container is emptied; on error it
/// keeps its tasks and nothing usable was recorded.
#[no_mangle]
pub unsafe extern "C" fn hrt_build_gpu_task(
    ctx: *mut HrtContext,
    container: *mut HrtTaskContainer,
    command_buffer: VkCommandBuffer,
    ticket: *mut HrtTicket,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let k = container_mut(container)?;
        let out = get_mut(ticket, "ticket")?;
        let t = c.ctx.build_gpu_task(&mut k.inner, vk::CommandBuffer::from_raw(command_buffer as u64))?;
        *out = t.into_raw();
        Ok(())
    })
}

/// Hands a ticket back after the GPU finished its command buffer. Writes up to `capacity`
/// per-task timings and their total number to `timing_count` (both optional). A ticket
/// returned twice or never issued is HRT_ERROR_UNKNOWN_TICKET.
#[no_mangle]
pub unsafe extern "C" fn hrt_mark_gpu_task_completed(
    ctx: *mut HrtContext,
    ticket: HrtTicket,
    timings: *mut HrtTaskTiming,
    capacity: u32,
    timing_count: *mut u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let done = c.ctx.mark_gpu_task_completed(rt::GpuTicket::from_raw(ticket))?;
        if let Some(n) = timing_count.as_mut() {
            *n = done.timings.len() as u32;
        }
        if !timings.is_null() {
            for (i, t) in done.timings.iter().take(capacity as usize).enumerate() {
                *timings.add(i) = HrtTaskTiming {
                    kind: match t.kind {
                        rt::TaskKind::Bvh => HrtTaskKind::HRT_TASK_BVH,
                        rt::TaskKind::AmbientOcclusion => HrtTaskKind::HRT_TASK_AMBIENT_OCCLUSION,
                        rt::TaskKind::BlasBuild => HrtTaskKind::HRT_TASK_BLAS_BUILD,
                        rt::TaskKind::TlasBuild => HrtTaskKind::HRT_TASK_TLAS_BUILD,
                        rt::TaskKind::DirectLightingInjection => HrtTaskKind::HRT_TASK_DIRECT_LIGHTING_INJECTION,
                        rt::TaskKind::CacheUpdate => HrtTaskKind::HRT_TASK_CACHE_UPDATE,
                        rt::TaskKind::CacheTransfer => HrtTaskKind::HRT_TASK_CACHE_TRANSFER,
                        rt::TaskKind::Shadow => HrtTaskKind::HRT_TASK_SHADOW,
                        rt::TaskKind::Diffuse => HrtTaskKind::HRT_TASK_DIFFUSE,
                        rt::TaskKind::Specular => HrtTaskKind::HRT_TASK_SPECULAR,
                        rt::TaskKind::MultiShadow => HrtTaskKind::HRT_TASK_MULTI_SHADOW,
                        rt::TaskKind::DenoiseSpecular => HrtTaskKind::HRT_TASK_DENOISE_SPECULAR,
                        rt::TaskKind::DenoiseDiffuse => HrtTaskKind::HRT_TASK_DENOISE_DIFFUSE,
                        rt::TaskKind::DenoiseSpecularAndDiffuse => HrtTaskKind::HRT_TASK_DENOISE_SPECULAR_AND_DIFFUSE,
                        rt::TaskKind::DenoiseDiffuseOcclusion => HrtTaskKind::HRT_TASK_DENOISE_DIFFUSE_OCCLUSION,
                        rt::TaskKind::DenoiseShadow => HrtTaskKind::HRT_TASK_DENOISE_SHADOW,
                        rt::TaskKind::DenoiseMultiShadow => HrtTaskKind::HRT_TASK_DENOISE_MULTI_SHADOW,
                        rt::TaskKind::CacheRelight => HrtTaskKind::HRT_TASK_CACHE_RELIGHT,
                    },
                    task_index: t.task_index,
                    gpu_ms: t.gpu_ms,
                };
            }
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_release_device_resources_immediately(ctx: *mut HrtContext) -> HrtStatus {
    guard(|| Ok(context(ctx)?.ctx.release_device_resources_immediately()?))
}

#[no_mangle]
pub unsafe extern "C" fn hrt_pending_blas_builds(ctx: *const HrtContext) -> u32 {
    context(ctx).map_or(0, |c| c.ctx.pending_blas_builds() as u32)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_tlas_instance_count(ctx: *const HrtContext) -> u32 {
    context(ctx).map_or(0, |c| c.ctx.tlas_instance_count() as u32)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_resource_allocations(ctx: *const HrtContext, out: *mut HrtResourceAllocations) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        *get_mut(out, "out")? = c.ctx.resource_allocations().into();
        Ok(())
    })
}

/// Serials of the tickets built and not yet handed back: writes up to `capacity` and the total
/// to `count`.
#[no_mangle]
pub unsafe extern "C" fn hrt_tickets_in_flight(
    ctx: *const HrtContext,
    serials: *mut u64,
    capacity: u32,
    count: *mut u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let all = c.ctx.tickets_in_flight();
        *get_mut(count, "count")? = all.len() as u32;
        if !serials.is_null() {
            for (i, s) in all.iter().take(capacity as usize).enumerate() {
                *serials.add(i) = *s;
            }
        }
        Ok(())
    })
}

/// Tickets in flight whose command buffers the GPU has not run to the end (what must finish
/// before hrt_context_destroy succeeds); same conventions as hrt_tickets_in_flight.
#[no_mangle]
pub unsafe extern "C" fn hrt_unfinished_tickets(
    ctx: *const HrtContext,
    serials: *mut u64,
    capacity: u32,
    count: *mut u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let all = c.ctx.unfinished_tickets();
        *get_mut(count, "count")? = all.len() as u32;
        if !serials.is_null() {
            for (i, s) in all.iter().take(capacity as usize).enumerate() {
                *serials.add(i) = *s;
            }
        }
        Ok(())
    })
}

/// The device's name (NUL-terminated, truncated to `capacity`). Returns its full length.
#[no_mangle]
pub unsafe extern "C" fn hrt_device_name(ctx: *const HrtContext, buffer: *mut c_char, capacity: u32) -> u32 {
    let Ok(c) = context(ctx) else { return 0 };
    let name = c.ctx.device_name();
    if !buffer.is_null() && capacity > 0 {
        let n = name.len().min(capacity as usize - 1);
        std::ptr::copy_nonoverlapping(name.as_ptr() as *const c_char, buffer, n);
        *buffer.add(n) = 0;
    }
    name.len() as u32
}

#[no_mangle]
pub extern "C" fn hrt_direct_lighting_injection_task_default() -> HrtDirectLightingInjectionTask {
    types::injection_task_default()
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_direct_lighting_injection(
    container: *mut HrtTaskContainer,
    task: *const HrtDirectLightingInjectionTask,
) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        Ok(c.inner.schedule_direct_lighting_injection(&types::injection_task(get(task, "task")?)?)?)
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_clear_cache(container: *mut HrtTaskContainer, task: *const HrtClearCacheTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        Ok(c.inner.schedule_clear_cache(&rt::ClearCacheTask { instance: rt::InstanceHandle(t.instance) })?)
    })
}

/// Triangles of a geometry's last registered or updated data whose indices reach past its
/// vertex count: the SDK made them degenerate (the driver never sees the bad index) and logged
/// a warning. 0 until the ticket that copied the data has come back.
#[no_mangle]
pub unsafe extern "C" fn hrt_geometry_invalid_triangles(
    ctx: *const HrtContext,
    geometry: HrtGeometryHandle,
    triangles: *mut u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        *get_mut(triangles, "triangles")? = c.ctx.geometry_invalid_triangles(rt::GeometryHandle(geometry))?;
        Ok(())
    })
}

/// A NUL-terminated UTF-8 name (lossy: invalid bytes become U+FFFD).
unsafe fn name_arg(name: *const c_char) -> Result<String, Failure> {
    if name.is_null() {
        return Err(status::null("name"));
    }
    Ok(CStr::from_ptr(name).to_string_lossy().into_owned())
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
        Ok(c.ctx.set_geometry_name(rt::GeometryHandle(geometry), &name_arg(name)?)?)
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
        Ok(c.ctx.set_instance_name(rt::InstanceHandle(instance), &name_arg(name)?)?)
    })
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
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        Ok(c.inner.schedule_direct_light_transfer(&rt::DirectLightTransferTask {
            source: rt::InstanceHandle(t.source),
            target: rt::InstanceHandle(t.target),
            max_distance: t.max_distance,
            enable_bilinear_sampling: t.enable_bilinear_sampling,
        })?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_shadow_task_default() -> HrtTraceShadowTask {
    types::shadow_task_default()
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_shadow(container: *mut HrtTaskContainer, task: *const HrtTraceShadowTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        Ok(c.inner.schedule_shadow(&types::shadow_task(get(task, "task")?)?)?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_diffuse_task_default() -> HrtTraceDiffuseTask {
    let d = rt::TraceDiffuseTask::default();
    let ao = types::ao_task_default();
    HrtTraceDiffuseTask {
        common: types::trace_common_default(),
        output: ao.output,
        rays_per_pixel: d.rays_per_pixel,
        ray_length: d.ray_length,
        miss_radiance: d.miss_radiance,
        brdf: d.brdf as u32,
        environment: types::environment_default(),
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_diffuse(container: *mut HrtTaskContainer, task: *const HrtTraceDiffuseTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        let common = types::trace_common(&t.common)?;
        let ao = types::ao_task(&HrtTraceAmbientOcclusionTask { output: t.output, ..types::ao_task_default() })?;
        Ok(c.inner.schedule_diffuse(&rt::TraceDiffuseTask {
            common,
            output: ao.output,
            rays_per_pixel: t.rays_per_pixel,
            ray_length: t.ray_length,
            miss_radiance: t.miss_radiance,
            brdf: match t.brdf {
                0 => rt::DiffuseBrdfType::Lambertian,
                1 => rt::DiffuseBrdfType::NormalizedDisney,
                v => return Err(Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid HrtTraceDiffuseTask.brdf: {v}"))),
            },
            environment: types::environment(&t.environment),
        })?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_specular_task_default() -> HrtTraceSpecularTask {
    let d = rt::TraceSpecularTask::default();
    HrtTraceSpecularTask {
        common: types::trace_common_default(),
        output: types::ao_task_default().output,
        rays_per_pixel: d.rays_per_pixel,
        ray_length: d.ray_length,
        miss_radiance: d.miss_radiance,
        firefly_clamp: d.firefly_clamp,
        demodulated_output: types::ao_task_default().output,
        environment: types::environment_default(),
        hit_lighting: types::HrtHitLighting {
            lights: std::ptr::null(),
            light_count: 0,
            max_roughness: d.hit_lighting.max_roughness,
            indirect: d.hit_lighting.indirect as u32,
            gather_rays: d.hit_lighting.gather_rays,
        },
    }
}

/// # Safety
/// `container` from hrt_create_task_container; `task` valid, its `hit_lighting.lights`
/// `hit_lighting.light_count` long (or null with a count of 0).
#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_specular(container: *mut HrtTaskContainer, task: *const HrtTraceSpecularTask) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        let ao =
            types::ao_task(&HrtTraceAmbientOcclusionTask { common: t.common, output: t.output, ..types::ao_task_default() })?;
        let demod =
            types::ao_task(&HrtTraceAmbientOcclusionTask { output: t.demodulated_output, ..types::ao_task_default() })?.output;
        Ok(c.inner.schedule_specular(&rt::TraceSpecularTask {
            common: ao.common,
            output: ao.output,
            rays_per_pixel: t.rays_per_pixel,
            ray_length: t.ray_length,
            miss_radiance: t.miss_radiance,
            firefly_clamp: t.firefly_clamp,
            demodulated_output: demod,
            environment: types::environment(&t.environment),
            hit_lighting: rt::HitLighting {
                lights: slice(t.hit_lighting.lights, t.hit_lighting.light_count, "task->hit_lighting.lights")?
                    .iter()
                    .map(types::light)
                    .collect::<Result<_, _>>()?,
                max_roughness: t.hit_lighting.max_roughness,
                indirect: types::pick(
                    "HrtHitLighting.indirect",
                    t.hit_lighting.indirect,
                    &[rt::HitIndirect::CacheResidual, rt::HitIndirect::Gather, rt::HitIndirect::None],
                )?,
                gather_rays: t.hit_lighting.gather_rays,
            },
        })?)
    })
}

#[no_mangle]
pub extern "C" fn hrt_trace_multi_shadow_task_default() -> HrtTraceMultiShadowTask {
    let out = types::ao_task_default().output;
    HrtTraceMultiShadowTask {
        common: types::trace_common_default(),
        lights: std::ptr::null(),
        light_count: 0,
        visibility: out,
        visibility_high: types::image_c(&hybrid_rt::ImageInput::default()),
        packed: out,
        light_outputs: [types::HrtLightShadowOutput { light: 0, output: out }; 4],
        light_output_count: 0,
        rays_per_pixel: 1,
        first_hit: rt::TraceMultiShadowTask::default().first_hit,
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_multi_shadow(
    container: *mut HrtTaskContainer,
    task: *const HrtTraceMultiShadowTask,
) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        let t = get(task, "task")?;
        let lights = slice(t.lights, t.light_count, "task->lights")?;
        Ok(c.inner.schedule_multi_shadow(&types::multi_shadow_task(t, lights)?)?)
    })
}

#[cfg(test)]
mod tests {
    /// The C constants are the Rust SDK's limits.
    #[test]
    fn limits_match_the_sdk() {
        assert_eq!(super::HRT_MAX_SHADOW_LIGHTS as usize, hybrid_rt::MAX_SHADOW_LIGHTS);
        assert_eq!(super::HRT_MAX_LIGHT_OUTPUTS as usize, hybrid_rt::MAX_LIGHT_OUTPUTS);
        assert_eq!(super::HRT_MAX_TILE_RESOLUTION, hybrid_rt::MAX_TILE_RESOLUTION);
        assert_eq!(super::HRT_MAX_DENOISING_EXTENT, hybrid_rt::MAX_DENOISING_EXTENT);
    }
}
