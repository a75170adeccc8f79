//! hybrid-rt's test kit: the CPU reference renderer (`reference`), a headless Vulkan host that
//! plays the engine (`host`), and glue that loads reference scenes into the SDK (`sdk_scene`).
//! Used by the integration tests in tests/tests, the sample and the bench.
pub mod host;
pub mod reference;
pub mod sdk_scene;
pub mod stats;
