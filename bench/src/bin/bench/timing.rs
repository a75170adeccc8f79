//! The medians every row is made of: frames of one kind, a trace beside its bare-ray floor, a
//! trace and its denoiser in the same frames; a frame whose recording is timed on the CPU; the
//! warm-up that lets GPU clocks settle first.
use crate::{sdk, Bench};
use hybrid_rt::{CompletedTask, TaskContainer, TaskKind};
use hybrid_rt_testkit::sdk_scene::run_frame;
use std::time::{Duration, Instant};

/// (pass name, median GPU ms) of a task's passes, in recording order.
pub type PassMedians = Vec<(&'static str, f64)>;

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

/// Runs `work` over and over for `duration`: GPU clocks ramp up over hundreds of milliseconds
/// of load, and single short frames with waits between them measured up to 2.8x slower on the
/// H100.
pub fn warm_up(duration: Duration, mut work: impl FnMut() -> Result<(), String>) -> Result<(), String> {
    let until = Instant::now() + duration;
    while Instant::now() < until {
        work()?;
    }
    Ok(())
}

impl Bench<'_> {
    /// Median GPU time of `kind` over the settings' frames (after 3 warm-up frames), each frame
    /// scheduled by `schedule`.
    pub fn time_frames(
        &mut self,
        kind: TaskKind,
        mut schedule: impl FnMut(&mut TaskContainer) -> Result<(), String>,
    ) -> Result<f64, String> {
        let mut times = Vec::new();
        for i in 0..self.settings.frames + 3 {
            schedule(&mut self.frame)?;
            let ms = run_frame(self.host, self.ctx, &mut self.frame)?.gpu_ms(kind);
            if i >= 3 {
                times.push(ms);
            }
        }
        Ok(median(times))
    }

    /// Median GPU times of `kind` with the real shaders and with the bare-ray floor (empty hit
    /// and miss shaders), alternating frame by frame after 4 warm-up frames.
    pub fn time_vs_floor(
        &mut self,
        kind: TaskKind,
        mut schedule: impl FnMut(&mut TaskContainer) -> Result<(), String>,
    ) -> Result<(f64, f64), String> {
        let mut times = [Vec::new(), Vec::new()];
        for i in 0..2 * self.settings.frames + 4 {
            let floor = i % 2 == 1;
            self.ctx.set_bench_floor_mode(floor).map_err(sdk)?;
            schedule(&mut self.frame)?;
            let ms = run_frame(self.host, self.ctx, &mut self.frame)?.gpu_ms(kind);
            if i >= 4 {
                times[floor as usize].push(ms);
            }
        }
        self.ctx.set_bench_floor_mode(false).map_err(sdk)?;
        let [t, f] = times;
        Ok((median(t), median(f)))
    }

    /// Median GPU times of two task kinds recorded in the same frames (a trace and its
    /// denoiser), and the median of each pass of the second (the context times passes), in
    /// recording order.
    pub fn time_pair(
        &mut self,
        kinds: [TaskKind; 2],
        mut schedule: impl FnMut(&mut TaskContainer) -> Result<(), String>,
    ) -> Result<([f64; 2], PassMedians), String> {
        let mut times = [Vec::new(), Vec::new()];
        let mut passes: Vec<(&'static str, Vec<f64>)> = Vec::new();
        for i in 0..self.settings.frames + 3 {
            schedule(&mut self.frame)?;
            let done = run_frame(self.host, self.ctx, &mut self.frame)?;
            if i < 3 {
                continue;
            }
            for k in 0..2 {
                times[k].push(done.gpu_ms(kinds[k]));
            }
            for p in done.pass_timings.iter().filter(|p| p.kind == kinds[1]) {
                match passes.iter_mut().find(|(name, _)| *name == p.pass) {
                    Some((_, v)) => v.push(p.gpu_ms),
                    None => passes.push((p.pass, vec![p.gpu_ms])),
                }
            }
        }
        let [a, b] = times;
        Ok(([median(a), median(b)], passes.into_iter().map(|(name, v)| (name, median(v))).collect()))
    }

    /// Records the scheduled frame into a fresh command buffer, submits it and waits: the
    /// completed ticket, and the microseconds `build_gpu_task` took on the CPU (recording
    /// only; no submission or wait is inside).
    pub fn recorded_frame(&mut self) -> Result<(CompletedTask, f64), String> {
        let host = self.host;
        let cmd = host.allocate_command_buffer()?;
        host.begin(cmd)?;
        let t = Instant::now();
        // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
        let ticket = unsafe { self.ctx.build_gpu_task(&mut self.frame, cmd) }.map_err(sdk)?;
        let cpu_us = t.elapsed().as_secs_f64() * 1e6;
        let fence = host.submit(cmd)?;
        host.wait(fence)?;
        Ok((self.ctx.mark_gpu_task_completed(ticket).map_err(sdk)?, cpu_us))
    }
}
