//! `HrtImageInput`, the image every task reads or writes, and its two conversions: from C
//! (`image`) and from the SDK's values (`image_c`, used for the `hrt_*_default()` functions).
//! Every image field of every task goes through these two.
use crate::vulkan::{VkFormat, VkImage, VkImageLayout, VkImageView};
use ash::vk;
use ash::vk::Handle;
use hybrid_rt as rt;

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtImageInput {
    pub image: VkImage,
    pub view: VkImageView,
    pub format: VkFormat,
    pub width: u32,
    pub height: u32,
    /// Inputs: VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL (default) or another read-only layout;
    /// outputs: VK_IMAGE_LAYOUT_GENERAL.
    pub layout: VkImageLayout,
    /// The VkImageUsageFlags the image was created with (required: inputs need
    /// VK_IMAGE_USAGE_SAMPLED_BIT, outputs VK_IMAGE_USAGE_STORAGE_BIT; 0 is refused).
    pub usage: u32,
}

/// The SDK's image description of a C one (the SDK validates it when the task is scheduled).
pub(crate) fn image(i: &HrtImageInput) -> rt::ImageInput {
    rt::ImageInput {
        image: vk::Image::from_raw(i.image),
        view: vk::ImageView::from_raw(i.view),
        format: vk::Format::from_raw(i.format),
        width: i.width,
        height: i.height,
        layout: vk::ImageLayout::from_raw(i.layout),
        usage: vk::ImageUsageFlags::from_raw(i.usage),
    }
}

/// The C image description of an SDK one (for defaults).
pub(crate) fn image_c(i: &rt::ImageInput) -> HrtImageInput {
    HrtImageInput {
        image: i.image.as_raw(),
        view: i.view.as_raw(),
        format: i.format.as_raw(),
        width: i.width,
        height: i.height,
        layout: i.layout.as_raw(),
        usage: i.usage.as_raw(),
    }
}
