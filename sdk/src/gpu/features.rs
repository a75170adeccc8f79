//! The device features the SDK needs: the structs to enable ([`DeviceFeatures`]), merging them
//! into a feature chain an engine already has (its own `VkPhysicalDeviceVulkan13Features` and
//! all), and reading back from the chain the engine created its device with what it enabled —
//! a `VkDevice` cannot be asked, and a feature left off is a flood of validation errors (or a
//! crash) at the first build, not an error the engine can act on.
use ash::vk;
use std::ffi::c_void;

/// One feature the SDK relies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Feature {
    BufferDeviceAddress,
    Synchronization2,
    AccelerationStructure,
    RayTracingPipeline,
    ShaderBufferFloat32AtomicAdd,
    RayQuery,
}

impl Feature {
    pub const REQUIRED: [Feature; 5] = [
        Feature::BufferDeviceAddress,
        Feature::Synchronization2,
        Feature::AccelerationStructure,
        Feature::RayTracingPipeline,
        Feature::ShaderBufferFloat32AtomicAdd,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Feature::BufferDeviceAddress => "bufferDeviceAddress",
            Feature::Synchronization2 => "synchronization2",
            Feature::AccelerationStructure => "accelerationStructure",
            Feature::RayTracingPipeline => "rayTracingPipeline",
            Feature::ShaderBufferFloat32AtomicAdd => "shaderBufferFloat32AtomicAdd",
            Feature::RayQuery => "rayQuery",
        }
    }
}

