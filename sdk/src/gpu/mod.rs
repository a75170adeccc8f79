//! Thin ash helpers: the device and its loaders, memory, barriers, pipelines, deferred frees.
//! Nothing here knows what a pass computes.
pub(crate) mod allocation_log;
pub(crate) mod commands;
pub(crate) mod deferred;
pub mod device;
pub mod features;
pub(crate) mod formats;
pub mod memory;
pub(crate) mod pipeline;
pub(crate) mod sync;
pub(crate) mod timestamps;
pub(crate) mod upload;
