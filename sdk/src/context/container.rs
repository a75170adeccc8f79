//! Task containers: where the engine schedules a frame's tasks, on any thread (one container per
//! thread; they are `Send`). Scheduling validates each task at once. A built container is
//! emptied and can be reused next frame; a container whose build failed keeps its tasks, so a
//! frame refused for lack of a working set can be built again later.
use super::validate;
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
    /// The frame the next build belongs to (see `set_frame_index`).
    pub(crate) frame_index: Option<u64>,
}

impl TaskContainer {
    fn shared(&self) -> Result<Arc<Shared>> {
        self.shared.upgrade().ok_or(crate::Error::ContextDestroyed)
    }

    /// Registers or updates a geometry (its data is checked against the buffers and device limits now).
    pub fn schedule_geometry(&mut self, task: &GeometryTask) -> Result<()> {
        let shared = self.shared()?;
        shared.check_geometry_alive(task.handle)?;
        validate::geometry_input(&shared.device, &task.input)?;
        self.tasks.push(Task::Geometry(task.clone()));
        Ok(())
    }

    /// Registers, updates or removes an instance (its transform must be finite and invertible).
    pub fn schedule_instance(&mut self, task: &InstanceTask) -> Result<()> {
        let shared = self.shared()?;
        shared.check_instance_alive(task.handle)?;
        if task.operation != InstanceOperation::Remove {
            shared.check_geometry_alive(task.input.geometry)?;
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

    /// Ambient occlusion from the G-buffer (see `TraceAmbientOcclusionTask`).
    pub fn schedule_ambient_occlusion(&mut self, task: &TraceAmbientOcclusionTask) -> Result<()> {
        let shared = self.shared()?;
        validate::ambient_occlusion(task, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::AmbientOcclusion(*task)));
        Ok(())
    }

    /// Shadows from one light (see `TraceShadowTask`).
    pub fn schedule_shadow(&mut self, task: &TraceShadowTask) -> Result<()> {
        let shared = self.shared()?;
        validate::shadow(task, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::Shadow(*task)));
        Ok(())
    }

    /// Shadows from several lights in one pass (see `TraceMultiShadowTask`).
    pub fn schedule_multi_shadow(&mut self, task: &TraceMultiShadowTask) -> Result<()> {
        let shared = self.shared()?;
        validate::multi_shadow(task, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::MultiShadow(task.clone())));
        Ok(())
    }

    /// Diffuse GI shaded from the cache (see `TraceDiffuseTask`).
    pub fn schedule_diffuse(&mut self, task: &TraceDiffuseTask) -> Result<()> {
        let shared = self.shared()?;
        validate::diffuse(task, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::Diffuse(*task)));
        Ok(())
    }

    /// Specular reflections shaded from the cache (see `TraceSpecularTask`).
    pub fn schedule_specular(&mut self, task: &TraceSpecularTask) -> Result<()> {
        let shared = self.shared()?;
        validate::specular(task, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::Specular(task.clone())));
        Ok(())
    }

    fn schedule_denoise(&mut self, job: DenoiseJob) -> Result<()> {
        let shared = self.shared()?;
        shared.check_denoising_context_alive(job.context)?;
        validate::denoise(&job, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::Denoise(Box::new(job))));
        Ok(())
    }

    /// Denoises a specular trace (see `DenoiseSpecularTask`).
    pub fn schedule_denoise_specular(&mut self, task: &DenoiseSpecularTask) -> Result<()> {
        self.schedule_denoise(task.into())
    }

    /// Denoises a diffuse GI trace (see `DenoiseDiffuseTask`).
    pub fn schedule_denoise_diffuse(&mut self, task: &DenoiseDiffuseTask) -> Result<()> {
        self.schedule_denoise(task.into())
    }

    /// Denoises specular and diffuse traces in one set of passes.
    pub fn schedule_denoise_specular_and_diffuse(&mut self, task: &DenoiseSpecularAndDiffuseTask) -> Result<()> {
        self.schedule_denoise(task.into())
    }

    /// Denoises an ambient-occlusion trace.
    pub fn schedule_denoise_diffuse_occlusion(&mut self, task: &DenoiseDiffuseOcclusionTask) -> Result<()> {
        self.schedule_denoise(task.into())
    }

    /// Denoises a single-light shadow trace.
    pub fn schedule_denoise_shadow(&mut self, task: &DenoiseShadowTask) -> Result<()> {
        self.schedule_denoise(task.into())
    }

    /// Denoises a multi-light shadow trace's packed output.
    pub fn schedule_denoise_multi_shadow(&mut self, task: &DenoiseMultiShadowTask) -> Result<()> {
        self.schedule_denoise(task.into())
    }

    /// Bakes a lit view into the direct-lighting caches (see `DirectLightingInjectionTask`).
    pub fn schedule_direct_lighting_injection(&mut self, task: &DirectLightingInjectionTask) -> Result<()> {
        let shared = self.shared()?;
        validate::injection(task, &shared.device.limits)?;
        self.tasks.push(Task::Render(RenderTask::DirectLightingInjection(*task)));
        Ok(())
    }

    /// Resets an instance's cache to its initial colour (before the container's render tasks).
    pub fn schedule_clear_cache(&mut self, task: &ClearCacheTask) -> Result<()> {
        self.shared()?.check_instance_alive(task.instance)?;
        self.tasks.push(Task::ClearCache(*task));
        Ok(())
    }

    /// Lights cache samples no camera has injected from the engine's lights (see
    /// `RelightCacheTask`).
    pub fn schedule_cache_relight(&mut self, task: &RelightCacheTask) -> Result<()> {
        self.shared()?;
        validate::relight(task)?;
        self.tasks.push(Task::Render(RenderTask::CacheRelight(task.clone())));
        Ok(())
    }

    /// Copies one instance's cached lighting onto another covering the same surface.
    pub fn schedule_direct_light_transfer(&mut self, task: &DirectLightTransferTask) -> Result<()> {
        let shared = self.shared()?;
        shared.check_instance_alive(task.source)?;
        shared.check_instance_alive(task.target)?;
        if task.source == task.target {
            return Err(crate::Error::invalid("DirectLightTransferTask", "source and target are the same instance"));
        }
        if !(task.max_distance.is_finite() && task.max_distance > 0.0) {
            return Err(crate::Error::invalid("DirectLightTransferTask.max_distance", "must be finite and > 0"));
        }
        self.tasks.push(Task::Render(RenderTask::DirectLightTransfer(*task)));
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

    /// Drops every scheduled task (and a frame index set for the next build).
    pub fn clear(&mut self) {
        self.tasks.clear();
        self.frame_index = None;
    }
}

impl std::fmt::Debug for TaskContainer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TaskContainer").field("tasks", &self.tasks.len()).finish()
    }
}

// Containers are filled on the engine's threads: keep them Send.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<TaskContainer>();
};
