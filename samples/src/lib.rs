//! Shared pieces of the sample and the bench: built-in scenes, image output, argument parsing.
//! The engine side (device, images, submission) is `hybrid_rt_testkit::host`; the G-buffer
//! comes from `raster` (a Vulkan graphics pass, as an engine's) or, for comparison, from the
//! CPU reference renderer.
pub mod args;
pub mod gltf_scene;
pub mod gpu;
pub mod images;
pub mod lighting;
pub mod modes;
pub mod raster;
pub mod renderer;
pub mod report;
pub mod scene;
pub mod scenes;
pub mod window;
