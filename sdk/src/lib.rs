//! # hybrid-rt
//!
//! Ray-traced ambient occlusion, shadows, diffuse GI and reflections for a *rasterizing* Vulkan
//! engine. The engine keeps its renderer and its queues: it hands the SDK its G-buffer and
//! camera, and the SDK records ray-tracing work into a command buffer the engine owns.
//!
//! One frame: register a mesh and an instance, build the BVH, and trace AO into the engine's
//! command buffer; once the engine's fence says the GPU is done, hand the ticket back.
//!
//! ```no_run
//! use hybrid_rt::ash::vk;
//! use hybrid_rt::*;
//!
//! fn frame(
//!     ctx: &ExecuteContext,
//!     cmd: vk::CommandBuffer,
//!     mesh_data: GeometryInput,
//!     transform: glam::Affine3A,
//!     ao: &TraceAmbientOcclusionTask,
//! ) -> hybrid_rt::Result<GpuTicket> {
//!     let mesh = ctx.create_geometry_handles(1)[0];
//!     let inst = ctx.create_instance_handles(1)[0];
//!     let mut frame = ctx.create_task_container(); // Send; one per thread; reuse it
//!     // SAFETY: the buffers in `mesh_data` are alive (and stay so until the ticket is back).
//!     unsafe { frame.schedule_geometry(&GeometryTask { handle: mesh, input: mesh_data, ..Default::default() }) }?;
//!     frame.schedule_instance(&InstanceTask {
//!         handle: inst,
//!         input: InstanceInput { geometry: mesh, transform, ..Default::default() },
//!         ..Default::default()
//!     })?;
//!     frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 4, ..Default::default() })?;
//!     frame.schedule_ambient_occlusion(ao)?;
//!     // SAFETY: `cmd` is recording; the images and buffers the tasks name outlive the ticket.
//!     unsafe { ctx.build_gpu_task(&mut frame, cmd) } // records into *your* command buffer
//! }
//!
//! fn frame_done(ctx: &ExecuteContext, ticket: GpuTicket) -> hybrid_rt::Result<()> {
//!     // After your fence for that command buffer signalled.
//!     let done = ctx.mark_gpu_task_completed(ticket)?;
//!     for t in &done.timings {
//!         println!("{:?}: {:.3} ms", t.kind, t.gpu_ms);
//!     }
//!     Ok(())
//! }
//! ```
//!
//! ## Where to start
//!
//! - [`ExecuteContext`]: the SDK on the engine's device ([`DeviceDesc`], [`DeviceFeatures`],
//!   [`query_device_support`]); it creates handles, containers and denoising contexts, records
//!   containers with [`ExecuteContext::build_gpu_task`] and takes tickets back.
//! - [`TaskContainer`]: one frame's tasks, each checked when it is scheduled.
//! - The tasks and their inputs, all plain data with `Default`, grouped in [`types`] and
//!   re-exported here: scene tasks ([`GeometryTask`], [`InstanceTask`], [`BvhBuildTask`]),
//!   traces ([`TraceAmbientOcclusionTask`], [`TraceShadowTask`], [`TraceSpecularTask`], ...),
//!   the direct-lighting cache ([`DirectLightingInjectionTask`], [`RelightCacheTask`], ...) and
//!   the denoisers ([`DenoiseSpecularAndDiffuseTask`], ...).
//! - [`Error`]: every way a call can fail, naming the field, handle or limit at fault.
//!
//! The [integration guide](https://github.com/hybrid-rt/hybrid-rt/blob/main/docs/integration.md)
//! follows an engine through a frame (device set-up, inputs, layouts and barriers, lifetimes,
//! threading, debugging), and `examples/ao_reflections.rs` is the whole integration in one
//! program.
#![deny(missing_docs)]

pub(crate) mod cache;
pub(crate) mod context;
pub mod error;
pub mod gpu;
pub(crate) mod passes;
pub(crate) mod scene;
#[doc(hidden)]
pub mod shaders;
pub(crate) mod tasks;
pub mod types;

pub use context::container::TaskContainer;
pub use context::ExecuteContext;
pub use error::{Error, HandleProblem, Result};
pub use gpu::device::{query_device_support, DeviceDesc, DeviceSupport, OPTIONAL_DEVICE_EXTENSIONS, REQUIRED_DEVICE_EXTENSIONS};
pub use gpu::features::DeviceFeatures;
pub use gpu::memory::{AllocationCount, MemoryKind, ResourceAllocations};
// The public data, family by family (not `types::*`, which would also export the family
// modules under names the crate's own layers use).
pub use types::cache::*;
pub use types::denoise::*;
pub use types::handles::{DenoisingContextHandle, GeometryHandle, InstanceHandle, ManyLightsContextHandle};
pub use types::inputs::*;
pub use types::limits::*;
pub use types::many_lights::*;
pub use types::scene::*;
pub use types::settings::*;
pub use types::ticket::*;
pub use types::trace::*;

/// Version of the SDK (major, minor, patch), from the workspace's Cargo.toml — the one place
/// the version is written. The C ABI checks it at context creation.
pub const VERSION: (u32, u32, u32) =
    (parse(env!("CARGO_PKG_VERSION_MAJOR")), parse(env!("CARGO_PKG_VERSION_MINOR")), parse(env!("CARGO_PKG_VERSION_PATCH")));

const fn parse(digits: &str) -> u32 {
    let bytes = digits.as_bytes();
    let mut i = 0;
    let mut v = 0;
    while i < bytes.len() {
        v = v * 10 + (bytes[i] - b'0') as u32;
        i += 1;
    }
    v
}

// Re-exported so users name the same versions the SDK was built with.
pub use ash;
pub use glam;
