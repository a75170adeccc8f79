//! Setting up the engine's device for the SDK: the device extensions and features it needs,
//! whether a physical device has them, and loading Vulkan's entry points.
use crate::args::{get_mut, write_string};
use crate::status::{guard, null, Failure, HrtStatus};
use crate::vulkan::{PFN_vkGetInstanceProcAddr, VkInstance, VkPhysicalDevice};
use ash::vk;
use ash::vk::Handle;
use hybrid_rt as rt;
use std::ffi::{c_char, c_void, CStr};

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

/// Writes a static list of extension names (built once) and its length (both optional).
unsafe fn extension_list(
    list: &'static std::sync::OnceLock<Vec<usize>>,
    sdk: &[&'static CStr],
    names: *mut *const *const c_char,
    count: *mut u32,
) {
    let v = list.get_or_init(|| sdk.iter().map(|n| n.as_ptr() as usize).collect());
    unsafe {
        if let Some(n) = names.as_mut() {
            *n = v.as_ptr() as *const *const c_char;
        }
        if let Some(c) = count.as_mut() {
            *c = v.len() as u32;
        }
    }
}

/// The device extensions the SDK needs (static strings). Enable all of them, plus
/// VK_KHR_ray_query where the device has it (`hrt_optional_device_extensions`), and these
/// features: bufferDeviceAddress (1.2), synchronization2 (1.3), accelerationStructure,
/// rayTracingPipeline, shaderBufferFloat32AtomicAdd (and rayQuery if enabled).
#[no_mangle]
pub unsafe extern "C" fn hrt_required_device_extensions(names: *mut *const *const c_char, count: *mut u32) {
    static NAMES: std::sync::OnceLock<Vec<usize>> = std::sync::OnceLock::new();
    extension_list(&NAMES, rt::REQUIRED_DEVICE_EXTENSIONS, names, count)
}

/// Optional extensions (VK_KHR_ray_query), same form as hrt_required_device_extensions.
#[no_mangle]
pub unsafe extern "C" fn hrt_optional_device_extensions(names: *mut *const *const c_char, count: *mut u32) {
    static NAMES: std::sync::OnceLock<Vec<usize>> = std::sync::OnceLock::new();
    extension_list(&NAMES, rt::OPTIONAL_DEVICE_EXTENSIONS, names, count)
}

pub(super) unsafe fn entry_from(get_instance_proc_addr: PFN_vkGetInstanceProcAddr) -> Result<ash::Entry, Failure> {
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
        write_string(&s.missing.join(", "), missing, missing_capacity);
        Ok(())
    })
}
