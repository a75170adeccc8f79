//! What every pass builds on: the [`Recording`] it records into, the SDK state it may read or
//! advance ([`World`]), the description of a render task kind ([`PassTask`]), and the bindings
//! every G-buffer trace starts with.
use super::descriptors;
use super::Passes;
use crate::cache::pool::CachePool;
use crate::error::Result;
use crate::gpu::commands::Commands;
use crate::gpu::device::Device;
use crate::gpu::pipeline::Binding;
use crate::gpu::sync::Hazards;
use crate::gpu::timestamps::{Span, Timer};
use crate::gpu::upload::{Upload, UploadRing};
use crate::scene::Scene;
use crate::types::handles::Registry;
use crate::types::*;
use ash::vk;

/// What a pass needs while it records.
pub(crate) struct Recording<'a> {
    pub device: &'a Device,
    /// The build's command list (replayed into the engine's buffer once the build succeeds).
    pub cmd: &'a Commands,
    pub ring: &'a mut UploadRing,
    pub hazards: &'a mut Hazards,
    pub tlas: vk::AccelerationStructureKHR,
    /// The random seed (the container's frame index, else the ticket serial), so successive
    /// frames get fresh samples and a replayed frame the same ones.
    pub seed: u32,
    /// Device address of this recording's instance table (0 when the recording has none).
    pub instance_table: u64,
    /// Device address of the per-instance usage flags (0 without a cache budget).
    pub usage: u64,
    /// Device address of the blue-noise tile (0 unless a task asked for
    /// `RandomNumbers::BlueNoise`).
    pub blue_noise: u64,
    /// The task asked for inline ray queries and the device has them (see `program`).
    pub inline: bool,
    /// Bench only: trace with the programs' floor pipelines (empty hit and miss shaders).
    pub floor: bool,
    /// The working set's timer and the task being recorded, for the intervals of its passes
    /// (None in maintenance recordings, which have no task).
    pub task_timer: Option<(&'a mut Timer, TaskKind, u32)>,
}

impl<'a> Recording<'a> {
    /// A recording for the compute passes of scene and cache maintenance (geometry packs,
    /// cache fills, surfel layouts): no TLAS, instance table or usage flags.
    pub fn maintenance(
        device: &'a Device,
        cmd: &'a Commands,
        ring: &'a mut UploadRing,
        hazards: &'a mut Hazards,
        seed: u32,
    ) -> Recording<'a> {
        Recording {
            device,
            cmd,
            ring,
            hazards,
            tlas: vk::AccelerationStructureKHR::null(),
            seed,
            instance_table: 0,
            usage: 0,
            blue_noise: 0,
            inline: false,
            floor: false,
            task_timer: None,
        }
    }

    /// Opens one pass of the task: a debug-utils region named for it and, with
    /// `InitSettings::time_passes`, its timed interval (`CompletedTask::pass_timings`).
    pub fn begin_pass(&mut self, pass: &'static str) -> Span {
        self.device.begin_label(self.cmd, pass);
        match &mut self.task_timer {
            Some((timer, kind, index)) => timer.begin_pass(self.cmd, *kind, *index, pass),
            None => Span::NONE,
        }
    }

    /// Closes the pass `begin_pass` opened.
    pub fn end_pass(&mut self, span: Span) {
        if let Some((timer, ..)) = &mut self.task_timer {
            timer.end(self.cmd, span);
        }
        self.device.end_label(self.cmd);
    }
}

