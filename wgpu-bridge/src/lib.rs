//! hybrid-rt inside a wgpu renderer (Vulkan backend).
//!
//! Many Rust engines render with wgpu. This crate lets such an engine use hybrid-rt without
//! leaving wgpu: it opens the wgpu device itself, on the engine's adapter, with everything the
//! SDK needs (extensions and features merged into what wgpu asked for — one `VkDevice` serves
//! both; [`RtDevice::new`]) or attaches to a device the engine opened with
//! [`SDK_WGPU_FEATURES`] and [`add_sdk_requirements`] ([`RtDevice::attach`]), makes the SDK's
//! [`ExecuteContext`] on it, turns wgpu textures and buffers into the
//! SDK's inputs, and records a [`TaskContainer`] into a wgpu command buffer through wgpu's
//! HAL escape hatch. The command buffer is submitted with the engine's others, on wgpu's queue;
//! the ticket goes back to the SDK after the submission completed.
//!
//! Kickstart RT reaches D3D11 engines through an interop layer that owns a D3D12 device and
//! its own submissions. Here there is one device and one queue, and the engine keeps the
//! ordering: the SDK's work sits in a command buffer between its own.
//!
//! # The contract
//! - wgpu tracks resource states; the SDK's commands are not tracked. So before
//!   [`RtDevice::record`], put every texture the SDK reads in [`SDK_READ`] and every texture it
//!   writes in [`SDK_WRITE`], and every buffer it copies from in [`SDK_COPY`]: record
//!   [`prepare`] (wgpu's `transition_resources`) in a wgpu encoder submitted before the SDK's.
//!   The SDK leaves every texture in that state, and [`RtDevice::image`] declares that layout.
//! - The SDK's command buffer starts and ends with a full memory barrier, so wgpu's work before
//!   and after it is ordered with the SDK's ray-tracing and compute work.
//! - Wait for the submission (`device.poll(PollType::Wait { .. })`, or a later one's
//!   completion) before handing the ticket back with `context().mark_gpu_task_completed`.
//! - A texture the SDK writes must hold contents in wgpu's eyes (created with data, written or
//!   cleared once): wgpu zero-fills a texture it never saw written before its first tracked
//!   read, and it cannot see the SDK's writes — that fill would erase them.
//! - The textures and buffers must outlive the ticket (the SDK does not hold references).
//!
//! ```no_run
//! # fn demo(adapter: &wgpu::Adapter) -> Result<(), hybrid_rt_wgpu::BridgeError> {
//! use hybrid_rt_wgpu::RtDevice;
//! let rt = RtDevice::new(adapter, &wgpu::DeviceDescriptor::default(), &hybrid_rt::InitSettings::default())?;
//! let mut tasks = rt.context().create_task_container();
//! // ... schedule geometry, instances, a BVH build and traces, with inputs from rt.image() ...
//! // SAFETY: the textures and buffers the tasks name outlive the ticket.
//! let (sdk_commands, ticket) = unsafe { rt.record(&mut tasks, Some("hybrid-rt")) }?;
//! let index = rt.queue.submit([sdk_commands]);
//! rt.device.poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None }).ok();
//! rt.context().mark_gpu_task_completed(ticket)?;
//! # Ok(()) }
//! ```
#![deny(missing_docs)]

use ash::vk;
use hybrid_rt::{DeviceDesc, DeviceFeatures, ExecuteContext, GpuTicket, ImageInput, InitSettings, TaskContainer};
use std::ffi::CStr;
use wgpu::hal::api::Vulkan;
use wgpu::hal::vulkan::conv;

pub use hybrid_rt;
pub use wgpu;

/// The state (and so the Vulkan layout) of a texture the SDK reads: sampled.
pub const SDK_READ: wgpu::TextureUses = wgpu::TextureUses::RESOURCE;
/// The state (and layout: GENERAL) of a texture the SDK writes: storage.
pub const SDK_WRITE: wgpu::TextureUses = wgpu::TextureUses::STORAGE_READ_WRITE;
/// The state of a buffer the SDK copies geometry from.
pub const SDK_COPY: wgpu::BufferUses = wgpu::BufferUses::COPY_SRC;