/// Sets (`set`) or reads the SDK's features in one struct of a chain, whatever struct of the
/// several that can carry a feature the engine used (Vulkan12Features or the older
/// BufferDeviceAddressFeatures, ...). Returns the features the struct carries.
///
/// # Safety
/// `s` points to a valid feature struct whose `s_type` says what it is.
unsafe fn visit(s: *mut vk::BaseOutStructure<'_>, set: &[Feature], found: &mut Vec<Feature>) {
    use vk::StructureType as T;
    let on = |f: Feature| set.contains(&f);
    let mut mark = |f: Feature, v: &mut vk::Bool32| {
        if on(f) {
            *v = vk::TRUE;
        }
        if *v == vk::TRUE {
            found.push(f);
        }
    };
    // SAFETY: the caller's contract: `s` is a valid struct of the type its `s_type` names,
    // so the cast matches the memory behind it.
    unsafe {
        match (*s).s_type {
            T::PHYSICAL_DEVICE_VULKAN_1_2_FEATURES => mark(
                Feature::BufferDeviceAddress,
                &mut (*(s as *mut vk::PhysicalDeviceVulkan12Features<'_>)).buffer_device_address,
            ),
            T::PHYSICAL_DEVICE_BUFFER_DEVICE_ADDRESS_FEATURES => mark(
                Feature::BufferDeviceAddress,
                &mut (*(s as *mut vk::PhysicalDeviceBufferDeviceAddressFeatures<'_>)).buffer_device_address,
            ),
            T::PHYSICAL_DEVICE_VULKAN_1_3_FEATURES => {
                mark(Feature::Synchronization2, &mut (*(s as *mut vk::PhysicalDeviceVulkan13Features<'_>)).synchronization2)
            }
            T::PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES => mark(
                Feature::Synchronization2,
                &mut (*(s as *mut vk::PhysicalDeviceSynchronization2Features<'_>)).synchronization2,
            ),
            T::PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR => mark(
                Feature::AccelerationStructure,
                &mut (*(s as *mut vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'_>)).acceleration_structure,
            ),
            T::PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR => mark(
                Feature::RayTracingPipeline,
                &mut (*(s as *mut vk::PhysicalDeviceRayTracingPipelineFeaturesKHR<'_>)).ray_tracing_pipeline,
            ),
            T::PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT => mark(
                Feature::ShaderBufferFloat32AtomicAdd,
                &mut (*(s as *mut vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT<'_>)).shader_buffer_float32_atomic_add,
            ),
            T::PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR => {
                mark(Feature::RayQuery, &mut (*(s as *mut vk::PhysicalDeviceRayQueryFeaturesKHR<'_>)).ray_query)
            }
            _ => {}
        }
    }
}

/// The features enabled in a `pNext` chain (what `vkCreateDevice` was given), read only.
///
/// # Safety
/// `chain` is null or the head of a valid chain of Vulkan structs.
pub(crate) unsafe fn enabled_in(chain: *const c_void) -> Vec<Feature> {
    let mut found = Vec::new();
    let mut s = chain as *mut vk::BaseOutStructure<'_>;
    let mut guard = 0;
    while !s.is_null() && guard < 256 {
        // SAFETY: the caller's contract: `s` is a node of a valid chain.
        unsafe {
            visit(s, &[], &mut found);
            s = (*s).p_next;
        }
        guard += 1;
    }
    found
}

/// The feature structs the SDK needs enabled.
///
/// Either give a `VkDeviceCreateInfo` all of them with [`DeviceFeatures::push_to`] (an engine
/// with no feature chain of its own), or merge them into the chain you already have with
/// [`DeviceFeatures::merge_into`]. Both link to fields of `self`: keep it alive, and in place,
/// until `vkCreateDevice` — and `ExecuteContext::new`, which reads the chain — have returned.
#[non_exhaustive]
pub struct DeviceFeatures {
    /// The head of the chain `push_to` builds; no core feature is needed (the SDK writes
    /// engine images without a format qualifier only in formats whose
    /// `VK_FORMAT_FEATURE_2_STORAGE_WRITE_WITHOUT_FORMAT_BIT` the device reports, which Vulkan
    /// 1.3 allows without `shaderStorageImageWriteWithoutFormat`).
    pub core: vk::PhysicalDeviceFeatures2<'static>,
    /// `bufferDeviceAddress` (`push_to`).
    pub vulkan12: vk::PhysicalDeviceVulkan12Features<'static>,
    /// `synchronization2` (`push_to`).
    pub vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
    /// `accelerationStructure`.
    pub acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
    /// `rayTracingPipeline`.
    pub ray_tracing_pipeline: vk::PhysicalDeviceRayTracingPipelineFeaturesKHR<'static>,
    /// `rayQuery`, when asked for.
    pub ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR<'static>,
    /// `shaderBufferFloat32AtomicAdd` (cache injection).
    pub atomic_float: vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT<'static>,
    /// The per-extension forms `merge_into` appends to a chain without Vulkan12/13Features.
    pub buffer_device_address: vk::PhysicalDeviceBufferDeviceAddressFeatures<'static>,
    /// `synchronization2` as a per-extension struct (`merge_into`).
    pub synchronization2: vk::PhysicalDeviceSynchronization2Features<'static>,
}

/// The features it enables, by name.
impl std::fmt::Debug for DeviceFeatures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DeviceFeatures").field("enables", &self.wanted_names()).finish()
    }
}

impl DeviceFeatures {
    /// The features to enable. `with_ray_query` adds `rayQuery` (only if the device has
    /// VK_KHR_ray_query: see [`DeviceSupport`](crate::DeviceSupport)).
    pub fn required(with_ray_query: bool) -> Self {
        DeviceFeatures {
            core: vk::PhysicalDeviceFeatures2::default(),
            vulkan12: vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(true),
            vulkan13: vk::PhysicalDeviceVulkan13Features::default().synchronization2(true),
            acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true),
            ray_tracing_pipeline: vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default().ray_tracing_pipeline(true),
            ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(with_ray_query),
            atomic_float: vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default().shader_buffer_float32_atomic_add(true),
            buffer_device_address: vk::PhysicalDeviceBufferDeviceAddressFeatures::default().buffer_device_address(true),
            synchronization2: vk::PhysicalDeviceSynchronization2Features::default().synchronization2(true),
        }
    }

    /// The features this set enables, by their Vulkan names.
    fn wanted_names(&self) -> Vec<&'static str> {
        self.wants().into_iter().map(Feature::name).collect()
    }

    fn wants(&self) -> Vec<Feature> {
        let mut w = Feature::REQUIRED.to_vec();
        if self.ray_query.ray_query == vk::TRUE {
            w.push(Feature::RayQuery);
        }
        w
    }

    /// Links every struct into one chain starting at `core` and returns its head.
    fn link(&mut self) -> *mut c_void {
        self.core.p_next = &mut self.vulkan12 as *mut _ as *mut c_void;
        self.vulkan12.p_next = &mut self.vulkan13 as *mut _ as *mut c_void;
        self.vulkan13.p_next = &mut self.acceleration_structure as *mut _ as *mut c_void;
        self.acceleration_structure.p_next = &mut self.ray_tracing_pipeline as *mut _ as *mut c_void;
        self.ray_tracing_pipeline.p_next = &mut self.atomic_float as *mut _ as *mut c_void;
        self.atomic_float.p_next = if self.ray_query.ray_query == vk::TRUE {
            &mut self.ray_query as *mut _ as *mut c_void
        } else {
            std::ptr::null_mut()
        };
        self.ray_query.p_next = std::ptr::null_mut();
        &mut self.core as *mut _ as *mut c_void
    }

    /// Chains all the SDK's feature structs into `info` (as `pNext`, `pEnabledFeatures` left
    /// null) — for an engine with no chain of its own: `info` must have no `pNext` yet. Pass
    /// [`DeviceFeatures::chain`] as `DeviceDesc::enabled_features`.
    pub fn push_to<'a>(&'a mut self, info: vk::DeviceCreateInfo<'a>) -> vk::DeviceCreateInfo<'a> {
        let head = self.link();
        vk::DeviceCreateInfo { p_next: head as *const c_void, ..info }
    }

    /// The chain `push_to` built (what `DeviceDesc::enabled_features` takes).
    pub fn chain(&self) -> *const c_void {
        &self.core as *const _ as *const c_void
    }

    /// Enables the SDK's features in the engine's own chain: a feature whose struct the chain
    /// already has (a `VkPhysicalDeviceVulkan13Features`, or an older per-extension struct such
    /// as `VkPhysicalDeviceSynchronization2Features`) is switched on there; the structs it
    /// lacks are appended from `self`. The chain's `VkPhysicalDeviceFeatures2` (`features2`)
    /// stays its head: give it to `VkDeviceCreateInfo::pNext` and `DeviceDesc::enabled_features`.
    ///
    /// ```no_run
    /// use hybrid_rt::ash::{self, vk};
    /// use hybrid_rt::{DeviceDesc, DeviceFeatures, ExecuteContext, InitSettings, REQUIRED_DEVICE_EXTENSIONS};
    ///
    /// unsafe fn create(
    ///     entry: &ash::Entry,
    ///     instance: &ash::Instance,
    ///     pdev: vk::PhysicalDevice,
    ///     queues: &[vk::DeviceQueueCreateInfo<'_>],
    /// ) -> Result<(ash::Device, ExecuteContext), Box<dyn std::error::Error>> {
    ///     // The engine's own features, with the SDK's merged in.
    ///     let mut own13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true);
    ///     let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut own13);
    ///     let mut sdk = DeviceFeatures::required(false);
    ///     sdk.merge_into(&mut features2);
    ///     let names: Vec<_> = REQUIRED_DEVICE_EXTENSIONS.iter().map(|n| n.as_ptr()).collect();
    ///     let mut info = vk::DeviceCreateInfo::default().queue_create_infos(queues).enabled_extension_names(&names);
    ///     info.p_next = &features2 as *const _ as *const std::ffi::c_void;
    ///     let device = instance.create_device(pdev, &info, None)?;
    ///     let chain = &features2 as *const _ as *const std::ffi::c_void;
    ///     let desc = DeviceDesc::new(entry, instance, pdev, &device)
    ///         .enabled_extensions(REQUIRED_DEVICE_EXTENSIONS)
    ///         .instance_api_version(vk::API_VERSION_1_3)
    ///         .enabled_features(chain);
    ///     let ctx = ExecuteContext::new(&desc, &InitSettings::default())?;
    ///     Ok((device, ctx))
    /// }
    /// ```
    ///
    /// # Safety
    /// `features2` heads a valid chain of Vulkan structs; `self` stays alive and in place while
    /// the chain is used (it may now link to `self`'s fields).
    pub unsafe fn merge_into(&mut self, features2: &mut vk::PhysicalDeviceFeatures2<'_>) {
        let wants = self.wants();
        // Switch the features on wherever the chain has a struct for them.
        let mut covered = Vec::new();
        let mut s = features2 as *mut _ as *mut vk::BaseOutStructure<'_>;
        let mut tail = s;
        while !s.is_null() {
            tail = s;
            // SAFETY: the caller's contract: `s` is a node of a valid chain.
            unsafe {
                visit(s, &wants, &mut covered);
                s = (*s).p_next;
            }
        }
        // Append per-extension structs for the rest: unlike Vulkan12/13Features they never
        // clash with what the chain holds (a chain may not mix VkPhysicalDeviceVulkan13Features
        // with, say, VkPhysicalDeviceSynchronization2Features; this one has no Vulkan13Features,
        // or it would have covered the feature).
        let nodes: [(Feature, *mut c_void); 6] = [
            (Feature::BufferDeviceAddress, &mut self.buffer_device_address as *mut _ as *mut c_void),
            (Feature::Synchronization2, &mut self.synchronization2 as *mut _ as *mut c_void),
            (Feature::AccelerationStructure, &mut self.acceleration_structure as *mut _ as *mut c_void),
            (Feature::RayTracingPipeline, &mut self.ray_tracing_pipeline as *mut _ as *mut c_void),
            (Feature::ShaderBufferFloat32AtomicAdd, &mut self.atomic_float as *mut _ as *mut c_void),
            (Feature::RayQuery, &mut self.ray_query as *mut _ as *mut c_void),
        ];
        for (feature, node) in nodes {
            if wants.contains(&feature) && !covered.contains(&feature) {
                // SAFETY: `tail` is the chain's last node (valid, the caller's contract) or one
                // of `self`'s structs, which outlive the chain's use (the caller's contract).
                unsafe {
                    (*tail).p_next = node as *mut vk::BaseOutStructure<'_>;
                    tail = node as *mut vk::BaseOutStructure<'_>;
                    (*tail).p_next = std::ptr::null_mut();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An engine chain with its own Vulkan13Features (synchronization2 off)
    /// and the per-extension buffer-device-address struct: merging switches the SDK's features
    /// on in those structs, appends only what is missing, and never adds a second struct of a
    /// type the chain has (`push_to` did: vkCreateDevice then failed).
    #[test]
    fn merging_keeps_one_struct_per_type_and_enables_everything() {
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true);
        let mut bda = vk::PhysicalDeviceBufferDeviceAddressFeatures::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut v13).push_next(&mut bda);
        let mut sdk = DeviceFeatures::required(false);
        // SAFETY: the chain is made of live structs above; `sdk` outlives its use.
        unsafe { sdk.merge_into(&mut f2) };
        let mut types = Vec::new();
        let mut s = &f2 as *const _ as *const vk::BaseInStructure<'_>;
        while !s.is_null() {
            // SAFETY: `s` walks the chain built above.
            unsafe {
                types.push((*s).s_type);
                s = (*s).p_next;
            }
        }
        let mut unique = types.clone();
        unique.sort_by_key(|t| t.as_raw());
        unique.dedup();
        assert_eq!(unique.len(), types.len(), "one struct per type: {types:?}");
        assert!(
            !types.contains(&vk::StructureType::PHYSICAL_DEVICE_VULKAN_1_2_FEATURES),
            "no Vulkan12Features beside the per-extension struct"
        );
        // SAFETY: the chain built above.
        let enabled = unsafe { enabled_in(&f2 as *const _ as *const c_void) };
        for f in Feature::REQUIRED {
            assert!(enabled.contains(&f), "{} enabled", f.name());
        }
        assert!(!enabled.contains(&Feature::RayQuery));
        assert_eq!(v13.dynamic_rendering, vk::TRUE, "the engine's own features stay");
        assert_eq!(v13.synchronization2, vk::TRUE, "set in the engine's Vulkan13Features");
    }

    #[test]
    fn push_to_chains_every_required_feature() {
        let mut sdk = DeviceFeatures::required(true);
        let info = sdk.push_to(vk::DeviceCreateInfo::default());
        // SAFETY: `push_to` chained live structs of `sdk`.
        let enabled = unsafe { enabled_in(info.p_next) };
        for f in Feature::REQUIRED.iter().chain([&Feature::RayQuery]) {
            assert!(enabled.contains(f), "{}", f.name());
        }
    }
}
