//! Task containers: where the engine schedules a frame's tasks, on any thread (one container per
//! thread; they are `Send`). Scheduling validates each task at once. A built container is
//! emptied and can be reused next frame; a container whose build failed keeps its tasks, so a
//! frame refused for lack of a working set can be built again later.
use super::validate::{self, Check, ToPayload};
use super::Shared;
use crate::error::Result;
use crate::passes::RenderTask;
use crate::types::*;
use std::sync::{Arc, Weak};

/// A scheduled task. Scene tasks are applied before render tasks, whatever their order
/// (`context::record`); render tasks record in scheduled order.
// Render tasks are most of a frame's container: boxing them would allocate per task to save
// the padding of the few scene tasks.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub(crate) enum Task {
    Geometry(GeometryTask),
    Instance(InstanceTask),
    BvhBuild(BvhBuildTask),
    ClearCache(ClearCacheTask),
    Render(RenderTask),
}

/// Holds only a weak reference to its context: dropping the `ExecuteContext` frees the SDK's
/// GPU objects at once, whatever containers are still around (they then refuse to schedule
/// with `Error::ContextDestroyed`).
pub struct TaskContainer {
    pub(crate) shared: Weak<Shared>,
    pub(crate) tasks: Vec<Task>,
    /// Labels of scheduled tasks: (task index, label), in ascending index order.
    pub(crate) labels: Vec<(u32, String)>,
    /// The frame the next build belongs to (see `set_frame_index`).
    pub(crate) frame_index: Option<u64>,
}

/// The tasks scheduled (how many), their labels and the frame index.
impl std::fmt::Debug for TaskContainer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TaskContainer")
            .field("tasks", &self.tasks.len())
            .field("labels", &self.labels)
            .field("frame_index", &self.frame_index)
            .field("context_alive", &(self.shared.strong_count() > 0))
            .finish()
    }
}

impl TaskContainer {
    fn shared(&self) -> Result<Arc<Shared>> {
        self.shared.upgrade().ok_or(crate::Error::ContextDestroyed)
    }

    /// Registers or updates a geometry (its data is checked against the buffers and device limits now).
    ///
    /// # Safety
    /// Every buffer and image the task names (vertices, indices, UVs, colours, the albedo and
    /// alpha textures, extra components') is a live object of the context's device, and stays
    /// alive until the ticket of the build that records this task has come back: scheduling
    /// asks the driver for the buffers' sizes, and the build copies from them. (The SDK checks
    /// every value it can; it cannot tell a destroyed handle from a live one.)
    pub unsafe fn schedule_geometry(&mut self, task: &GeometryTask) -> Result<()> {
        let shared = self.shared()?;
        shared.check_geometry_alive(task.handle, "GeometryTask.handle")?;
        validate::geometry_input(&shared.device, &task.input)?;
        self.tasks.push(Task::Geometry(task.clone()));
        Ok(())
    }

    /// Registers, updates or removes an instance (its transform must be finite and invertible).
    pub fn schedule_instance(&mut self, task: &InstanceTask) -> Result<()> {
        let shared = self.shared()?;
        shared.check_instance_alive(task.handle, "InstanceTask.handle")?;
        if task.operation != InstanceOperation::Remove {
            shared.check_geometry_alive(task.input.geometry, "InstanceTask.input.geometry")?;
            validate::transform("InstanceInput.transform", &task.input.transform)?;
            if task.input.initial_tile_color.iter().any(|c| !c.is_finite()) {
                return Err(crate::Error::invalid("InstanceInput.initial_tile_color", "is not finite"));
            }
            if !task.input.albedo.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(crate::Error::invalid("InstanceInput.albedo", "each channel must be in 0..=1"));
            }
            if !task.input.emission.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(crate::Error::invalid("InstanceInput.emission", "each channel must be finite and >= 0"));
            }
        }
        self.tasks.push(Task::Instance(*task));
        Ok(())
    }

    /// Builds queued BLASes (throttled), refits, and the TLAS (see `BvhBuildTask`).
    pub fn schedule_bvh_build(&mut self, task: &BvhBuildTask) -> Result<()> {
        self.shared()?;
        self.tasks.push(Task::BvhBuild(*task));
        Ok(())
    }

    /// Resets an instance's cache to its initial colour (before the container's render tasks).
    pub fn schedule_clear_cache(&mut self, task: &ClearCacheTask) -> Result<()> {
        self.shared()?.check_instance_alive(task.instance, "ClearCacheTask.instance")?;
        self.tasks.push(Task::ClearCache(*task));
        Ok(())
    }

    /// Names the task scheduled last: its region in the command buffer (with debug utils on,
    /// as RenderDoc and Nsight show it) and its timings (`CompletedTask::label`) carry the
    /// label. A second label for the same task replaces the first. An empty container, or a
    /// label with a NUL character, is `Error::InvalidInput`.
    pub fn set_task_label(&mut self, label: &str) -> Result<()> {
        let Some(last) = self.tasks.len().checked_sub(1) else {
            return Err(crate::Error::invalid("set_task_label", "the container has no task to label"));
        };
        let index = u32::try_from(last).map_err(|_| crate::Error::invalid("set_task_label", "too many tasks"))?;
        // Vulkan's label and the C ABI's are NUL-terminated: a NUL inside would cut them.
        if label.contains('\0') {
            return Err(crate::Error::invalid("set_task_label label", "contains a NUL character"));
        }
        match self.labels.last_mut() {
            Some((i, l)) if *i == index => *l = label.to_owned(),
            _ => self.labels.push((index, label.to_owned())),
        }
        Ok(())
    }

    /// Checks a render task's payload (see `Check`) and queues it.
    fn schedule_render<P: Check>(&mut self, payload: P, wrap: fn(P) -> RenderTask) -> Result<()> {
        let shared = self.shared()?;
        payload.check(&shared)?;
        self.tasks.push(Task::Render(wrap(payload)));
        Ok(())
    }

    /// The engine's frame number for the next build of this container: it seeds every random
    /// sequence (ray directions, light samples) and picks the checkerboard half, so the same
    /// frame index with the same inputs gives the same image, and two containers built for one
    /// frame (BVH work on an async-compute queue, tracing on graphics) trace the same
    /// checkerboard half. Applies to the next successful build only; without it the ticket's
    /// serial is used (fresh samples every build).
    pub fn set_frame_index(&mut self, index: u64) {
        self.frame_index = Some(index);
    }

    /// Tasks scheduled and not yet built.
    pub fn len(&self) -> usize {
        self.tasks.len()
    }

    /// Whether no task is scheduled.
    pub fn is_empty(&self) -> bool {
        self.tasks.is_empty()
    }

    /// Drops every scheduled task (with its label, and a frame index set for the next build).
    pub fn clear(&mut self) {
        self.tasks.clear();
        self.labels.clear();
        self.frame_index = None;
    }
}

/// Makes the public `schedule_*` functions of the render tasks from the task table
/// (`crate::tasks`): each converts the task into its row's payload, checks it and queues it.
macro_rules! schedule_functions {
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
        impl TaskContainer {
            $( $(
                $(#[$sm])*
                pub fn $sched(&mut self, task: &$STask) -> Result<()> {
                    let payload: $Payload = task.to_payload();
                    self.schedule_render(payload, RenderTask::$Variant)
                }
            )+ )*
        }
    };
}
crate::tasks::task_table!(schedule_functions);

// Containers are filled on the engine's threads: keep them Send.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<TaskContainer>();
};
