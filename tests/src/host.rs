//! The headless Vulkan host the tests play the engine with: `hybrid_rt_host`, which the sample
//! and the bench build on too (validation-layer capture included: a host that saw a validation
//! error or a counted warning panics when dropped).
pub use hybrid_rt_host::{
    layout_access, texel_size, vkerr, AsyncCompute, Host, HostBuffer, HostImage, HostResult, API_VERSION, WORK_STAGES,
};
