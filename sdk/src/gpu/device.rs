//! The engine's device as the SDK sees it: extension loaders, the properties passes need, and
//! the check that everything the SDK relies on is there (with an error naming what is not).
use crate::error::{Error, Result};
use crate::gpu::commands::Commands;
use crate::gpu::formats::FormatSet;
use ash::{khr, vk};
use std::ffi::CStr;

/// Device extensions the SDK needs. Enable them all when creating the VkDevice.
pub const REQUIRED_DEVICE_EXTENSIONS: &[&CStr] = &[
    khr::acceleration_structure::NAME,
    khr::ray_tracing_pipeline::NAME,
    khr::deferred_host_operations::NAME,
    khr::push_descriptor::NAME,
    // Float atomics: injection adds radiance from many pixels into one cache sample.
    ash::ext::shader_atomic_float::NAME,
];

/// Enable where present: lets trace tasks with `use_inline_rt` run as compute shaders with ray
/// queries (NVIDIA's 580 driver on H100 does not expose it; lavapipe does).
pub const OPTIONAL_DEVICE_EXTENSIONS: &[&CStr] = &[khr::ray_query::NAME];

/// What a physical device offers, for the engine to decide before it creates its device.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct DeviceSupport {
    /// Everything required is present (`missing` is empty).
    pub supported: bool,
    /// Names of missing extensions, features or API version.
    pub missing: Vec<String>,
    /// VK_KHR_ray_query and its feature are available.
    pub ray_query: bool,
}

/// Checks a physical device against the SDK's needs.
pub fn query_device_support(instance: &ash::Instance, pdev: vk::PhysicalDevice) -> DeviceSupport {
    let mut missing = Vec::new();
    // SAFETY: plain queries on a physical device the caller got from this instance.
    let props = unsafe { instance.get_physical_device_properties(pdev) };
    if vk::api_version_major(props.api_version) < 1
        || (vk::api_version_major(props.api_version) == 1 && vk::api_version_minor(props.api_version) < 3)
    {
        missing.push("Vulkan 1.3".to_string());
    }
    // SAFETY: a plain query on a physical device of this instance.
    let exts = unsafe { instance.enumerate_device_extension_properties(pdev) }.unwrap_or_default();
    let has = |name: &CStr| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
    for name in REQUIRED_DEVICE_EXTENSIONS {
        if !has(name) {
            missing.push(name.to_string_lossy().into_owned());
        }
    }
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut frt = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut frq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut faf = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    {
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f12)
            .push_next(&mut f13)
            .push_next(&mut fas)
            .push_next(&mut frt)
            .push_next(&mut frq)
            .push_next(&mut faf);
        // SAFETY: a well-formed feature chain that lives for the call.
        unsafe { instance.get_physical_device_features2(pdev, &mut f2) };
    }
    let checks: [(&str, vk::Bool32); 5] = [
        ("feature shaderBufferFloat32AtomicAdd", faf.shader_buffer_float32_atomic_add),
        ("feature bufferDeviceAddress", f12.buffer_device_address),
        ("feature synchronization2", f13.synchronization2),
        ("feature accelerationStructure", fas.acceleration_structure),
        ("feature rayTracingPipeline", frt.ray_tracing_pipeline),
    ];
    for (name, on) in checks {
        if on != vk::TRUE {
            missing.push(name.to_string());
        }
    }
    let ray_query = has(khr::ray_query::NAME) && frq.ray_query == vk::TRUE;
    DeviceSupport { supported: missing.is_empty(), missing, ray_query }
}

