//! hybrid-rt's test kit: the CPU reference renderer (`reference`), the headless Vulkan host
//! that plays the engine (`host`, re-exported from `hybrid_rt_host`), glue that loads reference
//! scenes into the SDK (`sdk_scene`), and the denoiser quality measurements (`quality`).
//! Used by the integration tests in tests/tests, the sample and the bench.
//!
//! Its doctests are the Rust snippets of the repository's README and user guides: each guide
//! is included below as the documentation of an item that exists only under `cfg(doctest)`,
//! so `cargo test` compiles every snippet against today's API (the published `hybrid-rt`
//! crate cannot include files outside its package).
pub mod host;
pub mod quality;
pub mod reference;
pub mod sdk_scene;
pub mod stats;

/// Compiles the Rust snippets of a markdown file as this crate's doctests.
macro_rules! markdown_doctests {
    ($($name:ident = $path:literal;)*) => {
        $(
            #[cfg(doctest)]
            #[doc = include_str!($path)]
            pub struct $name;
        )*
    };
}

markdown_doctests! {
    ReadmeDoctests = "../../README.md";
    IntegrationGuideDoctests = "../../docs/integration.md";
    MigrationGuideDoctests = "../../docs/migration-kickstart-rt.md";
    SampleGuideDoctests = "../../docs/sample.md";
    WgpuGuideDoctests = "../../docs/wgpu.md";
    CApiGuideDoctests = "../../docs/c-api.md";
    BenchmarksDoctests = "../../docs/benchmarks.md";
}
