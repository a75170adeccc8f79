//! Forwards the SDK's `log` records to a C callback, filtered by severity.
use parking_lot::RwLock;
use std::ffi::{c_char, c_void, CString};

/// Severity of a diagnostic message (higher = more severe).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum HrtLogSeverity {
    HRT_LOG_DEBUG = 0,
    HRT_LOG_INFO = 1,
    HRT_LOG_WARNING = 2,
    HRT_LOG_ERROR = 3,
}

/// Receives one message (NUL-terminated, valid only during the call).
pub type HrtLogCallback = Option<unsafe extern "C" fn(severity: HrtLogSeverity, message: *const c_char, user_data: *mut c_void)>;

struct Sink {
    callback: HrtLogCallback,
    min: HrtLogSeverity,
    user_data: usize,
}

static SINK: RwLock<Option<Sink>> = RwLock::new(None);

struct Bridge;
static BRIDGE: Bridge = Bridge;

fn severity(level: log::Level) -> HrtLogSeverity {
    match level {
        log::Level::Error => HrtLogSeverity::HRT_LOG_ERROR,
        log::Level::Warn => HrtLogSeverity::HRT_LOG_WARNING,
        log::Level::Info => HrtLogSeverity::HRT_LOG_INFO,
        _ => HrtLogSeverity::HRT_LOG_DEBUG,
    }
}

impl log::Log for Bridge {
    fn enabled(&self, m: &log::Metadata<'_>) -> bool {
        SINK.read().as_ref().is_some_and(|s| severity(m.level()) >= s.min)
    }
    fn log(&self, record: &log::Record<'_>) {
        let sink = SINK.read();
        let Some(s) = sink.as_ref() else { return };
        let sev = severity(record.level());
        if sev < s.min {
            return;
        }
        if let (Some(cb), Ok(msg)) = (s.callback, CString::new(record.args().to_string())) {
            // SAFETY: the caller registered a callback valid for the process.
            unsafe { cb(sev, msg.as_ptr(), s.user_data as *mut c_void) };
        }
    }
    fn flush(&self) {}
}

/// Installs (or with a NULL callback removes) the sink. Returns false when another `log`
/// logger already owns the process (a Rust host): the SDK's messages go there instead.
pub(crate) fn install(callback: HrtLogCallback, min: HrtLogSeverity, user_data: *mut c_void) -> bool {
    *SINK.write() = callback.map(|_| Sink { callback, min, user_data: user_data as usize });
    static INSTALLED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *INSTALLED.get_or_init(|| log::set_logger(&BRIDGE).is_ok());
    if ok {
        log::set_max_level(log::LevelFilter::Debug);
    }
    ok
}
