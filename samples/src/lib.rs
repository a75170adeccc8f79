//! Shared pieces of the sample, the bench and the quality program: built-in scenes, image
//! output, progress.
//! The engine side (device, images, submission, the triangle scenes) is `hybrid_rt_host`; the
//! G-buffer comes from `raster` (a Vulkan graphics pass, as an engine's).
pub mod figure;
mod gltf_lights;
mod gltf_rig;
pub mod gltf_scene;
pub mod gltf_textures;
mod gltf_uri;
pub mod gpu;
pub mod images;
pub mod lighting;
pub mod mesh_buffers;
pub mod modes;
pub mod progress;
pub mod raster;
pub mod renderer;
pub mod report;
pub mod scene;
pub mod scenes;
pub mod skin;
pub mod skinning;
pub mod tangents;
pub mod window;
