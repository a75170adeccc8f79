//! The allocation log (`ExecuteContext::begin_logging_resource_allocations`): one CSV line per
//! device-memory allocation and free the SDK makes, for finding what a level load or a
//! resolution change costs and when it is given back.
//!
//! Kickstart RT writes such a log to a file; here the engine hands any writer (a file, its own
//! log sink, a buffer a test reads), and gets it back at the end. Columns:
//!
//! `time_ms,event,kind,name,bytes,kind_live_bytes` — milliseconds since the log began,
//! `alloc` or `free`, the [`MemoryKind`] (the rows of `ResourceAllocations`), what the memory
//! holds ("BLAS", "denoiser history"), its bytes as allocated, and the bytes of that kind live
//! after the event.
use super::memory::MemoryKind;
use std::io::{BufWriter, Write};
use std::time::Instant;

/// The header line of the log.
pub(crate) const HEADER: &str = "time_ms,event,kind,name,bytes,kind_live_bytes";

pub(crate) struct AllocationLog {
    out: BufWriter<Box<dyn Write + Send>>,
    start: Instant,
    /// The first write error: the log stops there, and its end reports it.
    failed: Option<std::io::Error>,
}

impl AllocationLog {
    pub fn new(out: Box<dyn Write + Send>) -> AllocationLog {
        let mut log = AllocationLog { out: BufWriter::new(out), start: Instant::now(), failed: None };
        log.write(format_args!("{HEADER}\n"));
        log
    }

    fn write(&mut self, line: std::fmt::Arguments<'_>) {
        if self.failed.is_some() {
            return;
        }
        if let Err(e) = self.out.write_fmt(line) {
            log::warn!("resource allocation log: writing failed ({e}); logging stops");
            self.failed = Some(e);
        }
    }

    /// One event: `alloc` or `free` of `bytes` of `kind`, leaving `live` bytes of it.
    pub fn event(&mut self, event: &str, kind: MemoryKind, name: &str, bytes: u64, live: u64) {
        let ms = self.start.elapsed().as_secs_f64() * 1e3;
        // Names are the SDK's own labels; quoted all the same should one hold a comma.
        if name.contains([',', '"']) {
            let quoted = name.replace('"', "\"\"");
            self.write(format_args!("{ms:.3},{event},{kind:?},\"{quoted}\",{bytes},{live}\n"));
        } else {
            self.write(format_args!("{ms:.3},{event},{kind:?},{name},{bytes},{live}\n"));
        }
    }

    /// Flushes and hands the writer back, or the first write error.
    pub fn finish(self) -> std::io::Result<Box<dyn Write + Send>> {
        if let Some(e) = self.failed {
            return Err(e);
        }
        self.out.into_inner().map_err(|e| e.into_error())
    }
}
