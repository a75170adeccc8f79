//! One module per GPU pass. A pass owns its pipelines (made in its module's `new`, owned by
//! [`Passes`]' arena) and records itself: it declares what it reads and writes to the hazard
//! tracker (which emits the barriers) and never reaches into another pass.
//!
//! Each render task kind has one description, [`PassTask`], implemented beside its pass: the
//! kind its time is reported as, the upload bytes it needs, and how it records. The recorder
//! (`context::render`) only walks [`RenderTask`]s; adding a task kind is a variant in
//! `RenderTask` plus a `PassTask` impl, and no `match` in the recorder.
pub(crate) mod ao;
pub(crate) mod cache_ops;
pub(crate) mod constants;
pub(crate) mod debug;
pub(crate) mod denoise;
pub(crate) mod descriptors;
pub(crate) mod diffuse;
pub(crate) mod geometry_pack;
pub(crate) mod inject;
pub(crate) mod program;
pub(crate) mod relight;
pub(crate) mod shadow;
pub(crate) mod specular;
pub(crate) mod surfel_layout;
pub(crate) mod transfer;

use crate::cache::pool::CachePool;
use crate::error::{Error, Result};
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::{Binding, PipelineArena, PipelineBuilder};
use crate::gpu::sync::Hazards;
use crate::gpu::upload::{Upload, UploadRing};
use crate::scene::Scene;
use crate::types::handles::Registry;
use crate::types::*;
use ash::vk;

/// What a pass needs while it records.
pub(crate) struct Recording<'a> {
    pub device: &'a Device,
    pub cmd: vk::CommandBuffer,
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
    /// The task asked for inline ray queries and the device has them (see `program`).
    pub inline: bool,
    /// Bench only: trace with the programs' floor pipelines (empty hit and miss shaders).
    pub floor: bool,
}

impl<'a> Recording<'a> {
    /// A recording for the compute passes of scene and cache maintenance (geometry packs,
    /// cache fills, surfel layouts): no TLAS, instance table or usage flags.
    pub fn maintenance(
        device: &'a Device,
        cmd: vk::CommandBuffer,
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
            inline: false,
            floor: false,
        }
    }
}

/// The SDK state some tasks read or advance while they record.
pub(crate) struct World<'a> {
    pub scene: &'a Scene,
    pub cache_pool: &'a CachePool,
    pub denoisers: &'a mut Registry<DenoisingContextHandle, denoise::DenoiserState>,
    /// The denoisers' shared intermediates.
    pub denoise_temps: &'a mut denoise::TempPool,
    pub limits: &'a crate::gpu::device::Limits,
    /// Where the cache relight walk goes on (`RelightCacheTask`).
    pub relight_cursor: &'a mut relight::RelightCursor,
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

/// Every render task kind: the tasks recorded in scheduled order after the BVH and cache work.
#[derive(Debug, Clone)]
pub(crate) enum RenderTask {
    AmbientOcclusion(TraceAmbientOcclusionTask),
    Shadow(TraceShadowTask),
    MultiShadow(TraceMultiShadowTask),
    Diffuse(TraceDiffuseTask),
    Specular(TraceSpecularTask),
    DirectLightingInjection(DirectLightingInjectionTask),
    DirectLightTransfer(DirectLightTransferTask),
    CacheRelight(RelightCacheTask),
    /// Boxed: a denoise task is several times larger than the others.
    Denoise(Box<DenoiseJob>),
}

impl RenderTask {
    pub fn describe(&self) -> &dyn PassTask {
        match self {
            RenderTask::AmbientOcclusion(t) => t,
            RenderTask::Shadow(t) => t,
            RenderTask::MultiShadow(t) => t,
            RenderTask::Diffuse(t) => t,
            RenderTask::Specular(t) => t,
            RenderTask::DirectLightingInjection(t) => t,
            RenderTask::DirectLightTransfer(t) => t,
            RenderTask::CacheRelight(t) => t,
            RenderTask::Denoise(t) => t.as_ref(),
        }
    }

    /// The debug visualisation this task records instead of itself, if it asks for one.
    fn debug_view(&self) -> Option<(&TraceCommon, &ImageInput)> {
        let t = self.describe();
        let common = t.trace_common().filter(|c| c.debug_output != DebugOutput::Default)?;
        Some((common, t.debug_target()?))
    }

    /// Upload-ring bytes its recording may push (itself or its debug view), before alignment.
    pub fn upload_bytes(&self) -> u64 {
        self.describe().upload_bytes().max(debug::UPLOAD_BYTES)
    }

    /// Records the task — or, for a trace task with a debug mode, the visualisation instead.
    pub fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        match self.debug_view() {
            Some((common, output)) => passes.debug.record(r, common, output),
            None => self.describe().record(r, passes, world),
        }
    }
}

