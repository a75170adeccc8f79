//! Per-task GPU timing from timestamp queries: one pool per working set, intervals may nest
//! (the BVH interval holds the BLAS and TLAS intervals; a task's interval the intervals of its
//! passes, when passes are timed), read back when the ticket returns.
use super::commands::Commands;
use crate::error::{Error, Result};
use crate::types::{PassTiming, TaskKind, TaskTiming};
use ash::vk;

struct Interval {
    kind: TaskKind,
    task_index: u32,
    /// The pass of the task this interval covers (None: the whole task).
    pass: Option<&'static str>,
    begin: u32,
    end: Option<u32>,
}

pub(crate) struct Timer {
    pool: vk::QueryPool,
    slots: u32,
    next: u32,
    intervals: Vec<Interval>,
    /// False when the device cannot time compute work: every call is a no-op.
    enabled: bool,
    /// Whether `begin_pass` times anything (`InitSettings::time_passes`).
    time_passes: bool,
}

/// The most passes of one task that are timed when passes are (the longest denoiser has 8).
pub(crate) const PASSES_PER_TASK: u32 = 12;

/// An interval begun with `Timer::begin` (None when out of slots or timing is off).
#[derive(Clone, Copy)]
pub(crate) struct Span(Option<usize>);

impl Span {
    /// An interval that times nothing.
    pub const NONE: Span = Span(None);
}

impl Timer {
    /// A pool with two slots per timed task (and `PASSES_PER_TASK` times as many again when
    /// passes are timed), plus the BVH work's.
    pub fn new(device: &ash::Device, max_timed_tasks: u32, enabled: bool, time_passes: bool) -> Result<Timer> {
        let per_task = if time_passes { 2 + 2 * PASSES_PER_TASK } else { 2 };
        let slots = max_timed_tasks.saturating_mul(per_task).saturating_add(4);
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(slots);
        // SAFETY: valid create info; destroyed in `destroy`.
        let pool = unsafe { device.create_query_pool(&info, None) }.map_err(Error::vk("vkCreateQueryPool"))?;
        Ok(Timer { pool, slots, next: 0, intervals: Vec::new(), enabled, time_passes })
    }

    /// Starts a recording: every slot is reset in the command buffer itself.
    pub fn reset(&mut self, cmd: &Commands) {
        self.next = 0;
        self.intervals.clear();
        if self.enabled {
            cmd.reset_query_pool(self.pool, 0, self.slots);
        }
    }

    fn write(&mut self, cmd: &Commands) -> u32 {
        let slot = self.next;
        cmd.write_timestamp(self.pool, slot);
        self.next += 1;
        slot
    }

    pub fn begin(&mut self, cmd: &Commands, kind: TaskKind, task_index: u32) -> Span {
        self.open(cmd, kind, task_index, None)
    }

    /// Opens the interval of one pass of a task (a no-op unless passes are timed).
    pub fn begin_pass(&mut self, cmd: &Commands, kind: TaskKind, task_index: u32, pass: &'static str) -> Span {
        if !self.time_passes {
            return Span(None);
        }
        self.open(cmd, kind, task_index, Some(pass))
    }

    fn open(&mut self, cmd: &Commands, kind: TaskKind, task_index: u32, pass: Option<&'static str>) -> Span {
        // Keep a slot free for the end of every open interval.
        let open = self.intervals.iter().filter(|i| i.end.is_none()).count() as u32;
        if !self.enabled || self.next + open + 2 > self.slots {
            return Span(None);
        }
        let begin = self.write(cmd);
        self.intervals.push(Interval { kind, task_index, pass, begin, end: None });
        Span(Some(self.intervals.len() - 1))
    }

    pub fn end(&mut self, cmd: &Commands, span: Span) {
        if let Some(i) = span.0 {
            let slot = self.write(cmd);
            self.intervals[i].end = Some(slot);
        }
    }

    /// Reads the intervals of a completed ticket: the tasks' and their passes'.
    pub fn read(
        &self,
        device: &ash::Device,
        period_ns: f64,
    ) -> std::result::Result<(Vec<TaskTiming>, Vec<PassTiming>), vk::Result> {
        let (mut tasks, mut passes) = (Vec::new(), Vec::new());
        if self.next == 0 {
            return Ok((tasks, passes));
        }
        let mut stamps = vec![0u64; self.next as usize];
        // SAFETY: called on a completed ticket: its queries were written.
        unsafe { device.get_query_pool_results(self.pool, 0, &mut stamps, vk::QueryResultFlags::TYPE_64) }?;
        for i in &self.intervals {
            let Some(end) = i.end else { continue };
            let ticks = stamps[end as usize].saturating_sub(stamps[i.begin as usize]);
            let gpu_ms = ticks as f64 * period_ns * 1e-6;
            match i.pass {
                None => tasks.push(TaskTiming { kind: i.kind, task_index: i.task_index, gpu_ms }),
                Some(pass) => passes.push(PassTiming { kind: i.kind, task_index: i.task_index, pass, gpu_ms }),
            }
        }
        Ok((tasks, passes))
    }

    pub fn destroy(&self, device: &ash::Device) {
        // SAFETY: the owning working set is idle; destroyed once.
        unsafe { device.destroy_query_pool(self.pool, None) };
    }
}
