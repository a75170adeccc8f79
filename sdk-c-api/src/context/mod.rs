//! The context and what is not one task's: the library version, error messages and logging,
//! context creation and destruction (the device set-up is in `device`), task containers,
//! building a container into a command buffer, the SDK's device memory; handing tickets back
//! with the per-task and per-pass GPU timings, and the tickets in flight, are in `tickets`.
//!
//! `HrtTaskKind` is the type of a timing's task; each task area's file defines the
//! `HRT_TASK_*` values of its own tasks.
mod device;
mod tickets;

use crate::args::{get, get_mut, slice, string_arg, write_string};
use crate::live;
use crate::log_bridge::{self, HrtLogCallback, HrtLogSeverity};
use crate::status::{self, guard, null, Failure, HrtStatus};
use crate::vulkan::{PFN_vkGetInstanceProcAddr, VkCommandBuffer, VkDevice, VkInstance, VkPhysicalDevice};
use ash::vk;
use ash::vk::Handle;
pub use device::*;
use hybrid_rt as rt;
use std::ffi::{c_char, c_void, CStr};
pub use tickets::*;

/// The API version this header describes: (major << 22) | (minor << 12) | patch.
pub const HRT_API_VERSION: u32 = 1 << 12; // (major 0 << 22) | (minor 1 << 12) | patch 0

pub type HrtTicket = u64;

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

/// Converts `task` with `convert` and schedules it into `container` with `schedule`: the body
/// of every `hrt_schedule_*` function.
pub(crate) fn schedule<C, T>(
    container: *mut HrtTaskContainer,
    task: *const C,
    convert: impl FnOnce(&C) -> Result<T, Failure>,
    schedule: impl FnOnce(&mut rt::TaskContainer, &T) -> rt::Result<()>,
) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        let t = convert(get(task, "task")?)?;
        Ok(schedule(&mut c.inner, &t)?)
    })
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
    write_string(&status::last_error(), buffer, capacity)
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

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtInitSettings {
    /// Tickets in flight at once. Default 2.
    pub supported_working_sets: u32,
    /// Initial upload ring bytes per working set. Default 1 MiB.
    pub upload_ring_bytes: u64,
    /// Timed intervals per ticket, besides two for the BVH and cache work; tasks past it run
    /// untimed. Default 64.
    pub max_timed_tasks: u32,
    /// An engine-owned VkPipelineCache the SDK creates its pipelines through (0: none).
    /// Save it with vkGetPipelineCacheData and reload it next run to skip shader compilation.
    pub pipeline_cache: u64,
    /// Queue families recording SDK work (first `queue_family_count`; 2+: SDK memory is
    /// VK_SHARING_MODE_CONCURRENT over them, for BVH work on an async-compute queue).
    pub queue_family_indices: [u32; 4],
    pub queue_family_count: u32,
    /// Most bytes the direct-lighting caches may hold; the least recently used instances'
    /// caches are evicted past it (0: no limit, the default). See hrt_cache_report.
    pub cache_budget_bytes: u64,
    /// Time every pass of the denoisers as well as the task (default false): the passes'
    /// times come back through hrt_mark_gpu_task_completed_with_passes.
    pub time_passes: bool,
}

impl From<rt::InitSettings> for HrtInitSettings {
    fn from(s: rt::InitSettings) -> Self {
        HrtInitSettings {
            supported_working_sets: s.supported_working_sets,
            upload_ring_bytes: s.upload_ring_bytes,
            max_timed_tasks: s.max_timed_tasks,
            pipeline_cache: s.pipeline_cache.as_raw(),
            queue_family_indices: s.queue_family_indices,
            queue_family_count: s.queue_family_count,
            cache_budget_bytes: s.cache_budget_bytes,
            time_passes: s.time_passes,
        }
    }
}
impl From<&HrtInitSettings> for rt::InitSettings {
    fn from(s: &HrtInitSettings) -> Self {
        rt::InitSettings {
            supported_working_sets: s.supported_working_sets,
            upload_ring_bytes: s.upload_ring_bytes,
            max_timed_tasks: s.max_timed_tasks,
            pipeline_cache: vk::PipelineCache::from_raw(s.pipeline_cache),
            queue_family_indices: s.queue_family_indices,
            queue_family_count: s.queue_family_count,
            cache_budget_bytes: s.cache_budget_bytes,
            time_passes: s.time_passes,
        }
    }
}

