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
    /// Set by the first write error: the log stops there (a warning says so).
    failed: bool,
}

impl AllocationLog {
    pub fn new(out: Box<dyn Write + Send>) -> AllocationLog {
        let mut log = AllocationLog { out: BufWriter::new(out), start: Instant::now(), failed: false };
        log.write(format_args!("{HEADER}\n"));
        log
    }

    fn write(&mut self, line: std::fmt::Arguments<'_>) {
        if self.failed {
            return;
        }
        if let Err(e) = self.out.write_fmt(line) {
            log::warn!("resource allocation log: writing failed ({e}); logging stops");
            self.failed = true;
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

    /// Flushes and hands the writer back.
    pub fn finish(self) -> Box<dyn Write + Send> {
        match self.out.into_inner() {
            Ok(w) => w,
            Err(e) => {
                log::warn!("resource allocation log: the last lines were not written ({})", e.error());
                e.into_inner().into_parts().0
            }
        }
    }
}
