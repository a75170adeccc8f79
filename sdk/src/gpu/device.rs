//! The engine's device as the SDK sees it: extension loaders, the properties passes need, and
//! the check that everything the SDK relies on is there (with an error naming what is not).
use crate::error::{Error, Result};
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

/// The feature structs the SDK needs enabled. Fill a `VkDeviceCreateInfo` with
/// [`DeviceFeatures::push_to`]; the `pNext` chain borrows `self`, so keep it alive until
/// `vkCreateDevice` returns.
pub struct DeviceFeatures {
    pub core: vk::PhysicalDeviceFeatures2<'static>,
    pub vulkan12: vk::PhysicalDeviceVulkan12Features<'static>,
    pub vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
    pub acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
    pub ray_tracing_pipeline: vk::PhysicalDeviceRayTracingPipelineFeaturesKHR<'static>,
    pub ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR<'static>,
    pub atomic_float: vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT<'static>,
}

impl DeviceFeatures {
    /// The features to enable. `with_ray_query` adds `rayQuery` (only if the device has
    /// VK_KHR_ray_query: see [`DeviceSupport`]).
    pub fn required(with_ray_query: bool) -> Self {
        DeviceFeatures {
            core: vk::PhysicalDeviceFeatures2::default().features(
                vk::PhysicalDeviceFeatures::default().shader_storage_image_write_without_format(true).shader_int64(false),
            ),
            vulkan12: vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(true),
            // maintenance4: compute shaders are SPIR-V 1.6, whose workgroup size is LocalSizeId.
            vulkan13: vk::PhysicalDeviceVulkan13Features::default().synchronization2(true).maintenance4(true),
            acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true),
            ray_tracing_pipeline: vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default().ray_tracing_pipeline(true),
            ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(with_ray_query),
            atomic_float: vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default().shader_buffer_float32_atomic_add(true),
        }
    }

    /// Chains the features into `info` (as `pNext`, with `pEnabledFeatures` left null).
    pub fn push_to<'a>(&'a mut self, info: vk::DeviceCreateInfo<'a>) -> vk::DeviceCreateInfo<'a> {
        let with_rq = self.ray_query.ray_query == vk::TRUE;
        let mut info = info
            .push_next(&mut self.core)
            .push_next(&mut self.vulkan12)
            .push_next(&mut self.vulkan13)
            .push_next(&mut self.acceleration_structure)
            .push_next(&mut self.ray_tracing_pipeline)
            .push_next(&mut self.atomic_float);
        if with_rq {
            info = info.push_next(&mut self.ray_query);
        }
        info
    }
}

/// What a physical device offers, for the engine to decide before it creates its device.
#[derive(Debug, Clone)]
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
    let core = {
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f12)
            .push_next(&mut f13)
            .push_next(&mut fas)
            .push_next(&mut frt)
            .push_next(&mut frq)
            .push_next(&mut faf);
        // SAFETY: a well-formed feature chain that lives for the call.
        unsafe { instance.get_physical_device_features2(pdev, &mut f2) };
        f2.features
    };
    let checks: [(&str, vk::Bool32); 7] = [
        ("feature shaderBufferFloat32AtomicAdd", faf.shader_buffer_float32_atomic_add),
        ("feature bufferDeviceAddress", f12.buffer_device_address),
        ("feature synchronization2", f13.synchronization2),
        ("feature maintenance4", f13.maintenance4),
        ("feature accelerationStructure", fas.acceleration_structure),
        ("feature rayTracingPipeline", frt.ray_tracing_pipeline),
        ("feature shaderStorageImageWriteWithoutFormat", core.shader_storage_image_write_without_format),
    ];
    for (name, on) in checks {
        if on != vk::TRUE {
            missing.push(name.to_string());
        }
    }
    let ray_query = has(khr::ray_query::NAME) && frq.ray_query == vk::TRUE;
    DeviceSupport { supported: missing.is_empty(), missing, ray_query }
}

/// The engine's objects the context is made from. The SDK clones the function tables; it does
/// not take ownership: the engine destroys its device after dropping the context.
#[derive(Clone)]
pub struct DeviceDesc<'a> {
    pub entry: &'a ash::Entry,
    pub instance: &'a ash::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: &'a ash::Device,
    /// The device extensions the engine enabled: the SDK checks its needs against this list
    /// (a VkDevice cannot be asked) and uses ray queries only when VK_KHR_ray_query is here.
    pub enabled_extensions: &'a [&'a CStr],
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
}

impl Device {
    pub fn new(desc: &DeviceDesc<'_>) -> Result<Device> {
        let support = query_device_support(desc.instance, desc.physical_device);
        let mut missing = support.missing.clone();
        for name in REQUIRED_DEVICE_EXTENSIONS {
            if !desc.enabled_extensions.contains(name) {
                missing.push(format!("{} (not enabled on the VkDevice)", name.to_string_lossy()));
            }
        }
        if !missing.is_empty() {
            return Err(Error::MissingDeviceSupport { missing });
        }
        let ray_query = support.ray_query && desc.enabled_extensions.contains(&khr::ray_query::NAME);

        let mut rt_props = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut props13 = vk::PhysicalDeviceVulkan13Properties::default();
        let mut props2 =
            vk::PhysicalDeviceProperties2::default().push_next(&mut rt_props).push_next(&mut as_props).push_next(&mut props13);
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
        })
    }
}