/// The wgpu features a device made elsewhere (by the engine, by Bevy) must have been created
/// with for [`RtDevice::attach`]: with them wgpu itself enables the acceleration-structure,
/// ray-tracing-pipeline, buffer-device-address and float-atomic extensions and their features.
/// Add [`wgpu::Features::EXPERIMENTAL_RAY_QUERY`] for the SDK's ray-query paths where the
/// adapter has it. The "EXPERIMENTAL" features need `ExperimentalFeatures::enabled()` in the
/// `DeviceDescriptor`.
pub const SDK_WGPU_FEATURES: wgpu::Features =
    wgpu::Features::EXPERIMENTAL_RAY_TRACING_PIPELINES.union(wgpu::Features::SHADER_FLOAT32_ATOMIC);

/// Adds to a device that wgpu-hal is about to create what the SDK needs and wgpu does not
/// enable for [`SDK_WGPU_FEATURES`]: the rest of [`hybrid_rt::REQUIRED_DEVICE_EXTENSIONS`]
/// (push descriptors) and a `VkPhysicalDeviceSynchronization2Features`. Call it from wgpu-hal's
/// create-device callback — `wgpu::hal::vulkan::Adapter::open_with_callback`'s, or one
/// registered with Bevy's raw Vulkan initialisation (`RawVulkanInitSettings`), which hands its
/// callbacks the same arguments. The feature struct must outlive the device's creation, which
/// a callback cannot see the end of: each call leaks one (a few dozen bytes per device made).
///
/// ```no_run
/// # fn demo(adapter: &wgpu::Adapter) -> Result<(), Box<dyn std::error::Error>> {
/// use hybrid_rt_wgpu::{add_sdk_requirements, RtDevice, SDK_WGPU_FEATURES};
/// use wgpu::hal::api::Vulkan;
/// let desc = wgpu::DeviceDescriptor {
///     required_features: SDK_WGPU_FEATURES,
///     // SAFETY: the SDK uses wgpu's ray-tracing features only to have them enabled.
///     experimental_features: unsafe { wgpu::ExperimentalFeatures::enabled() },
///     ..Default::default()
/// };
/// // SAFETY: the callback only adds extensions and a feature struct.
/// let open = unsafe {
///     adapter.as_hal::<Vulkan>().ok_or("not Vulkan")?.open_with_callback(
///         desc.required_features,
///         &desc.required_limits,
///         &desc.memory_hints,
///         Some(Box::new(|mut args| add_sdk_requirements(&mut args))),
///     )?
/// };
/// // SAFETY: `open` is a device of this adapter.
/// let (device, queue) = unsafe { adapter.create_device_from_hal(open, &desc) }?;
/// let rt = RtDevice::attach(adapter, &device, &queue, &hybrid_rt::InitSettings::default())?;
/// # Ok(()) }
/// ```
pub fn add_sdk_requirements(args: &mut wgpu::hal::vulkan::CreateDeviceCallbackArgs<'_, '_, '_>) {
    for e in hybrid_rt::REQUIRED_DEVICE_EXTENSIONS {
        if !args.extensions.contains(e) {
            args.extensions.push(e);
        }
    }
    // wgpu chains per-extension feature structs and never this one (nor a Vulkan13Features
    // that would also carry it): the chain gets one struct of its type.
    let synchronization2: &'static mut vk::PhysicalDeviceSynchronization2Features<'static> =
        Box::leak(Box::new(vk::PhysicalDeviceSynchronization2Features::default().synchronization2(true)));
    synchronization2.p_next = args.create_info.p_next as *mut std::ffi::c_void;
    args.create_info.p_next =
        synchronization2 as *const vk::PhysicalDeviceSynchronization2Features<'_> as *const std::ffi::c_void;
}

