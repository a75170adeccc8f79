//! Ambient occlusion.
//!
//! Kickstart RT's AO is a binary hit/miss average over uniformly sampled rays. Ours:
//! cosine-distributed rays (so the plain mean estimates the cosine-weighted visibility the
//! shading model wants, with lower variance than uniform sampling), a per-pixel rotated R2
//! low-discrepancy sequence (lower variance again at several rays per pixel), and
//! distance-weighted occlusion with a falloff power (hits count (t/L)^p), so
//! far occluders fade in instead of popping at the ray's end. The same body
//! (shaders/include/ao.glsl) runs as a ray-tracing pipeline or as a compute shader with ray
//! queries; the only difference is the one function that traces a ray.
use super::constants::{AoConstantsGpu, TraceCommonGpu};
use super::program::{Payload, RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::PipelineBuilder;
use crate::shaders;
use crate::types::{ImageInput, InstanceInclusionMask, TaskKind, TraceAmbientOcclusionTask, TraceCommon};
use ash::vk;

pub(crate) struct AoPass {
    pub program: RtProgram,
}

impl AoPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<AoPass> {
        let program = RtProgram::new(
            b,
            &super::gbuffer_bindings(sampler, &[]),
            Shaders {
                raygen: shaders::AO_RGEN,
                misses: &[shaders::HIT_T_RMISS],
                closest_hits: &[shaders::HIT_T_RCHIT],
                any_hit: Some(shaders::ALPHA_TEST_RAHIT),
                inline: Some(shaders::AO_COMP),
                floor: Some(Payload::HitT),
            },
        )?;
        Ok(AoPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceAmbientOcclusionTask) {
        let constants = AoConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::AMBIENT_OCCLUSION.bits()),
            params: [task.ray_length, task.falloff_power, 0.0, 0.0],
            counts: [task.rays_per_pixel, 0, 0, 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let mut slots = super::gbuffer_slots(r.tlas, &task.common, &task.output, ubo);
        slots.push(super::input_mask_slot(&task.common));
        let vp = &task.common.viewport;
        self.program.run(r, &slots, vp.width, vp.height, Writes::Storage);
    }
}

impl PassTask for TraceAmbientOcclusionTask {
    fn kind(&self) -> TaskKind {
        TaskKind::AmbientOcclusion
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<AoConstantsGpu>() as u64
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        Some(&self.common)
    }
    fn debug_target(&self) -> Option<&ImageInput> {
        Some(&self.output)
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, _: &mut World<'_>) {
        passes.ao.record(r, self);
    }
}
