//! # hybrid-rt
//!
//! Ray-traced ambient occlusion, shadows, diffuse GI and reflections for a *rasterizing* Vulkan
//! engine. The engine keeps its renderer and its queues: it hands the SDK its G-buffer and
//! camera, and the SDK records ray-tracing work into a command buffer the engine owns.
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
//! ## Layers
//! Arrows point one way (docs/design-notes.md has the picture):
//! `context` (the engine that records containers; nothing imports it) → `passes` (one module
//! per GPU pass) → `scene` (registries, BLAS queue, TLAS) → `cache` (surfel layouts, sample
//! pages) → `gpu` (ash helpers) → `types` (the public plain data) and `error`.
//!
//! See docs/ for the integration guide and shared/DESIGN.md for the architecture.
pub(crate) mod cache;
pub(crate) mod context;
pub mod error;
pub mod gpu;
pub(crate) mod passes;
pub(crate) mod scene;
#[doc(hidden)]
pub mod shaders;
pub mod types;

pub use context::container::TaskContainer;
pub use context::ExecuteContext;
pub use error::{Error, HandleProblem, Result};
pub use gpu::device::{query_device_support, DeviceDesc, DeviceSupport, OPTIONAL_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS};
pub use gpu::features::DeviceFeatures;
pub use gpu::memory::{AllocationCount, ResourceAllocations};
// The public data, family by family (not `types::*`, which would also export the family
// modules under names the crate's own layers use).
pub use types::cache::*;
pub use types::denoise::*;
pub use types::handles::{DenoisingContextHandle, GeometryHandle, InstanceHandle};
pub use types::inputs::*;
pub use types::limits::*;
pub use types::scene::*;
pub use types::settings::*;
pub use types::ticket::*;
pub use types::trace::*;

/// Version of the SDK (the C ABI checks it at context creation).
pub const VERSION: (u32, u32, u32) = (0, 1, 0);

// Re-exported so users name the same versions the SDK was built with.
pub use ash;
pub use glam;
