//! Direct-lighting injection (see `DirectLightingInjectionTask`): a ray-tracing pass that adds
//! each lit pixel's radiance to the cache sample under it (float atomics), followed by the
//! cache resolve (passes::cache_ops) that applies the running average.
use super::constants::TraceCommonGpu;
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders};
use super::Recording;
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::Binding;
use crate::gpu::sync;
use crate::shaders;
use crate::types::{DirectLightingInjectionTask, InstanceInclusionMask, TraceCommon};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `InjectConstants` in shaders/inject.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct InjectConstantsGpu {
    pub common: TraceCommonGpu,
    pub table: [u32; 4],
}

pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<InjectConstantsGpu>() as u64;

pub(crate) struct InjectPass {
    program: RtProgram,
}

impl InjectPass {
    pub fn new(device: &Device, memory: &Memory, sampler: vk::Sampler) -> Result<InjectPass> {
        let program = RtProgram::new(
            device,
            memory,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            vk::ShaderStageFlags::RAYGEN_KHR,
            Shaders {
                raygen: shaders::INJECT_RGEN,
                misses: &[shaders::HIT_RECORD_RMISS],
                closest_hits: &[shaders::HIT_RECORD_RCHIT],
                any_hit: None,
                inline: None,
            },
        )?;
        Ok(InjectPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &DirectLightingInjectionTask) {
        let common = TraceCommon { depth: task.depth, viewport: task.viewport, camera: task.camera, ..Default::default() };
        let table = r.instance_table;
        let constants = InjectConstantsGpu {
            common: TraceCommonGpu::new(&common, r.seed, InstanceInclusionMask::LIGHT_INJECTION.0),
            table: [table as u32, (table >> 32) as u32, 0, 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let stage = vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR;
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_atomic(stage));
        let slots = [Slot::Tlas(r.tlas), Slot::Sampled(&task.depth.image), Slot::Sampled(&task.lit), Slot::Uniform(ubo)];
        self.program.trace(r, &slots, task.viewport.width, task.viewport.height);
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        self.program.destroy(device, memory);
    }
}