/// The SDK state some tasks read or advance while they record.
pub(crate) struct World<'a> {
    pub scene: &'a Scene,
    pub cache_pool: &'a CachePool,
    pub denoisers: &'a mut Registry<DenoisingContextHandle, super::denoise::DenoiserState>,
    pub many_lights: &'a mut Registry<ManyLightsContextHandle, super::many_lights::ManyLightsState>,
    /// The denoisers' shared intermediates.
    pub denoise_temps: &'a mut super::denoise::TempPool,
    /// The denoisers' guides, by view (or context).
    pub denoise_guides: &'a mut std::collections::HashMap<super::denoise_guide::GuideKey, super::denoise_guide::Guide>,
    /// While a build checks its tasks: the G-buffer inputs of each view's first denoise task,
    /// which the view's later tasks must match (`ViewInputs::check`).
    pub view_inputs: std::cell::RefCell<Vec<(u32, super::denoise_guide::ViewInputs)>>,
    /// The ticket serial of the recording (0 while a build checks its tasks).
    pub serial: u64,
    pub limits: &'a crate::gpu::device::Limits,
    /// Where the cache relight walk goes on (`RelightCacheTask`).
    pub relight_cursor: &'a mut super::relight::RelightCursor,
}

/// The one description of a render task kind (see the module doc).
pub(crate) trait PassTask {
    /// The kind its GPU time is reported under.
    fn kind(&self) -> TaskKind;
    /// Upload-ring bytes its recording pushes (constants), before alignment.
    fn upload_bytes(&self) -> u64;
    /// The G-buffer inputs of tasks that trace from it (`use_inline_rt`, debug views).
    fn trace_common(&self) -> Option<&TraceCommon> {
        None
    }
    /// The image a debug visualisation writes instead, for tasks with one colour output.
    fn debug_target(&self) -> Option<&ImageInput> {
        None
    }
    /// Checks at build what scheduling could not: handles still alive and fit for the task.
    fn check(&self, _world: &World<'_>) -> Result<()> {
        Ok(())
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>);
}

/// A boxed payload (the denoise jobs) describes itself as its contents do.
impl<T: PassTask + ?Sized> PassTask for Box<T> {
    fn kind(&self) -> TaskKind {
        (**self).kind()
    }
    fn upload_bytes(&self) -> u64 {
        (**self).upload_bytes()
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        (**self).trace_common()
    }
    fn debug_target(&self) -> Option<&ImageInput> {
        (**self).debug_target()
    }
    fn check(&self, world: &World<'_>) -> Result<()> {
        (**self).check(world)
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        (**self).record(r, passes, world)
    }
}

/// The bindings a G-buffer trace starts with: TLAS, depth, normals, output image, constants;
/// then the pass's own (`extra`), then the input mask (`input_mask_slot`) last.
pub(crate) fn gbuffer_bindings(sampler: vk::Sampler, extra: &[Binding]) -> Vec<Binding> {
    use vk::DescriptorType as T;
    let mut b = vec![
        Binding { ty: T::ACCELERATION_STRUCTURE_KHR, sampler: None },
        Binding { ty: T::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
        Binding { ty: T::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
        Binding { ty: T::STORAGE_IMAGE, sampler: None },
        Binding { ty: T::UNIFORM_BUFFER, sampler: None },
    ];
    b.extend(extra.iter().map(|x| Binding { ty: x.ty, sampler: x.sampler }));
    b.push(input_mask_binding(sampler));
    b
}

/// The input mask's binding: the last of every trace pass's set.
pub(crate) fn input_mask_binding(sampler: vk::Sampler) -> Binding {
    Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) }
}

/// The input mask's slot: the mask, or the normals standing in when there is none (the shader
/// is told by `TraceCommonGpu` not to read it then).
pub(crate) fn input_mask_slot(common: &TraceCommon) -> descriptors::Slot<'_> {
    descriptors::Slot::Sampled(descriptors::optional_or(&common.input_mask, &common.normals.image))
}

/// The first slots matching `gbuffer_bindings` (the pass pushes its own and the input mask's).
pub(crate) fn gbuffer_slots<'a>(
    tlas: vk::AccelerationStructureKHR,
    common: &'a TraceCommon,
    output: &'a ImageInput,
    constants: Upload,
) -> Vec<descriptors::Slot<'a>> {
    use descriptors::Slot;
    vec![
        Slot::Tlas(tlas),
        Slot::Sampled(&common.depth.image),
        Slot::Sampled(&common.normals.image),
        Slot::Storage(output),
        Slot::Uniform(constants),
    ]
}
