//! What the SDK knows about image formats.
use ash::vk;

/// Channels of the formats denoise inputs may have (None: not one of them).
pub(crate) fn channel_count(f: vk::Format) -> Option<u32> {
    use vk::Format as F;
    Some(match f {
        F::R8_UNORM | F::R16_UNORM | F::R16_SFLOAT | F::R32_SFLOAT => 1,
        F::R16G16_SFLOAT | F::R32G32_SFLOAT => 2,
        F::R8G8B8A8_UNORM | F::R16G16B16A16_SFLOAT | F::R32G32B32A32_SFLOAT => 4,
        _ => return None,
    })
}

/// Colour formats a float sampler reads, the R channel first: unorm, snorm, sRGB and float,
/// packed or not. The input mask accepts those of them the device can sample
/// (`FormatSet::sampled`); integer formats need an integer sampler, and depth/stencil formats an
/// aspect the SDK's views do not choose.
pub(crate) const FLOAT_READABLE_FORMATS: &[vk::Format] = &[
    vk::Format::R8_UNORM,
    vk::Format::R8_SNORM,
    vk::Format::R8_SRGB,
    vk::Format::R8G8_UNORM,
    vk::Format::R8G8_SNORM,
    vk::Format::R8G8_SRGB,
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::R8G8B8A8_SNORM,
    vk::Format::R8G8B8A8_SRGB,
    vk::Format::B8G8R8A8_UNORM,
    vk::Format::B8G8R8A8_SNORM,
    vk::Format::B8G8R8A8_SRGB,
    vk::Format::A8B8G8R8_UNORM_PACK32,
    vk::Format::A8B8G8R8_SNORM_PACK32,
    vk::Format::A8B8G8R8_SRGB_PACK32,
    vk::Format::A2B10G10R10_UNORM_PACK32,
    vk::Format::A2R10G10B10_UNORM_PACK32,
    vk::Format::R5G6B5_UNORM_PACK16,
    vk::Format::B5G6R5_UNORM_PACK16,
    vk::Format::R4G4B4A4_UNORM_PACK16,
    vk::Format::B4G4R4A4_UNORM_PACK16,
    vk::Format::R5G5B5A1_UNORM_PACK16,
    vk::Format::B5G5R5A1_UNORM_PACK16,
    vk::Format::A1R5G5B5_UNORM_PACK16,
    vk::Format::R16_UNORM,
    vk::Format::R16_SNORM,
    vk::Format::R16_SFLOAT,
    vk::Format::R16G16_UNORM,
    vk::Format::R16G16_SNORM,
    vk::Format::R16G16_SFLOAT,
    vk::Format::R16G16B16A16_UNORM,
    vk::Format::R16G16B16A16_SNORM,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::B10G11R11_UFLOAT_PACK32,
    vk::Format::E5B9G9R9_UFLOAT_PACK32,
    vk::Format::R32_SFLOAT,
    vk::Format::R32G32_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
];

/// Every format an engine image the SDK writes may have (trace, denoise and debug outputs):
/// the shaders declare those images without a format qualifier, so one shader serves them all.
pub(crate) const OUTPUT_FORMATS: &[vk::Format] = &[
    vk::Format::R8_UNORM,
    vk::Format::R16_UNORM,
    vk::Format::R16_SFLOAT,
    vk::Format::R32_SFLOAT,
    vk::Format::R16G16_SFLOAT,
    vk::Format::R32G32_SFLOAT,
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R32_UINT,
    vk::Format::R32G32B32A32_UINT,
];

/// Which formats of one of the lists above the device supports for one use (bit i: the
/// list's format i), asked once when the context is made.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FormatSet {
    list: &'static [vk::Format],
    bits: u64,
}

impl FormatSet {
    /// The formats of `list` for which `supported` holds.
    fn of(list: &'static [vk::Format], supported: impl Fn(vk::Format) -> bool) -> FormatSet {
        const _: () = assert!(FLOAT_READABLE_FORMATS.len() <= 64 && OUTPUT_FORMATS.len() <= 64);
        FormatSet { list, bits: list.iter().enumerate().filter(|(_, f)| supported(**f)).fold(0, |m, (i, _)| m | 1 << i) }
    }

    /// The `FLOAT_READABLE_FORMATS` the device samples in optimal tiling (input masks).
    pub(crate) fn sampled(instance: &ash::Instance, pdev: vk::PhysicalDevice) -> FormatSet {
        FormatSet::of(FLOAT_READABLE_FORMATS, |f| {
            // SAFETY: a plain query on the engine's physical device.
            let props = unsafe { instance.get_physical_device_format_properties(pdev, f) };
            props.optimal_tiling_features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE)
        })
    }

    /// The `OUTPUT_FORMATS` the device writes without a format qualifier
    /// (`VK_FORMAT_FEATURE_2_STORAGE_WRITE_WITHOUT_FORMAT_BIT`, optimal tiling). Vulkan 1.3
    /// reports it per format, so the SDK needs no device-wide
    /// `shaderStorageImageWriteWithoutFormat` (which wgpu, for one, leaves off).
    pub(crate) fn written_without_format(instance: &ash::Instance, pdev: vk::PhysicalDevice) -> FormatSet {
        FormatSet::of(OUTPUT_FORMATS, |f| {
            let mut props3 = vk::FormatProperties3::default();
            let mut props2 = vk::FormatProperties2::default().push_next(&mut props3);
            // SAFETY: a plain query on the engine's physical device (Vulkan 1.3, checked
            // before the context is made), with a property chain alive for the call.
            unsafe { instance.get_physical_device_format_properties2(pdev, f, &mut props2) };
            let wanted = vk::FormatFeatureFlags2::STORAGE_IMAGE | vk::FormatFeatureFlags2::STORAGE_WRITE_WITHOUT_FORMAT;
            props3.optimal_tiling_features.contains(wanted)
        })
    }

    /// Every output format (tests).
    #[cfg(test)]
    pub(crate) fn all_outputs() -> FormatSet {
        FormatSet::of(OUTPUT_FORMATS, |_| true)
    }

    /// Whether `f` is in the set (false for a format not in its list).
    pub(crate) fn contains(&self, f: vk::Format) -> bool {
        self.list.iter().position(|g| *g == f).is_some_and(|i| self.bits & (1 << i) != 0)
    }
}
