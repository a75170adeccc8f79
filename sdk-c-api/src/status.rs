//! Status codes, the thread-local last-error message, and the panic guard every entry point
//! runs inside: nothing unwinds across the C boundary.
use hybrid_rt::Error;
use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Result of every `hrt_*` call. On anything but `HRT_OK`, `hrt_last_error_message` tells
/// what went wrong, naming the field.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HrtStatus {
    HRT_OK = 0,
    /// A required pointer argument was NULL.
    HRT_ERROR_NULL_POINTER = 1,
    /// The header the caller was compiled with does not match this library.
    HRT_ERROR_VERSION_MISMATCH = 2,
    HRT_ERROR_MISSING_DEVICE_SUPPORT = 3,
    HRT_ERROR_VULKAN = 4,
    HRT_ERROR_OUT_OF_MEMORY = 5,
    HRT_ERROR_INVALID_HANDLE = 6,
    HRT_ERROR_INVALID_INPUT = 7,
    HRT_ERROR_UNSUPPORTED_FORMAT = 8,
    HRT_ERROR_BUFFER_TOO_SMALL = 9,
    HRT_ERROR_INVALID_TRANSFORM = 10,
    HRT_ERROR_WORKING_SETS_EXHAUSTED = 11,
    HRT_ERROR_UNKNOWN_TICKET = 12,
    HRT_ERROR_TICKETS_IN_FLIGHT = 13,
    HRT_ERROR_GEOMETRY_IN_USE = 14,
    HRT_ERROR_FOREIGN_CONTAINER = 15,
    /// An SDK bug (a caught panic); the context may be unusable.
    HRT_ERROR_INTERNAL = 16,
    /// The container's context was destroyed.
    HRT_ERROR_CONTEXT_DESTROYED = 17,
    /// The ticket's command buffer has not finished on the GPU (submitted and waited for?):
    /// nothing was recycled; hand the same ticket back once its fence has signalled.
    HRT_ERROR_TICKET_NOT_COMPLETE = 18,
}

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

pub(crate) fn set_last_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = msg);
}

pub(crate) fn last_error() -> String {
    LAST_ERROR.with(|e| e.borrow().clone())
}

pub(crate) fn status_of(e: &Error) -> HrtStatus {
    use HrtStatus::*;
    match e {
        Error::MissingDeviceSupport { .. } => HRT_ERROR_MISSING_DEVICE_SUPPORT,
        Error::Vulkan { .. } => HRT_ERROR_VULKAN,
        Error::OutOfMemory { .. } => HRT_ERROR_OUT_OF_MEMORY,
        Error::InvalidHandle { .. } => HRT_ERROR_INVALID_HANDLE,
        Error::InvalidInput { .. } => HRT_ERROR_INVALID_INPUT,
        Error::UnsupportedFormat { .. } => HRT_ERROR_UNSUPPORTED_FORMAT,
        Error::BufferTooSmall { .. } => HRT_ERROR_BUFFER_TOO_SMALL,
        Error::InvalidTransform { .. } => HRT_ERROR_INVALID_TRANSFORM,
        Error::WorkingSetsExhausted { .. } => HRT_ERROR_WORKING_SETS_EXHAUSTED,
        Error::UnknownTicket { .. } => HRT_ERROR_UNKNOWN_TICKET,
        Error::TicketNotComplete { .. } => HRT_ERROR_TICKET_NOT_COMPLETE,
        Error::TicketsInFlight { .. } => HRT_ERROR_TICKETS_IN_FLIGHT,
        Error::GeometryInUse { .. } => HRT_ERROR_GEOMETRY_IN_USE,
        Error::ForeignContainer => HRT_ERROR_FOREIGN_CONTAINER,
        Error::ContextDestroyed => HRT_ERROR_CONTEXT_DESTROYED,
        _ => HRT_ERROR_INTERNAL,
    }
}

/// What an entry point body returns on failure.
pub(crate) struct Failure(pub HrtStatus, pub String);

impl From<Error> for Failure {
    fn from(e: Error) -> Failure {
        Failure(status_of(&e), e.to_string())
    }
}

pub(crate) fn null(what: &str) -> Failure {
    Failure(HrtStatus::HRT_ERROR_NULL_POINTER, format!("{what} is NULL"))
}

