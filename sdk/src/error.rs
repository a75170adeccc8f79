//! The one error type of the SDK. Every public entry point returns [`Result`]; none panics on
//! bad input, and an error leaves the context as it was before the call.
use ash::vk;

/// Why a handle was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandleProblem {
    /// The null handle (0).
    Null,
    /// Made by another `ExecuteContext`.
    Foreign,
    /// Its slot was destroyed (and perhaps reused): the handle is stale.
    Destroyed,
    /// Alive, but no register task has been built for it yet.
    NotRegistered,
    /// A register task names a handle that is already registered.
    AlreadyRegistered,
}

impl std::fmt::Display for HandleProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            HandleProblem::Null => "is null",
            HandleProblem::Foreign => "belongs to another ExecuteContext",
            HandleProblem::Destroyed => "was destroyed (stale handle)",
            HandleProblem::NotRegistered => "is not registered",
            HandleProblem::AlreadyRegistered => "is already registered",
        })
    }
}

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The device lacks, or the engine did not enable, something the SDK needs.
    #[error("the Vulkan device is missing: {}", .missing.join(", "))]
    MissingDeviceSupport { missing: Vec<String> },

    /// A Vulkan call failed.
    #[error("{call} failed: {result:?}")]
    Vulkan { call: &'static str, result: vk::Result },

    /// Device memory could not be allocated.
    #[error("out of memory allocating {what}: {detail}")]
    OutOfMemory { what: &'static str, detail: String },

    #[error("{kind} handle {raw:#x} {problem}")]
    InvalidHandle { kind: &'static str, raw: u64, problem: HandleProblem },

    /// A parameter is out of range, null, or inconsistent with another.
    #[error("invalid {what}: {why}")]
    InvalidInput { what: &'static str, why: String },

    /// An image or buffer format the SDK cannot read or write for that input.
    #[error("{what}: format {format:?} is not supported (expected {expected})")]
    UnsupportedFormat { what: &'static str, format: vk::Format, expected: &'static str },

    /// A buffer region lies past the end of the buffer.
    #[error("{what}: needs {needed} bytes but the buffer holds at most {available}")]
    BufferTooSmall { what: &'static str, needed: u64, available: u64 },

    /// A matrix or transform holds NaN/infinity, or cannot be inverted.
    #[error("{what} is not a finite, invertible transform")]
    InvalidTransform { what: &'static str },

    /// Every working set is in flight: hand tickets back before building more.
    #[error("all {in_flight} working sets are in flight; mark a GPU task completed first")]
    WorkingSetsExhausted { in_flight: u32 },

    /// The ticket is not in flight: returned twice, forged, or from another context.
    #[error("GPU ticket {serial} is not in flight (returned twice or foreign)")]
    UnknownTicket { serial: u64 },

    /// The GPU has not finished the ticket's commands (the last one, a marker the SDK writes,
    /// has not run): the ticket stays in flight. Hand it back once the engine's fence says the
    /// command buffer is done — `GpuTicket::from_raw(raw)` rebuilds it.
    #[error("GPU ticket {serial} is not complete on the GPU yet (submitted and waited for?)")]
    TicketNotComplete { serial: u64, raw: u64 },

    /// `release_device_resources_immediately` while tickets are out.
    #[error("tickets still in flight: {serials:?}")]
    TicketsInFlight { serials: Vec<u64> },

    /// A geometry cannot be destroyed while registered instances use it.
    #[error("geometry handle {raw:#x} is used by {instances} registered instance(s)")]
    GeometryInUse { raw: u64, instances: usize },

    /// A task container made by another context.
    #[error("the task container belongs to another ExecuteContext")]
    ForeignContainer,

    /// The container's context was dropped.
    #[error("the task container's ExecuteContext has been destroyed")]
    ContextDestroyed,

    /// A bug in the SDK (a caught panic at the C boundary, an impossible state).
    #[error("internal error: {0}")]
    Internal(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn vk(call: &'static str) -> impl FnOnce(vk::Result) -> Error {
        move |result| Error::Vulkan { call, result }
    }

    pub(crate) fn invalid(what: &'static str, why: impl Into<String>) -> Error {
        Error::InvalidInput { what, why: why.into() }
    }
}