/// What can go wrong between wgpu and the SDK.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BridgeError {
    /// The adapter, texture, view, buffer or encoder is not one of wgpu's Vulkan backend.
    #[error("not a wgpu Vulkan object: {0}")]
    NotVulkan(&'static str),
    /// The adapter's device lacks what the SDK needs (the list names it).
    #[error("the adapter cannot run hybrid-rt: {0}")]
    Unsupported(String),
    /// vkCreateDevice failed.
    #[error("vkCreateDevice: {0}")]
    CreateDevice(vk::Result),
    /// wgpu-hal refused the device.
    #[error("wgpu-hal: {0}")]
    Hal(#[from] wgpu::hal::DeviceError),
    /// wgpu refused the device.
    #[error("wgpu: {0}")]
    RequestDevice(#[from] wgpu::RequestDeviceError),
    /// The SDK refused (see the error).
    #[error("hybrid-rt: {0}")]
    Sdk(#[from] hybrid_rt::Error),
}

/// A wgpu device and queue that hybrid-rt runs on, and the SDK's context.
///
/// Fields drop in order: the context goes before the device it was made on.
pub struct RtDevice {
    context: ExecuteContext,
    /// The raw device (the same `VkDevice` as `device`), for the SDK command buffer's barriers.
    raw: ash::Device,
    /// wgpu's queue (submit the SDK's command buffers here, with your others).
    pub queue: wgpu::Queue,
    /// wgpu's device, with the SDK's extensions and features enabled.
    pub device: wgpu::Device,
    adapter: wgpu::Adapter,
}

/// Whether `adapter` can run the SDK: `Err` names what it lacks.
pub fn check_adapter(adapter: &wgpu::Adapter) -> Result<(), BridgeError> {
    // SAFETY: only read (the guard keeps the adapter alive while used).
    let hal = unsafe { adapter.as_hal::<Vulkan>() }.ok_or(BridgeError::NotVulkan("adapter"))?;
    let support = hybrid_rt::query_device_support(hal.shared_instance().raw_instance(), hal.raw_physical_device());
    if support.supported {
        Ok(())
    } else {
        Err(BridgeError::Unsupported(support.missing.join(", ")))
    }
}

impl RtDevice {
    /// Opens a wgpu device on `adapter` as `desc` asks, with the SDK's extensions and features
    /// added (ray queries too where the adapter has them), and the SDK's context on it.
    pub fn new(
        adapter: &wgpu::Adapter,
        desc: &wgpu::DeviceDescriptor<'_>,
        settings: &InitSettings,
    ) -> Result<RtDevice, BridgeError> {
        check_adapter(adapter)?;
        // SAFETY: wgpu's Vulkan objects are only used while they live (the guard holds the
        // adapter; the instance outlives every device of it).
        let hal = unsafe { adapter.as_hal::<Vulkan>() }.ok_or(BridgeError::NotVulkan("adapter"))?;
        let (entry, instance, pdev, api_version) = vulkan_of(&hal);
        let support = hybrid_rt::query_device_support(&instance, pdev);

        // wgpu's extensions, then the SDK's.
        let mut extensions: Vec<&'static CStr> = hal.required_device_extensions(desc.required_features);
        let sdk_extensions = hybrid_rt::REQUIRED_DEVICE_EXTENSIONS.iter().chain(if support.ray_query {
            hybrid_rt::OPTIONAL_DEVICE_EXTENSIONS
        } else {
            &[]
        });
        for e in sdk_extensions {
            if !extensions.contains(e) {
                extensions.push(e);
            }
        }
        let names: Vec<_> = extensions.iter().map(|e| e.as_ptr()).collect();
        // wgpu-hal, like wgpu itself, opens queue 0 of family 0.
        let family = 0;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let mut wgpu_features = hal.physical_device_features(&extensions, desc.required_features);
        let info = wgpu_features
            .add_to_device_create(vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_extension_names(&names));
        // wgpu gives core features through pEnabledFeatures and per-extension structs in pNext;
        // the SDK's merge needs a VkPhysicalDeviceFeatures2 head: move the core features there
        // (a chain may not have both), then switch the SDK's features on in wgpu's structs and
        // append the structs wgpu did not add.
        // SAFETY: add_to_device_create set pEnabledFeatures to a struct of `wgpu_features`.
        let core = unsafe { *info.p_enabled_features };
        let mut features2 = vk::PhysicalDeviceFeatures2 { features: core, p_next: info.p_next as *mut _, ..Default::default() };
        let mut sdk_features = DeviceFeatures::required(support.ray_query);
        // SAFETY: `features2` heads wgpu's valid chain; `sdk_features` outlives its use below.
        unsafe { sdk_features.merge_into(&mut features2) };
        let chain = &features2 as *const vk::PhysicalDeviceFeatures2<'_> as *const std::ffi::c_void;
        let info = vk::DeviceCreateInfo { p_enabled_features: std::ptr::null(), p_next: chain, ..info };
        // SAFETY: a valid create info for this physical device (extensions it supports, checked
        // by query_device_support and wgpu-hal).
        let raw = unsafe { instance.create_device(pdev, &info, None) }.map_err(BridgeError::CreateDevice)?;

        // wgpu-hal takes ownership of the VkDevice (it destroys it with the wgpu device).
        // SAFETY: `raw` was made from this adapter with these extensions and wgpu's features.
        let open = unsafe {
            hal.device_from_raw(
                raw.clone(),
                None,
                &extensions,
                desc.required_features,
                &desc.required_limits,
                &desc.memory_hints,
                family,
                0,
            )
        }?;
        drop(hal);
        // SAFETY: `open` is a device of this adapter.
        let (device, queue) = unsafe { adapter.create_device_from_hal(open, desc) }?;

        let debug_utils = shared_has_debug_utils(adapter);
        let dd = DeviceDesc::new(&entry, &instance, pdev, &raw)
            .enabled_extensions(&extensions)
            .instance_api_version(api_version)
            .enabled_features(chain)
            .with_debug_utils(debug_utils);
        // SAFETY: the handles are the live instance, physical device and device wgpu now owns,
        // made with `extensions` and the chain `features2` heads (alive until this returns);
        // the context is dropped before the wgpu device (field order).
        let context = unsafe { ExecuteContext::new(&dd, settings) }?;
        Ok(RtDevice { context, raw, queue, device, adapter: adapter.clone() })
    }

    /// The SDK's context on a wgpu device made elsewhere — by the engine or by Bevy — with
    /// [`SDK_WGPU_FEATURES`] requested and [`add_sdk_requirements`] called in wgpu-hal's
    /// create-device callback. Checked: the adapter, the device's wgpu features and its enabled extensions
    /// (an error names what is missing). Not checkable (a `VkDevice` cannot be asked): that
    /// `synchronization2` was enabled, which `add_sdk_requirements` does. Ray queries are used
    /// where the device has [`wgpu::Features::EXPERIMENTAL_RAY_QUERY`].
    ///
    /// The returned `RtDevice` holds clones of `device` and `queue`; drop it (the context)
    /// before the engine destroys the device.
    pub fn attach(
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: &InitSettings,
    ) -> Result<RtDevice, BridgeError> {
        check_adapter(adapter)?;
        let features = device.features();
        if !features.contains(SDK_WGPU_FEATURES) {
            return Err(BridgeError::Unsupported(format!(
                "the device was created without the wgpu features {:?} (SDK_WGPU_FEATURES)",
                SDK_WGPU_FEATURES.difference(features)
            )));
        }
        // SAFETY: as in `new`.
        let hal = unsafe { adapter.as_hal::<Vulkan>() }.ok_or(BridgeError::NotVulkan("adapter"))?;
        let (entry, instance, pdev, api_version) = vulkan_of(&hal);
        drop(hal);
        // SAFETY: the raw device and its extension list are read while `device` lives.
        let hal_device = unsafe { device.as_hal::<Vulkan>() }.ok_or(BridgeError::NotVulkan("device"))?;
        if hal_device.raw_physical_device() != pdev {
            return Err(BridgeError::Unsupported("the device was not opened on this adapter".into()));
        }
        let raw = hal_device.raw_device().clone();
        let extensions: Vec<&'static CStr> = hal_device.enabled_device_extensions().to_vec();
        drop(hal_device);
        let missing: Vec<String> = hybrid_rt::REQUIRED_DEVICE_EXTENSIONS
            .iter()
            .filter(|e| !extensions.contains(e))
            .map(|e| e.to_string_lossy().into_owned())
            .collect();
        if !missing.is_empty() {
            return Err(BridgeError::Unsupported(format!(
                "the device was created without {} (call add_sdk_requirements in the create-device callback)",
                missing.join(", ")
            )));
        }
        let ray_query =
            features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) && extensions.contains(&ash::khr::ray_query::NAME);
        // What the device was created with, as the SDK reads it: SDK_WGPU_FEATURES made wgpu
        // enable the ray-tracing, address and atomic features, add_sdk_requirements
        // synchronization2 (the chain is read during `ExecuteContext::new` only).
        let mut enabled = DeviceFeatures::required(ray_query);
        let _ = enabled.push_to(vk::DeviceCreateInfo::default());
        let dd = DeviceDesc::new(&entry, &instance, pdev, &raw)
            .enabled_extensions(&extensions)
            .instance_api_version(api_version)
            .enabled_features(enabled.chain())
            .with_debug_utils(shared_has_debug_utils(adapter));
        // SAFETY: the live instance, physical device and device of `device`, made with
        // `extensions` and (the caller's contract, checked above where it can be) the SDK's
        // features; the context is dropped before the clones of the wgpu device it holds.
        let context = unsafe { ExecuteContext::new(&dd, settings) }?;
        Ok(RtDevice { context, raw, queue: queue.clone(), device: device.clone(), adapter: adapter.clone() })
    }

    /// The SDK's context: handles, containers, tickets.
    pub fn context(&self) -> &ExecuteContext {
        &self.context
    }

    /// The SDK's view of a wgpu texture that will be in `state` when the SDK's commands run
    /// ([`SDK_READ`] for inputs, [`SDK_WRITE`] for outputs): its image and view, Vulkan format,
    /// size, the layout wgpu keeps it in for `state`, and its usage flags.
    pub fn image(
        &self,
        texture: &wgpu::Texture,
        view: &wgpu::TextureView,
        state: wgpu::TextureUses,
    ) -> Result<ImageInput, BridgeError> {
        let format = texture.format();
        // SAFETY: raw handles read while the wgpu objects live; never destroyed by us. One
        // guard at a time: each holds wgpu's resource lock, which is not reentrant.
        let image = unsafe { texture.as_hal::<Vulkan>().ok_or(BridgeError::NotVulkan("texture"))?.raw_handle() };
        let raw_view = unsafe { view.as_hal::<Vulkan>().ok_or(BridgeError::NotVulkan("texture view"))?.raw_handle() };
        let vk_format =
            unsafe { self.adapter.as_hal::<Vulkan>().ok_or(BridgeError::NotVulkan("adapter"))?.texture_format_as_raw(format) };
        Ok(ImageInput {
            image,
            view: raw_view,
            format: vk_format,
            width: texture.width(),
            height: texture.height(),
            layout: conv::derive_image_layout(state, format),
            usage: conv::map_texture_usage(texture_uses(texture.usage(), format)),
        })
    }

    /// The `VkBuffer` of a wgpu buffer (geometry the SDK copies: `COPY_SRC` usage).
    pub fn buffer(&self, buffer: &wgpu::Buffer) -> Result<vk::Buffer, BridgeError> {
        // SAFETY: as in `image`.
        unsafe { Ok(buffer.as_hal::<Vulkan>().ok_or(BridgeError::NotVulkan("buffer"))?.raw_handle()) }
    }

    /// Records `container` into a new wgpu command buffer (between two full memory barriers)
    /// and returns it with the SDK's ticket. Submit it on [`RtDevice::queue`] after the
    /// commands that [`prepare`]d its resources. On error nothing was scheduled on the GPU and
    /// the container keeps its tasks.
    ///
    /// # Safety
    /// The wgpu textures and buffers whose handles the container's tasks hold (from
    /// [`RtDevice::image`] and [`RtDevice::buffer`]) stay alive until the ticket has come back
    /// (`ExecuteContext::build_gpu_task`'s contract; wgpu cannot see the SDK's use of them).
    pub unsafe fn record(
        &self,
        container: &mut TaskContainer,
        label: Option<&str>,
    ) -> Result<(wgpu::CommandBuffer, GpuTicket), BridgeError> {
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label });
        // SAFETY: the raw command buffer is recorded into only inside the callback, not ended
        // or destroyed; wgpu ends it at `finish`.
        let ticket = unsafe {
            encoder.as_hal_mut::<Vulkan, _, _>(|e| -> Result<GpuTicket, BridgeError> {
                let cmd = e.ok_or(BridgeError::NotVulkan("command encoder"))?.raw_handle();
                full_barrier(&self.raw, cmd);
                // The encoder's buffer is recording; the tasks' resources: this function's contract.
                let ticket = self.context.build_gpu_task(container, cmd)?;
                full_barrier(&self.raw, cmd);
                Ok(ticket)
            })
        }?;
        Ok((encoder.finish(), ticket))
    }
}

