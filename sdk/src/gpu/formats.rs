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
/// (`MaskFormats`); integer formats need an integer sampler, and depth/stencil formats an
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

/// Which of `FLOAT_READABLE_FORMATS` the device samples in optimal tiling (bit i: format i),
/// asked once when the context is made.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct MaskFormats(u64);

impl MaskFormats {
    pub(crate) fn query(instance: &ash::Instance, pdev: vk::PhysicalDevice) -> MaskFormats {
        const _: () = assert!(FLOAT_READABLE_FORMATS.len() <= 64);
        let sampled = |f: vk::Format| {
            // SAFETY: a plain query on the engine's physical device.
            let props = unsafe { instance.get_physical_device_format_properties(pdev, f) };
            props.optimal_tiling_features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE)
        };
        MaskFormats(FLOAT_READABLE_FORMATS.iter().enumerate().filter(|(_, f)| sampled(**f)).fold(0, |m, (i, _)| m | 1 << i))
    }

    /// Whether the device samples `f` (false for a format not float-readable).
    pub(crate) fn sampled(&self, f: vk::Format) -> bool {
        FLOAT_READABLE_FORMATS.iter().position(|g| *g == f).is_some_and(|i| self.0 & (1 << i) != 0)
    }
}
