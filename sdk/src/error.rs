//! The one error type of the SDK. Every public entry point returns [`Result`]; none panics on
//! bad input, and an error leaves the context as it was before the call.
use ash::vk;

/// Why a handle was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
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

/// Every way an SDK call can fail. Each leaves the context as it was before the call (a
/// failed build included), and names the field, handle or limit at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The device lacks, or the engine did not enable, something the SDK needs.
    #[error("the Vulkan device is missing: {}", .missing.join(", "))]
    MissingDeviceSupport {
        /// Every missing extension, feature, device function or API version, by name.
        missing: Vec<String>,
    },

    /// A Vulkan call failed.
    #[error("{call} failed: {result:?}")]
    Vulkan {
        /// The Vulkan function.
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },

    /// Device memory could not be allocated (or a buffer would exceed `maxBufferSize`).
    #[error("out of memory allocating {what}: {detail}")]
    OutOfMemory {
        /// What the memory was for.
        what: &'static str,
        /// The allocator's or the limit's message.
        detail: String,
    },

    /// A handle that is null, foreign, stale, or in the wrong state for the task.
    #[error(
        "{}{kind} handle {raw:#x}{} {problem}",
        if field.is_empty() { String::new() } else { format!("{field}: ") },
        .name.as_ref().map(|n| format!(" (\"{n}\")")).unwrap_or_default()
    )]
    InvalidHandle {
        /// The field or argument that held it ("InstanceTask.input.geometry"), empty where
        /// there is none to name.
        field: &'static str,
        /// "geometry", "instance" or "denoising context".
        kind: &'static str,
        /// The handle's raw value.
        raw: u64,
        /// Why it was refused.
        problem: HandleProblem,
        /// Its debug name, where the engine gave it one (`ExecuteContext::set_geometry_name`)
        /// and the handle is still live.
        name: Option<String>,
    },

    /// A parameter is out of range, null, or inconsistent with another or with a device limit.
    #[error("invalid {what}: {why}")]
    InvalidInput {
        /// The field (`TraceCommon.viewport`, ...).
        what: &'static str,
        /// What is wrong with it.
        why: String,
    },

    /// An image or buffer format the SDK cannot read or write for that input.
    #[error("{what}: format {format:?} is not supported (expected {expected})")]
    UnsupportedFormat {
        /// The field.
        what: &'static str,
        /// The format given.
        format: vk::Format,
        /// The formats it accepts.
        expected: &'static str,
    },

    /// A buffer region lies past the end of the buffer.
    #[error("{what}: needs {needed} bytes but the buffer holds at most {available}")]
    BufferTooSmall {
        /// The field.
        what: &'static str,
        /// Bytes the region reaches (offset + size).
        needed: u64,
        /// Bytes the buffer can hold (its memory requirement).
        available: u64,
    },

    /// A matrix or transform holds NaN/infinity, or cannot be inverted.
    #[error("{what} is not a finite, invertible transform")]
    InvalidTransform {
        /// The field.
        what: &'static str,
    },

    /// Every working set is in flight: hand tickets back before building more.
    #[error("all {in_flight} working sets are in flight; mark a GPU task completed first")]
    WorkingSetsExhausted {
        /// Tickets in flight (`InitSettings::supported_working_sets`).
        in_flight: u32,
    },

    /// The ticket is not in flight: returned twice, forged, or from another context.
    #[error("GPU ticket {serial} is not in flight (returned twice or foreign)")]
    UnknownTicket {
        /// The ticket's serial.
        serial: u64,
    },

    /// The GPU has not finished the ticket's commands (the last one, a marker the SDK writes,
    /// has not run): the ticket stays in flight. Hand it back once the engine's fence says the
    /// command buffer is done — `GpuTicket::from_raw(raw)` rebuilds it.
    #[error("GPU ticket {serial} is not complete on the GPU yet (submitted and waited for?)")]
    TicketNotComplete {
        /// The ticket's serial.
        serial: u64,
        /// The ticket as `GpuTicket::into_raw` gives it, to hand back later.
        raw: u64,
    },

    /// `release_device_resources_immediately` or `ExecuteContext::destroy` while tickets are
    /// out.
    #[error("tickets still in flight: {serials:?}")]
    TicketsInFlight {
        /// Their serials.
        serials: Vec<u64>,
    },

    /// A geometry cannot be destroyed while registered instances use it.
    #[error("geometry handle {raw:#x} is used by {instances} registered instance(s)")]
    GeometryInUse {
        /// The geometry handle's raw value.
        raw: u64,
        /// Registered instances that use it.
        instances: usize,
    },

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

/// The SDK's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Names the field that held a refused handle (an `InvalidHandle` that names none yet);
    /// any other error is returned as it is.
    pub(crate) fn for_field(self, at: &'static str) -> Error {
        match self {
            Error::InvalidHandle { field: "", kind, raw, problem, name } => {
                Error::InvalidHandle { field: at, kind, raw, problem, name }
            }
            other => other,
        }
    }

    pub(crate) fn vk(call: &'static str) -> impl FnOnce(vk::Result) -> Error {
        move |result| Error::Vulkan { call, result }
    }

    pub(crate) fn invalid(what: &'static str, why: impl Into<String>) -> Error {
        Error::InvalidInput { what, why: why.into() }
    }
}