/// The engine's objects the context is made from, and how the engine made them (a `VkDevice`
/// cannot be asked which extensions and features it has). The SDK clones the function tables;
/// it does not take ownership: the engine destroys its device after dropping the context.
#[derive(Clone)]
#[non_exhaustive]
pub struct DeviceDesc<'a> {
    /// The loader the engine uses.
    pub entry: &'a ash::Entry,
    /// The engine's instance.
    pub instance: &'a ash::Instance,
    /// The physical device of `device`.
    pub physical_device: vk::PhysicalDevice,
    /// The engine's device.
    pub device: &'a ash::Device,
    /// The device extensions the engine enabled: the SDK checks its needs against this list
    /// and uses ray queries only when VK_KHR_ray_query is here. Default none (`new` then names
    /// every required one missing).
    pub enabled_extensions: &'a [&'a CStr],
    /// `VkApplicationInfo::apiVersion` of the instance: 1.3 or later (the SDK records Vulkan
    /// 1.3 commands; with a 1.2 instance their function pointers may be missing). Default 0:
    /// unknown, refused by `ExecuteContext::new` — say what the instance was made with.
    pub instance_api_version: u32,
    /// The `pNext` chain given to `vkCreateDevice` (its feature structs), read during
    /// `ExecuteContext::new` only: [`DeviceFeatures::chain`](crate::DeviceFeatures::chain)
    /// after `push_to`, or the engine's own `VkPhysicalDeviceFeatures2` after `merge_into`.
    /// Default null (refused by `new`, naming the field).
    pub enabled_features: *const std::ffi::c_void,
    /// VK_EXT_debug_utils is enabled on the instance: the SDK then names every object it
    /// creates ("hybrid-rt ...") and labels every task in the command buffer, so RenderDoc,
    /// Nsight and validation messages show its passes. Default false.
    pub debug_utils: bool,
}

/// The device limits the SDK checks inputs against, so no size or count it hands the driver
/// exceeds what the device supports (an error names the limit instead).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Limits {
    /// VkPhysicalDeviceAccelerationStructurePropertiesKHR::maxPrimitiveCount (per BLAS).
    pub max_primitive_count: u64,
    /// ...::maxInstanceCount (per TLAS).
    pub max_instance_count: u64,
    /// VkPhysicalDeviceVulkan13Properties::maxBufferSize.
    pub max_buffer_size: u64,
    /// maxComputeWorkGroupCount[0] and [1].
    pub max_dispatch_groups: [u32; 2],
    /// VkPhysicalDeviceRayTracingPipelinePropertiesKHR::maxRayDispatchInvocationCount.
    pub max_ray_dispatch: u32,
    /// maxImageDimension2D (denoiser history images).
    pub max_image_dimension_2d: u32,
    /// The float-readable colour formats the device samples (input masks).
    pub mask_formats: FormatSet,
    /// The output formats the device writes without a format qualifier (engine outputs).
    pub write_formats: FormatSet,
}

/// The handles and what the engine says it made them with (the loader and function tables
/// are left out).
impl std::fmt::Debug for DeviceDesc<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DeviceDesc")
            .field("instance", &self.instance.handle())
            .field("physical_device", &self.physical_device)
            .field("device", &self.device.handle())
            .field("enabled_extensions", &self.enabled_extensions)
            .field("instance_api_version", &self.instance_api_version)
            .field("enabled_features", &self.enabled_features)
            .field("debug_utils", &self.debug_utils)
            .finish()
    }
}

impl<'a> DeviceDesc<'a> {
    /// The engine's objects; then say how it made them:
    ///
    /// ```no_run
    /// # use ash::vk;
    /// # fn f(entry: &ash::Entry, instance: &ash::Instance, pdev: vk::PhysicalDevice, device: &ash::Device,
    /// #      extensions: &[&std::ffi::CStr], chain: *const std::ffi::c_void) {
    /// let desc = hybrid_rt::DeviceDesc::new(entry, instance, pdev, device)
    ///     .enabled_extensions(extensions) // what vkCreateDevice was given
    ///     .instance_api_version(vk::API_VERSION_1_3) // VkApplicationInfo::apiVersion
    ///     .enabled_features(chain) // the pNext chain of vkCreateDevice
    ///     .with_debug_utils(true); // VK_EXT_debug_utils is on the instance
    /// # }
    /// ```
    pub fn new(
        entry: &'a ash::Entry,
        instance: &'a ash::Instance,
        physical_device: vk::PhysicalDevice,
        device: &'a ash::Device,
    ) -> DeviceDesc<'a> {
        DeviceDesc {
            entry,
            instance,
            physical_device,
            device,
            enabled_extensions: &[],
            instance_api_version: 0,
            enabled_features: std::ptr::null(),
            debug_utils: false,
        }
    }

    /// The device extensions the engine enabled (`enabled_extensions`).
    pub fn enabled_extensions(mut self, names: &'a [&'a CStr]) -> DeviceDesc<'a> {
        self.enabled_extensions = names;
        self
    }

    /// The instance's `VkApplicationInfo::apiVersion` (`instance_api_version`).
    pub fn instance_api_version(mut self, version: u32) -> DeviceDesc<'a> {
        self.instance_api_version = version;
        self
    }

    /// The `pNext` chain `vkCreateDevice` was given (`enabled_features`); read only by
    /// `ExecuteContext::new`, whose contract covers it.
    pub fn enabled_features(mut self, chain: *const std::ffi::c_void) -> DeviceDesc<'a> {
        self.enabled_features = chain;
        self
    }

    /// Says VK_EXT_debug_utils is enabled on the instance (object names and task labels).
    pub fn with_debug_utils(mut self, on: bool) -> DeviceDesc<'a> {
        self.debug_utils = on;
        self
    }
}

