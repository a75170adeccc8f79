//! Shared pieces of the sample and the bench: built-in scenes, image output, argument parsing.
//! The engine side (device, images, submission) is `hybrid_rt_testkit::host`; the G-buffer
//! comes from the CPU reference renderer until the sample grows its own rasterizer.
pub mod args;
pub mod images;
pub mod scenes;
