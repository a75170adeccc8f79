//! Progress of long headless runs: nothing for the first second (a quick run stays quiet), then
//! an indicatif bar on a terminal, or a line every few seconds when stderr is a log (CI), so a
//! two-core machine's minute-long render is never silent.
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How long a run goes before it shows progress.
const QUIET_FOR: Duration = Duration::from_secs(1);
/// Without a terminal: the interval between progress lines.
const LOG_EVERY: Duration = Duration::from_secs(5);

pub struct Progress {
    what: &'static str,
    total: u64,
    start: Instant,
    bar: Option<ProgressBar>,
    last_line: Option<Instant>,
    terminal: bool,
}

impl Progress {
    /// `what` names the work ("rendering"); `total` counts its steps.
    pub fn new(what: &'static str, total: u64) -> Progress {
        let terminal = std::io::stderr().is_terminal();
        Progress { what, total, start: Instant::now(), bar: None, last_line: None, terminal }
    }

    /// `done` of the steps are done.
    pub fn set(&mut self, done: u64) {
        let now = Instant::now();
        if now - self.start < QUIET_FOR || done >= self.total {
            if let Some(bar) = &self.bar {
                bar.set_position(done);
            }
            return;
        }
        if self.terminal {
            let bar = self.bar.get_or_insert_with(|| {
                let bar = ProgressBar::new(self.total);
                let style = ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} frames, {elapsed} (about {eta} left)")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> ");
                bar.set_style(style);
                bar.set_message(self.what);
                bar
            });
            bar.set_position(done);
        } else if self.last_line.is_none_or(|t| now - t >= LOG_EVERY) {
            self.last_line = Some(now);
            eprintln!("{}: {done}/{} frames, {:.0} s", self.what, self.total, (now - self.start).as_secs_f64());
        }
    }

    /// Clears the bar (the run's own output follows).
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}