/// Runs an entry point: maps errors to a status (recording the message) and panics to
/// HRT_ERROR_INTERNAL.
pub(crate) fn guard(f: impl FnOnce() -> Result<(), Failure>) -> HrtStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => HrtStatus::HRT_OK,
        Ok(Err(Failure(status, msg))) => {
            set_last_error(msg);
            status
        }
        Err(panic) => {
            let msg = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            set_last_error(format!("internal error (panic): {msg}"));
            HrtStatus::HRT_ERROR_INTERNAL
        }
    }
}

/// The status names, indexed by value (checked against the enum in the tests).
const STATUS_NAMES: [&std::ffi::CStr; 19] = [
    c"HRT_OK",
    c"HRT_ERROR_NULL_POINTER",
    c"HRT_ERROR_VERSION_MISMATCH",
    c"HRT_ERROR_MISSING_DEVICE_SUPPORT",
    c"HRT_ERROR_VULKAN",
    c"HRT_ERROR_OUT_OF_MEMORY",
    c"HRT_ERROR_INVALID_HANDLE",
    c"HRT_ERROR_INVALID_INPUT",
    c"HRT_ERROR_UNSUPPORTED_FORMAT",
    c"HRT_ERROR_BUFFER_TOO_SMALL",
    c"HRT_ERROR_INVALID_TRANSFORM",
    c"HRT_ERROR_WORKING_SETS_EXHAUSTED",
    c"HRT_ERROR_UNKNOWN_TICKET",
    c"HRT_ERROR_TICKETS_IN_FLIGHT",
    c"HRT_ERROR_GEOMETRY_IN_USE",
    c"HRT_ERROR_FOREIGN_CONTAINER",
    c"HRT_ERROR_INTERNAL",
    c"HRT_ERROR_CONTEXT_DESTROYED",
    c"HRT_ERROR_TICKET_NOT_COMPLETE",
];

/// The name of a status code as this header spells it ("HRT_ERROR_INVALID_INPUT"): a static
/// NUL-terminated string for logs, "HRT_STATUS_UNKNOWN" for a value that is no HrtStatus.
/// (What went wrong is `hrt_last_error_message`.)
#[no_mangle]
pub extern "C" fn hrt_status_string(status: i32) -> *const std::ffi::c_char {
    let name = usize::try_from(status).ok().and_then(|i| STATUS_NAMES.get(i));
    name.copied().unwrap_or(c"HRT_STATUS_UNKNOWN").as_ptr()
}

#[cfg(test)]
mod tests {
    use super::*;
    use HrtStatus::*;

    #[test]
    fn every_status_has_its_name() {
        let name = |s: i32| unsafe { std::ffi::CStr::from_ptr(hrt_status_string(s)) }.to_str().unwrap().to_owned();
        let all = [
            HRT_OK,
            HRT_ERROR_NULL_POINTER,
            HRT_ERROR_VERSION_MISMATCH,
            HRT_ERROR_MISSING_DEVICE_SUPPORT,
            HRT_ERROR_VULKAN,
            HRT_ERROR_OUT_OF_MEMORY,
            HRT_ERROR_INVALID_HANDLE,
            HRT_ERROR_INVALID_INPUT,
            HRT_ERROR_UNSUPPORTED_FORMAT,
            HRT_ERROR_BUFFER_TOO_SMALL,
            HRT_ERROR_INVALID_TRANSFORM,
            HRT_ERROR_WORKING_SETS_EXHAUSTED,
            HRT_ERROR_UNKNOWN_TICKET,
            HRT_ERROR_TICKETS_IN_FLIGHT,
            HRT_ERROR_GEOMETRY_IN_USE,
            HRT_ERROR_FOREIGN_CONTAINER,
            HRT_ERROR_INTERNAL,
            HRT_ERROR_CONTEXT_DESTROYED,
            HRT_ERROR_TICKET_NOT_COMPLETE,
        ];
        assert_eq!(all.len(), STATUS_NAMES.len());
        for s in all {
            assert_eq!(name(s as i32), format!("{s:?}"));
        }
        assert_eq!(name(all.len() as i32), "HRT_STATUS_UNKNOWN");
        assert_eq!(name(-1), "HRT_STATUS_UNKNOWN");
    }
}