/// Every pass, created together when the context is (an error leaves nothing behind), and the
/// arena that owns their pipelines.
pub(crate) struct Passes {
    pub ao: ao::AoPass,
    pub shadow: shadow::ShadowPass,
    pub multi_shadow: shadow::MultiShadowPass,
    pub diffuse: diffuse::DiffusePass,
    pub specular: specular::SpecularPass,
    pub debug: debug::DebugPass,
    pub inject: inject::InjectPass,
    pub transfer: transfer::TransferPass,
    pub relight: relight::RelightPass,
    pub cache_ops: cache_ops::CacheOps,
    pub denoise: denoise::DenoisePass,
    pub geometry_pack: geometry_pack::GeometryPack,
    pub surfel_layout: surfel_layout::SurfelLayoutPass,
    /// The one sampler of every sampled G-buffer binding (nearest, clamped: texel fetches).
    sampler: vk::Sampler,
    arena: PipelineArena,
    /// Bench only: trace through the floor pipelines (see `program`).
    pub floor: bool,
    /// The engine's pipeline cache, for pipelines made later (the bench floor).
    #[cfg_attr(not(feature = "bench-floor"), allow(dead_code))]
    cache: vk::PipelineCache,
}

impl Passes {
    pub fn new(device: &Device, memory: &Memory, cache: vk::PipelineCache) -> Result<Passes> {
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        // SAFETY: valid create info; destroyed in `destroy`.
        let sampler = unsafe { device.raw.create_sampler(&sampler_info, None) }.map_err(Error::vk("vkCreateSampler"))?;
        let mut arena = PipelineArena::default();
        device.name(sampler, "G-buffer sampler");
        match Self::make(&mut PipelineBuilder { device, memory, arena: &mut arena, cache, label: "" }, sampler) {
            Ok(passes) => Ok(Passes { arena, ..passes }),
            Err(e) => {
                arena.destroy(device, memory);
                unsafe { device.raw.destroy_sampler(sampler, None) };
                Err(e)
            }
        }
    }

    /// Makes every pass into the builder's arena (which `new` then moves into the result).
    fn make(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<Passes> {
        // Each pass's objects are named after it (debug utils).
        b.label = "ambient occlusion";
        let ao = ao::AoPass::new(b, sampler)?;
        b.label = "shadow";
        let shadow = shadow::ShadowPass::new(b, sampler)?;
        b.label = "multi-light shadow";
        let multi_shadow = shadow::MultiShadowPass::new(b, sampler)?;
        b.label = "diffuse GI";
        let diffuse = diffuse::DiffusePass::new(b, sampler)?;
        b.label = "specular";
        let specular = specular::SpecularPass::new(b, sampler)?;
        b.label = "debug view";
        let debug = debug::DebugPass::new(b)?;
        b.label = "injection";
        let inject = inject::InjectPass::new(b, sampler)?;
        b.label = "cache transfer";
        let transfer = transfer::TransferPass::new(b)?;
        b.label = "cache relight";
        let relight = relight::RelightPass::new(b)?;
        b.label = "cache fill/resolve";
        let cache_ops = cache_ops::CacheOps::new(b)?;
        b.label = "denoiser";
        let denoise = denoise::DenoisePass::new(b, sampler)?;
        b.label = "index check";
        let geometry_pack = geometry_pack::GeometryPack::new(b, sampler)?;
        b.label = "surfel layout";
        let surfel_layout = surfel_layout::SurfelLayoutPass::new(b)?;
        Ok(Passes {
            ao,
            shadow,
            multi_shadow,
            diffuse,
            specular,
            debug,
            inject,
            transfer,
            relight,
            cache_ops,
            denoise,
            geometry_pack,
            surfel_layout,
            sampler,
            arena: PipelineArena::default(),
            floor: false,
            cache: b.cache,
        })
    }

    /// Builds the bench's floor pipelines of every trace that has one (on first use).
    #[cfg(feature = "bench-floor")]
    pub fn ensure_floor(&mut self, device: &Device, memory: &Memory) -> Result<()> {
        let b = &mut PipelineBuilder { device, memory, arena: &mut self.arena, cache: self.cache, label: "bench floor" };
        for p in [
            &mut self.ao.program,
            &mut self.shadow.program,
            &mut self.multi_shadow.program,
            &mut self.diffuse.program,
            &mut self.specular.program,
        ] {
            p.ensure_floor(b)?;
        }
        Ok(())
    }

    /// Destroys every pass (no recording may still use them).
    pub fn destroy(&mut self, device: &Device, memory: &Memory) {
        self.arena.destroy(device, memory);
        unsafe { device.raw.destroy_sampler(self.sampler, None) };
        self.sampler = vk::Sampler::null();
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
