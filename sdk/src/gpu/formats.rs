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
