//! # hybrid-rt
//!
//! Ray-traced ambient occlusion (and, as the SDK grows, shadows, reflections and diffuse GI)
//! for a *rasterizing* Vulkan engine. The engine keeps its renderer and its queues: it hands
//! the SDK its G-buffer and camera, and the SDK records ray-tracing work into a command buffer
//! the engine owns.
//!
//! ```text
//! let ctx = ExecuteContext::new(&DeviceDesc { .. }, &InitSettings::default())?;
//! let [mesh] = ctx.create_geometry_handles(1)[..] else { .. };
//! let mut frame = ctx.create_task_container();
//! frame.schedule_geometry(&GeometryTask { handle: mesh, input, ..Default::default() })?;
//! frame.schedule_instance(&InstanceTask { handle: inst, input: InstanceInput { geometry: mesh, .. }, .. })?;
//! frame.schedule_bvh_build(&BvhBuildTask::default())?;
//! frame.schedule_ambient_occlusion(&ao_task)?;
//! let ticket = ctx.build_gpu_task(&mut frame, cmd)?;   // records into the engine's cmd
//! // engine: end, submit, wait on its fence
//! let done = ctx.mark_gpu_task_completed(ticket)?;     // per-task GPU times in done.timings
//! ```
//!
//! See docs/ for the integration guide and shared/DESIGN.md for the architecture.
pub mod api;
pub(crate) mod cache;
pub mod error;
pub mod gpu;
pub(crate) mod passes;
pub(crate) mod scene;
#[doc(hidden)]
pub mod shaders;

pub use api::container::TaskContainer;
pub use api::context::{ExecuteContext, MAX_DENOISING_EXTENT};
pub use api::denoising::*;
pub use api::handles::{DenoisingContextHandle, GeometryHandle, InstanceHandle};
pub use api::settings::InitSettings;
pub use api::tasks::*;
pub use api::ticket::{CompletedTask, GpuTicket, TaskKind, TaskTiming};
pub use error::{Error, HandleProblem, Result};
pub use gpu::device::{
    query_device_support, DeviceDesc, DeviceFeatures, DeviceSupport, OPTIONAL_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS,
};
pub use gpu::memory::{AllocationCount, ResourceAllocations};

/// Largest `SurfelSettings::tile_resolution_limit`.
pub const MAX_TILE_RESOLUTION: u32 = cache::layout::MAX_RESOLUTION;

/// Version of the SDK (the C ABI checks it at context creation).
pub const VERSION: (u32, u32, u32) = (0, 1, 0);

// Re-exported so users name the same versions the SDK was built with.
pub use ash;
pub use glam;