/// Puts textures and buffers in the states the SDK's commands expect ([`SDK_READ`],
/// [`SDK_WRITE`], [`SDK_COPY`]), in a wgpu encoder recorded before the SDK's command buffer.
pub fn prepare(
    encoder: &mut wgpu::CommandEncoder,
    reads: &[&wgpu::Texture],
    writes: &[&wgpu::Texture],
    copies: &[&wgpu::Buffer],
) {
    let textures = reads.iter().map(|t| (t, SDK_READ)).chain(writes.iter().map(|t| (t, SDK_WRITE)));
    encoder.transition_resources(
        copies.iter().map(|b| wgpu::BufferTransition { buffer: *b, state: SDK_COPY }),
        textures.map(|(t, state)| wgpu::TextureTransition { texture: *t, selector: None, state }),
    );
}

/// The loader, instance and physical device of a wgpu Vulkan adapter, and the API version its
/// instance was made with (wgpu-hal asks for Vulkan 1.3 whenever the loader is 1.1 or newer:
/// see its `Instance::init`).
fn vulkan_of(hal: &wgpu::hal::vulkan::Adapter) -> (ash::Entry, ash::Instance, vk::PhysicalDevice, u32) {
    let shared = hal.shared_instance();
    let api_version =
        if shared.instance_api_version() >= vk::API_VERSION_1_1 { vk::API_VERSION_1_3 } else { vk::API_VERSION_1_0 };
    (shared.entry().clone(), shared.raw_instance().clone(), hal.raw_physical_device(), api_version)
}

