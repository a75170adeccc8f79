//! The Vulkan types as the header names them. They are declared by <vulkan/vulkan.h>, not by
//! cbindgen (cbindgen.toml excludes them); these aliases only give the Rust side the same
//! names and sizes. Non-dispatchable handles are 64-bit on every platform the SDK supports.
use std::ffi::c_void;

pub type VkInstance = *mut c_void;
pub type VkPhysicalDevice = *mut c_void;
pub type VkDevice = *mut c_void;
pub type VkCommandBuffer = *mut c_void;
pub type VkBuffer = u64;
pub type VkImage = u64;
pub type VkImageView = u64;
pub type VkFormat = i32;
pub type VkImageLayout = i32;
pub type PFN_vkGetInstanceProcAddr = *const c_void;
