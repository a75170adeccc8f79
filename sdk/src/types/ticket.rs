//! Tickets and the timings a completed ticket reports.

/// Proof that a container was recorded into a command buffer. Hand it back with
/// `ExecuteContext::mark_gpu_task_completed` once the GPU has finished that command buffer.
/// Move-only: in Rust a ticket cannot be returned twice.
#[must_use = "a ticket must be handed back with mark_gpu_task_completed, or its working set stays busy"]
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct GpuTicket {
    pub(crate) ctx: u16,
    pub(crate) serial: u64,
}

impl GpuTicket {
    /// Increases by one per built container.
    pub fn serial(&self) -> u64 {
        self.serial
    }

    /// The ticket as one integer (for FFI or storing beside a fence).
    pub fn into_raw(self) -> u64 {
        ((self.ctx as u64) << 48) | (self.serial & 0xffff_ffff_ffff)
    }

    /// Rebuilds a ticket from `into_raw`. A forged or already-returned value is refused by
    /// `mark_gpu_task_completed` with `Error::UnknownTicket`.
    pub fn from_raw(raw: u64) -> GpuTicket {
        GpuTicket { ctx: (raw >> 48) as u16, serial: raw & 0xffff_ffff_ffff }
    }
}

/// Which kind of work a timing covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum TaskKind {
    /// All BVH work of the ticket: geometry copies, BLAS builds/refits/compactions, TLAS.
    Bvh = 0,
    /// `TraceAmbientOcclusionTask` (or its debug view).
    AmbientOcclusion = 1,
    /// Inside `Bvh`: the batched BLAS builds and refits (and compaction copies).
    BlasBuild = 2,
    /// Inside `Bvh`: the TLAS build (only when the scene changed since the working set's last).
    TlasBuild = 3,
    /// A direct-lighting injection and its cache resolve.
    DirectLightingInjection = 4,
    /// Cache maintenance of the ticket: new layouts, new and cleared caches.
    CacheUpdate = 5,
    /// A cache transfer between two instances.
    CacheTransfer = 6,
    /// `TraceShadowTask`.
    Shadow = 7,
    /// `TraceDiffuseTask`.
    Diffuse = 8,
    /// `TraceSpecularTask`.
    Specular = 9,
    /// `TraceMultiShadowTask`.
    MultiShadow = 10,
    /// `DenoiseSpecularTask`.
    DenoiseSpecular = 11,
    /// `DenoiseDiffuseTask`.
    DenoiseDiffuse = 12,
    /// `DenoiseSpecularAndDiffuseTask`.
    DenoiseSpecularAndDiffuse = 13,
    /// `DenoiseDiffuseOcclusionTask`.
    DenoiseDiffuseOcclusion = 14,
    /// `DenoiseShadowTask`.
    DenoiseShadow = 15,
    /// `DenoiseMultiShadowTask`.
    DenoiseMultiShadow = 16,
    /// `RelightCacheTask`.
    CacheRelight = 17,
}

/// The GPU time of one task of a ticket, from timestamp queries around it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
#[non_exhaustive]
pub struct TaskTiming {
    /// What the interval covers.
    pub kind: TaskKind,
    /// Position of the task in its container (for Bvh: the first BVH task).
    pub task_index: u32,
    /// GPU time between the timestamps around the task, in milliseconds.
    pub gpu_ms: f64,
}

/// What a completed ticket reports.
#[derive(Debug, Clone, Default)]
#[non_exhaustive]
pub struct CompletedTask {
    /// The ticket's serial.
    pub serial: u64,
    /// Per-task GPU times. Empty when the device cannot time compute work.
    pub timings: Vec<TaskTiming>,
}

impl CompletedTask {
    /// Sum of the times of the tasks of `kind`.
    pub fn gpu_ms(&self, kind: TaskKind) -> f64 {
        self.timings.iter().filter(|t| t.kind == kind).map(|t| t.gpu_ms).sum()
    }
}
