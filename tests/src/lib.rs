//! hybrid-rt's test kit: the CPU reference renderer (`reference`), a headless Vulkan host that
//! plays the engine (`host`), glue that loads reference scenes into the SDK (`sdk_scene`), and the denoiser quality
//! measurements (`quality`).
//! Used by the integration tests in tests/tests, the sample and the bench.
pub mod host;
pub mod quality;
pub mod reference;
pub mod sdk_scene;
pub mod stats;
