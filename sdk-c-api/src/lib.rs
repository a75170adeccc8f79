//! The C ABI of hybrid-rt. The header `include/hybrid_rt.h` is generated from this crate by
//! cbindgen (`HRT_BLESS=1 cargo test -p hybrid-rt-c header` rewrites it; the same test fails
//! when it is stale).
//!
//! Conventions: every function returns an `HrtStatus` (or a plain value that cannot fail);
//! output goes through pointers; a NULL required pointer is `HRT_ERROR_NULL_POINTER`; on error
//! `hrt_last_error_message` holds a message for the calling thread. No panic crosses this
//! boundary. Contexts and containers are opaque pointers; geometry and instance handles and
//! tickets are 64-bit integers that the SDK checks (stale, foreign, returned twice).
//!
//! One module per API area, each with its C structs, their conversions to the SDK's types, the
//! `hrt_*_default()` functions and the calls: `context` (with the device set-up), `scene`
//! (with geometry), `cache`, `trace` (with shadows and the shading traces), `denoise`,
//! `relight`, `many_lights`. Every C struct mirrors an SDK struct field for field, with the
//! same defaults, and each area defines the `HRT_TASK_*` values of its own tasks. The support modules:
//! `vulkan` (the Vulkan types as the header names them), `image` (`HrtImageInput`), `args`
//! (reading arguments, writing results), `status` (status codes, the last error, the panic
//! guard), `live` (the registry of live contexts and containers) and `log_bridge`.
#![allow(non_camel_case_types, clippy::missing_safety_doc)]
mod args;
mod cache;
mod context;
mod denoise;
mod image;
mod live;
mod log_bridge;
mod many_lights;
mod relight;
mod scene;
mod status;
mod trace;
mod vulkan;

pub use cache::*;
pub use context::*;
pub use denoise::*;
pub use image::HrtImageInput;
pub use log_bridge::{HrtLogCallback, HrtLogSeverity};
pub use many_lights::*;
pub use relight::*;
pub use scene::*;
pub use status::HrtStatus;
pub use trace::*;
pub use vulkan::*;