/// Loaders and properties used by the layers above.
pub(crate) struct Device {
    pub raw: ash::Device,
    pub accel: khr::acceleration_structure::Device,
    pub rt: khr::ray_tracing_pipeline::Device,
    pub push: khr::push_descriptor::Device,
    pub rt_props: vk::PhysicalDeviceRayTracingPipelinePropertiesKHR<'static>,
    pub scratch_alignment: u64,
    pub ubo_alignment: u64,
    /// Nanoseconds per timestamp tick; `None` when the device cannot time compute work.
    pub timestamp_period_ns: Option<f64>,
    pub ray_query: bool,
    pub device_name: String,
    pub limits: Limits,
    /// Object names and command-buffer labels (VK_EXT_debug_utils), when the engine has it.
    pub debug: Option<ash::ext::debug_utils::Device>,
}

/// Device functions the SDK calls that a 1.2 instance, or a device without an extension, may
/// leave unloaded (ash then installs a stub that panics — in a function that cannot unwind).
const DEVICE_FUNCTIONS: &[&CStr] = &[
    c"vkCmdPipelineBarrier2",
    c"vkCmdWriteTimestamp2",
    c"vkGetBufferDeviceAddress",
    c"vkCmdTraceRaysKHR",
    c"vkCmdBuildAccelerationStructuresKHR",
    c"vkCmdPushDescriptorSetKHR",
];

