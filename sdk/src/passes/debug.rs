//! Debug visualisations (`DebugOutput`): primary rays from the task's camera through the TLAS,
//! shaded by what they hit (cache colour, random sample/mesh colour, distance, barycentrics).
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
use crate::types::{DebugOutput, ImageInput, InstanceInclusionMask, TraceCommon};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `DebugConstants` in shaders/debug.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct DebugConstantsGpu {
    pub common: TraceCommonGpu,
    pub mode: [u32; 4],
}

pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<DebugConstantsGpu>() as u64;

pub(crate) struct DebugPass {
    program: RtProgram,
}

impl DebugPass {
    pub fn new(device: &Device, memory: &Memory) -> Result<DebugPass> {
        let program = RtProgram::new(
            device,
            memory,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            vk::ShaderStageFlags::RAYGEN_KHR,
            Shaders {
                raygen: shaders::DEBUG_RGEN,
                misses: &[shaders::HIT_RECORD_RMISS],
                closest_hits: &[shaders::HIT_RECORD_RCHIT],
                any_hit: None,
                inline: None,
            },
        )?;
        Ok(DebugPass { program })
    }

    /// Records the visualisation `common.debug_output` into `output`.
    pub fn record(&self, r: &mut Recording<'_>, common: &TraceCommon, output: &ImageInput) {
        let table = r.instance_table;
        let constants = DebugConstantsGpu {
            // Debug rays see every instance.
            common: TraceCommonGpu::new(common, r.seed, InstanceInclusionMask::ALL.0),
            mode: [common.debug_output as u32, common.enable_bilinear_sampling as u32, table as u32, (table >> 32) as u32],
        };
        debug_assert!(common.debug_output != DebugOutput::Default);
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let stage = vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR;
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        let vp = &common.viewport;
        self.program.trace(r, &[Slot::Tlas(r.tlas), Slot::Storage(output), Slot::Uniform(ubo)], vp.width, vp.height);
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        self.program.destroy(device, memory);
    }
}
