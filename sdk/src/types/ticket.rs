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

/// Makes `TaskKind` from the task table (`crate::tasks`): the kinds around the render tasks,
/// then each render task's, with `ALL` and `name`.
macro_rules! task_kinds {
    (
        other_kinds { $( $(#[$om:meta])* $OKind:ident = $on:literal, $oname:literal; )* }
        support_passes { $( $sfield:ident: $SPass:ty = $slabel:literal; )* }
        render_tasks { $(
            $Variant:ident($Payload:ty) {
                pass: $field:ident: $Pass:ty = $label:literal $(, floor $prog:ident)?;
                kinds: [ $( $(#[$km:meta])* $Kind:ident = $n:literal, $kname:literal; )+ ]
                schedule: [ $( $(#[$sm:meta])* $sched:ident($STask:ty); )+ ]
            }
        )* }
    ) => {
        /// Which kind of work a timing covers. New tasks bring new kinds: match with a
        /// wildcard arm (or use `name`).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[repr(u32)]
        #[non_exhaustive]
        pub enum TaskKind {
            $( $(#[$om])* $OKind = $on, )*
            $( $( $(#[$km])* $Kind = $n, )+ )*
        }

        impl TaskKind {
            /// Every kind, the kinds around the render tasks first.
            pub const ALL: &'static [TaskKind] = &[$(TaskKind::$OKind,)* $($(TaskKind::$Kind,)+)*];

            /// The kind's name in snake case (`"ambient_occlusion"`): the C ABI's constant is
            /// `HRT_TASK_` and this in capitals.
            pub fn name(self) -> &'static str {
                match self {
                    $( TaskKind::$OKind => $oname, )*
                    $( $( TaskKind::$Kind => $kname, )+ )*
                }
            }
        }
    };
}
crate::tasks::task_table!(task_kinds);

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

/// The GPU time of one pass of a task (`InitSettings::time_passes`): the dispatches a task is
/// made of, each between timestamps of its own. A task's passes add up to a little less than
/// its [`TaskTiming`] (the barriers between them are not in any pass).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct PassTiming {
    /// The kind of the task the pass belongs to.
    pub kind: TaskKind,
    /// Position of that task in its container.
    pub task_index: u32,
    /// The pass's name, as the task's documentation lists its passes (`"temporal"`,
    /// `"blur_1"`, …).
    pub pass: &'static str,
    /// GPU time between the timestamps around the pass, in milliseconds.
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
    /// Per-pass GPU times of the tasks made of several passes (the denoisers), in recording
    /// order; empty unless `InitSettings::time_passes` is on. Nested in `timings`: do not add
    /// them to it.
    pub pass_timings: Vec<PassTiming>,
    /// The labels the container's tasks were given (`TaskContainer::set_task_label`), by
    /// task index, in ascending order.
    pub(crate) labels: Vec<(u32, String)>,
}

impl CompletedTask {
    /// Sum of the times of the tasks of `kind`.
    pub fn gpu_ms(&self, kind: TaskKind) -> f64 {
        self.timings.iter().filter(|t| t.kind == kind).map(|t| t.gpu_ms).sum()
    }

    /// Sum of the times of the passes named `pass` of the tasks of `kind`.
    pub fn pass_ms(&self, kind: TaskKind, pass: &str) -> f64 {
        self.pass_timings.iter().filter(|t| t.kind == kind && t.pass == pass).map(|t| t.gpu_ms).sum()
    }

    /// The label the timed task was given when it was scheduled
    /// (`TaskContainer::set_task_label`). `Bvh` carries the label of the container's first BVH
    /// task; the intervals nested in it (`BlasBuild`, `TlasBuild`) and `CacheUpdate`, which
    /// serves no one task, have none, so summing labelled timings counts each interval once.
    pub fn label(&self, timing: &TaskTiming) -> Option<&str> {
        if matches!(timing.kind, TaskKind::BlasBuild | TaskKind::TlasBuild | TaskKind::CacheUpdate) {
            return None;
        }
        let i = self.labels.binary_search_by_key(&timing.task_index, |(i, _)| *i).ok()?;
        Some(&self.labels[i].1)
    }
}

#[cfg(test)]
mod tests {
    use super::TaskKind;

    /// The table gives every kind one value and one name, and the values are dense: C code
    /// can index an array by kind.
    #[test]
    fn every_kind_has_its_own_value_and_name() {
        let mut values: Vec<u32> = TaskKind::ALL.iter().map(|k| *k as u32).collect();
        values.sort_unstable();
        assert_eq!(values, (0..TaskKind::ALL.len() as u32).collect::<Vec<_>>());
        let mut names: Vec<&str> = TaskKind::ALL.iter().map(|k| k.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), TaskKind::ALL.len());
        assert_eq!(TaskKind::DenoiseSpecularAndDiffuse.name(), "denoise_specular_and_diffuse");
        // The name is the variant's in snake case.
        for k in TaskKind::ALL {
            let snake: String = format!("{k:?}")
                .chars()
                .enumerate()
                .flat_map(|(i, c)| {
                    let sep = (c.is_ascii_uppercase() && i > 0).then_some('_');
                    sep.into_iter().chain(std::iter::once(c.to_ascii_lowercase()))
                })
                .collect();
            assert_eq!(k.name(), snake);
        }
    }
}