/// The engine's Vulkan objects. The SDK keeps function tables, not ownership.
#[repr(C)]
pub struct HrtContextDesc {
    /// Must be HRT_API_VERSION (checked: a header/library mismatch is an error).
    pub api_version: u32,
    /// The loader's vkGetInstanceProcAddr; NULL loads libvulkan.so.1 itself.
    pub get_instance_proc_addr: PFN_vkGetInstanceProcAddr,
    pub instance: VkInstance,
    pub physical_device: VkPhysicalDevice,
    pub device: VkDevice,
    /// The device extensions the engine enabled (see hrt_required_device_extensions).
    pub enabled_extensions: *const *const std::ffi::c_char,
    pub enabled_extension_count: u32,
    /// VkApplicationInfo::apiVersion of the instance: VK_API_VERSION_1_3 or later.
    pub instance_api_version: u32,
    /// The pNext chain given to vkCreateDevice (a VkDevice cannot be asked which features it
    /// has): your VkPhysicalDeviceFeatures2 after hrt_device_features_merge, or
    /// hrt_device_features_chain. Read during hrt_context_create only.
    pub enabled_features: *const c_void,
    /// VK_EXT_debug_utils is enabled on the instance: the SDK names its objects and labels its
    /// tasks ("hybrid-rt ..."), for RenderDoc, Nsight and validation messages.
    pub debug_utils: bool,
    pub settings: HrtInitSettings,
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
        let entry = device::entry_from(desc.get_instance_proc_addr)?;
        let instance = ash::Instance::load(entry.static_fn(), vk::Instance::from_raw(desc.instance as u64));
        let device = ash::Device::load(instance.fp_v1_0(), vk::Device::from_raw(desc.device as u64));
        // SAFETY: the caller promises (header) that the handles are valid and belong together,
        // and that the device was created with these extensions and this feature chain.
        let ctx = rt::ExecuteContext::new(
            &rt::DeviceDesc::new(&entry, &instance, vk::PhysicalDevice::from_raw(desc.physical_device as u64), &device)
                .enabled_extensions(&exts)
                .instance_api_version(desc.instance_api_version)
                .enabled_features(desc.enabled_features)
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

/// Destroys a context after the engine's device was lost (VK_ERROR_DEVICE_LOST), when its
/// tickets can never come back: every GPU object and all host memory of the SDK are freed at
/// once, and nothing waits (NULL is ignored: HRT_OK). Call it before destroying the device.
/// Only after a device loss, or when no command buffer holding one of its tickets will run
/// again: on a working device it frees memory the GPU may still use. Destroying it twice, or
/// any call on it afterwards, is HRT_ERROR_INVALID_HANDLE.
#[no_mangle]
pub unsafe extern "C" fn hrt_context_destroy_after_device_lost(ctx: *mut HrtContext) -> HrtStatus {
    if ctx.is_null() {
        return HrtStatus::HRT_OK;
    }
    guard(|| {
        live::unregister(ctx, live::Kind::Context, "ctx")?;
        let HrtContext { ctx, _entry } = *Box::from_raw(ctx);
        // SAFETY: the caller declares the device lost (see above).
        ctx.destroy_after_device_lost();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn hrt_supports_inline_rt(ctx: *const HrtContext) -> bool {
    context(ctx).is_ok_and(|c| c.ctx.supports_inline_rt())
}

/// The device's name (NUL-terminated, truncated to `capacity`). Returns its full length.
#[no_mangle]
pub unsafe extern "C" fn hrt_device_name(ctx: *const HrtContext, buffer: *mut c_char, capacity: u32) -> u32 {
    let Ok(c) = context(ctx) else { return 0 };
    write_string(c.ctx.device_name(), buffer, capacity)
}

#[no_mangle]
pub unsafe extern "C" fn hrt_release_device_resources_immediately(ctx: *mut HrtContext) -> HrtStatus {
    guard(|| Ok(context(ctx)?.ctx.release_device_resources_immediately()?))
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

/// Names the task scheduled last in `container` (NUL-terminated UTF-8, copied; invalid bytes
/// become U+FFFD): its region in the command buffer carries the label (with debug_utils on, as
/// RenderDoc and Nsight show it), and so do its timings (HrtTaskTiming.label). A second label
/// for the same task replaces the first. An empty container is HRT_ERROR_INVALID_INPUT, a NULL
/// label HRT_ERROR_NULL_POINTER.
#[no_mangle]
pub unsafe extern "C" fn hrt_task_container_set_task_label(container: *mut HrtTaskContainer, label: *const c_char) -> HrtStatus {
    guard(|| {
        let c = container_mut(container)?;
        Ok(c.inner.set_task_label(&string_arg(label, "label")?)?)
    })
}

/// Records the container into `command_buffer` (begun by the engine, which also ends, submits
/// and waits for it) and writes a ticket. On success the container is emptied; on error it
/// keeps its tasks, the context is as before, and nothing was recorded into `command_buffer`:
/// the engine's own commands in it stay valid, and it can be ended and submitted as usual.
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
        // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
        let t = unsafe { c.ctx.build_gpu_task(&mut k.inner, vk::CommandBuffer::from_raw(command_buffer as u64)) }?;
        *out = t.into_raw();
        Ok(())
    })
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct HrtAllocationCount {
    pub count: u64,
    pub bytes: u64,
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct HrtResourceAllocations {
    pub geometry_copies: HrtAllocationCount,
    pub blas: HrtAllocationCount,
    pub build_scratch: HrtAllocationCount,
    pub tlas: HrtAllocationCount,
    pub upload_rings: HrtAllocationCount,
    pub pipelines: HrtAllocationCount,
    pub cache: HrtAllocationCount,
    pub readback: HrtAllocationCount,
    /// Denoising contexts' history images.
    pub denoiser: HrtAllocationCount,
    /// Many-lights contexts' light lists and resampling history.
    pub many_lights: HrtAllocationCount,
}

impl From<rt::ResourceAllocations> for HrtResourceAllocations {
    fn from(a: rt::ResourceAllocations) -> Self {
        let c = |x: rt::AllocationCount| HrtAllocationCount { count: x.count, bytes: x.bytes };
        HrtResourceAllocations {
            geometry_copies: c(a.geometry_copies),
            blas: c(a.blas),
            build_scratch: c(a.build_scratch),
            tlas: c(a.tlas),
            upload_rings: c(a.upload_rings),
            pipelines: c(a.pipelines),
            cache: c(a.cache),
            readback: c(a.readback),
            denoiser: c(a.denoiser),
            many_lights: c(a.many_lights),
        }
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_resource_allocations(ctx: *const HrtContext, out: *mut HrtResourceAllocations) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        *get_mut(out, "out")? = c.ctx.resource_allocations().into();
        Ok(())
    })
}

/// Starts a CSV log of every device-memory allocation and free the SDK makes, written to the
/// file at `path` (NUL-terminated UTF-8; created or truncated): one line per event,
/// `time_ms,event,kind,name,bytes,kind_live_bytes` after a header line (see the Rust docs of
/// `ExecuteContext::begin_logging_resource_allocations`). A file that cannot be created, or a
/// log already open, is HRT_ERROR_INVALID_INPUT.
#[no_mangle]
pub unsafe extern "C" fn hrt_begin_logging_resource_allocations(ctx: *const HrtContext, path: *const c_char) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let path = unsafe { string_arg(path, "path")? };
        let file = std::fs::File::create(&path).map_err(|e| {
            Failure(
                HrtStatus::HRT_ERROR_INVALID_INPUT,
                format!("hrt_begin_logging_resource_allocations path: cannot create {path:?}: {e}"),
            )
        })?;
        Ok(c.ctx.begin_logging_resource_allocations(file)?)
    })
}

/// Ends the allocation log: flushes and closes its file. With no log open, or when writing
/// it failed (the message says how), HRT_ERROR_INVALID_INPUT.
#[no_mangle]
pub unsafe extern "C" fn hrt_end_logging_resource_allocations(ctx: *const HrtContext) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        // The file is closed when the writer drops; the log was flushed into it.
        c.ctx.end_logging_resource_allocations()?;
        Ok(())
    })
}
