//! Ambient occlusion.
//!
//! Kickstart RT's AO is a binary hit/miss average over uniformly sampled rays. Ours:
//! cosine-distributed rays (so the plain mean estimates the cosine-weighted visibility the
//! shading model wants, with lower variance than uniform sampling), a per-pixel rotated R2
//! low-discrepancy sequence (lower variance again at several rays per pixel), and
//! distance-weighted occlusion with a falloff power (hits count (t/L)^p, shared/seeds/003), so
//! far occluders fade in instead of popping at the ray's end. The same body
//! (shaders/include/ao.glsl) runs as a ray-tracing pipeline or as a compute shader with ray
//! queries; the only difference is the one function that traces a ray.
use super::constants::{AoConstantsGpu, TraceCommonGpu};
use super::descriptors;
use super::program::{RtProgram, Shaders};
use super::Recording;
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::{self, RtPipeline};
use crate::gpu::sync;
use crate::shaders;
use crate::types::{InstanceInclusionMask, TraceAmbientOcclusionTask};
use ash::vk;

pub(crate) struct AoPass {
    program: RtProgram,
    /// Same raygen, empty hit and miss shaders: the bench's bare-ray floor.
    floor: Option<RtPipeline>,
    /// Compute + ray query variant, when the device has ray queries.
    inline: Option<vk::Pipeline>,
}

impl AoPass {
    pub fn new(device: &Device, memory: &Memory, sampler: vk::Sampler) -> Result<AoPass> {
        let program = RtProgram::new(
            device,
            memory,
            &super::gbuffer_bindings(sampler, &[]),
            vk::ShaderStageFlags::RAYGEN_KHR | vk::ShaderStageFlags::COMPUTE,
            Shaders {
                raygen: shaders::AO_RGEN,
                misses: &[shaders::HIT_T_RMISS],
                closest_hits: &[shaders::HIT_T_RCHIT],
                any_hit: None,
                inline: None,
            },
        )?;
        let floor = program.variant(
            device,
            memory,
            Shaders {
                raygen: shaders::AO_RGEN,
                misses: &[shaders::EMPTY_RMISS],
                closest_hits: &[shaders::EMPTY_RCHIT],
                any_hit: None,
                inline: None,
            },
        )?;
        let inline = if device.ray_query {
            Some(pipeline::compute_pipeline(&device.raw, program.layout, shaders::AO_COMP)?)
        } else {
            None
        };
        Ok(AoPass { program, floor: Some(floor), inline })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceAmbientOcclusionTask, inline: bool, floor: bool) {
        let constants = AoConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::AMBIENT_OCCLUSION.0),
            params: [task.ray_length, task.falloff_power, 0.0, 0.0],
            counts: [task.rays_per_pixel, 0, 0, 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let inline_pipeline = self.inline.filter(|_| inline && !floor);
        let stage = if inline_pipeline.is_some() {
            vk::PipelineStageFlags2::COMPUTE_SHADER
        } else {
            vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR
        };
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        let slots = super::gbuffer_slots(r.tlas, &task.common, &task.output, ubo);
        let vp = &task.common.viewport;
        match (inline_pipeline, floor.then_some(self.floor.as_ref()).flatten()) {
            (Some(p), _) => {
                let bind = vk::PipelineBindPoint::COMPUTE;
                // SAFETY: inputs validated at scheduling; the command buffer is recording.
                unsafe { r.device.raw.cmd_bind_pipeline(r.cmd, bind, p) };
                descriptors::push(r.device, r.cmd, bind, self.program.layout, &slots);
                unsafe { r.device.raw.cmd_dispatch(r.cmd, vp.width.div_ceil(8), vp.height.div_ceil(8), 1) };
            }
            (None, Some(floor)) => self.program.trace_with(r, floor, &slots, vp.width, vp.height),
            (None, None) => self.program.trace(r, &slots, vp.width, vp.height),
        }
    }

    pub fn destroy(mut self, device: &Device, memory: &Memory) {
        if let Some(p) = self.floor.take() {
            RtProgram::destroy_pipeline(device, memory, p);
        }
        if let Some(p) = self.inline {
            unsafe { device.raw.destroy_pipeline(p, None) };
        }
        self.program.destroy(device, memory);
    }
}

/// Upload-ring bytes one AO task needs (its constants, aligned).
pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<AoConstantsGpu>() as u64;