impl Device {
    /// # Safety
    /// As `ExecuteContext::new`: the handles are valid and belong together, and
    /// `enabled_features` is null or a valid chain.
    pub unsafe fn new(desc: &DeviceDesc<'_>) -> Result<Device> {
        let support = query_device_support(desc.instance, desc.physical_device);
        let mut missing = support.missing.clone();
        let api = desc.instance_api_version;
        if vk::api_version_major(api) < 1 || (vk::api_version_major(api) == 1 && vk::api_version_minor(api) < 3) {
            missing.push(format!(
                "a VkInstance of apiVersion 1.3 (DeviceDesc.instance_api_version is {}.{})",
                vk::api_version_major(api),
                vk::api_version_minor(api)
            ));
        }
        for name in REQUIRED_DEVICE_EXTENSIONS {
            if !desc.enabled_extensions.contains(name) {
                missing.push(format!("{} (not enabled on the VkDevice)", name.to_string_lossy()));
            }
        }
        if desc.enabled_features.is_null() {
            missing.push("DeviceDesc.enabled_features (null: give the pNext chain vkCreateDevice was given)".into());
        } else {
            // SAFETY: `enabled_features` is the chain vkCreateDevice was given (`new`'s contract).
            let enabled = unsafe { crate::gpu::features::enabled_in(desc.enabled_features) };
            for f in crate::gpu::features::Feature::REQUIRED {
                if !enabled.contains(&f) {
                    missing.push(format!("feature {} (not enabled on the VkDevice)", f.name()));
                }
            }
        }
        if missing.is_empty() {
            for name in DEVICE_FUNCTIONS {
                // SAFETY: the engine's live device of this instance; a NUL-terminated name.
                if unsafe { desc.instance.get_device_proc_addr(desc.device.handle(), name.as_ptr()) }.is_none() {
                    missing.push(format!("device function {} (not loaded)", name.to_string_lossy()));
                }
            }
        }
        if !missing.is_empty() {
            return Err(Error::MissingDeviceSupport { missing });
        }
        // SAFETY: as above (null was refused).
        let rq_feature =
            unsafe { crate::gpu::features::enabled_in(desc.enabled_features) }.contains(&crate::gpu::features::Feature::RayQuery);
        let ray_query = support.ray_query && rq_feature && desc.enabled_extensions.contains(&khr::ray_query::NAME);

        let mut rt_props = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut props13 = vk::PhysicalDeviceVulkan13Properties::default();
        let mut props2 =
            vk::PhysicalDeviceProperties2::default().push_next(&mut rt_props).push_next(&mut as_props).push_next(&mut props13);
        // SAFETY: a well-formed property chain on the engine's physical device, alive for the call.
        unsafe { desc.instance.get_physical_device_properties2(desc.physical_device, &mut props2) };
        let limits = props2.properties.limits;
        let device_name = props2.properties.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let scratch_alignment = as_props.min_acceleration_structure_scratch_offset_alignment.max(1) as u64;
        let rt_props = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR {
            p_next: std::ptr::null_mut(),
            _marker: std::marker::PhantomData,
            ..rt_props
        };
        let timestamp_period_ns = (limits.timestamp_compute_and_graphics == vk::TRUE).then_some(limits.timestamp_period as f64);
        let device_limits = Limits {
            max_primitive_count: as_props.max_primitive_count,
            max_instance_count: as_props.max_instance_count,
            max_buffer_size: props13.max_buffer_size,
            max_dispatch_groups: [limits.max_compute_work_group_count[0], limits.max_compute_work_group_count[1]],
            max_ray_dispatch: rt_props.max_ray_dispatch_invocation_count,
            max_image_dimension_2d: limits.max_image_dimension2_d,
            mask_formats: FormatSet::sampled(desc.instance, desc.physical_device),
            write_formats: FormatSet::written_without_format(desc.instance, desc.physical_device),
        };

        Ok(Device {
            raw: desc.device.clone(),
            accel: khr::acceleration_structure::Device::new(desc.instance, desc.device),
            rt: khr::ray_tracing_pipeline::Device::new(desc.instance, desc.device),
            push: khr::push_descriptor::Device::new(desc.instance, desc.device),
            rt_props,
            scratch_alignment,
            ubo_alignment: limits.min_uniform_buffer_offset_alignment.max(16),
            timestamp_period_ns,
            ray_query,
            device_name,
            limits: device_limits,
            debug: desc.debug_utils.then(|| ash::ext::debug_utils::Device::new(desc.instance, desc.device)),
        })
    }
}

impl Device {
    /// Names an SDK object for debuggers and validation messages ("hybrid-rt <name>").
    pub fn name<H: vk::Handle>(&self, handle: H, name: &str) {
        name_object(self.debug.as_ref(), handle, name);
    }

    /// Opens a labelled region of `cmd` ("hybrid-rt <name>"); close it with `end_label`.
    /// Without VK_EXT_debug_utils, nothing.
    pub fn begin_label(&self, cmd: &Commands, name: &str) {
        if self.debug.is_some() {
            cmd.begin_label(std::ffi::CString::new(format!("hybrid-rt {name}")).unwrap_or_default());
        }
    }

    pub fn end_label(&self, cmd: &Commands) {
        if self.debug.is_some() {
            cmd.end_label();
        }
    }
}

/// Names `handle` through `debug`, if the engine has VK_EXT_debug_utils.
pub(crate) fn name_object<H: vk::Handle>(debug: Option<&ash::ext::debug_utils::Device>, handle: H, name: &str) {
    let Some(d) = debug else { return };
    let Ok(text) = std::ffi::CString::new(format!("hybrid-rt {name}")) else { return };
    let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&text);
    // SAFETY: `handle` is a live object of this device. A failed naming changes nothing.
    let _ = unsafe { d.set_debug_utils_object_name(&info) };
}