fn shared_has_debug_utils(adapter: &wgpu::Adapter) -> bool {
    // SAFETY: read only.
    unsafe { adapter.as_hal::<Vulkan>() }
        .map(|a| a.shared_instance().extensions().contains(&ash::ext::debug_utils::NAME))
        .unwrap_or(false)
}

/// The wgpu-hal uses a texture of these wgpu usages was created with (what wgpu-core passes
/// wgpu-hal at creation, less internal additions: a subset, which is all the SDK's check needs).
fn texture_uses(usage: wgpu::TextureUsages, format: wgpu::TextureFormat) -> wgpu::TextureUses {
    let mut uses = wgpu::TextureUses::empty();
    let pairs = [
        (wgpu::TextureUsages::COPY_SRC, wgpu::TextureUses::COPY_SRC),
        (wgpu::TextureUsages::COPY_DST, wgpu::TextureUses::COPY_DST),
        (wgpu::TextureUsages::TEXTURE_BINDING, wgpu::TextureUses::RESOURCE),
        (wgpu::TextureUsages::STORAGE_BINDING, wgpu::TextureUses::STORAGE_READ_WRITE),
    ];
    for (u, h) in pairs {
        if usage.contains(u) {
            uses |= h;
        }
    }
    if usage.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) {
        uses |= if format.is_depth_stencil_format() {
            wgpu::TextureUses::DEPTH_STENCIL_WRITE
        } else {
            wgpu::TextureUses::COLOR_TARGET
        };
    }
    uses
}

/// Orders everything before with everything after (the SDK's stages are not among those wgpu
/// synchronises its tracked uses with: ray-tracing shaders, acceleration-structure builds).
fn full_barrier(device: &ash::Device, cmd: vk::CommandBuffer) {
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
    // SAFETY: `cmd` is recording (inside as_hal_mut); synchronization2 is enabled (the SDK's).
    unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier)) };
}
