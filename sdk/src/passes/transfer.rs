//! Cache transfer between two instances that cover the same surface (LOD switches): every
//! sample of the target takes the source's cached lighting where a ray along the sample's
//! normal meets the source (shaders/transfer.rgen). Kickstart RT traces two rays per source
//! primitive onto the destination; tracing from the destination's samples instead writes
//! every target sample exactly once per triangle, with no gaps where the target is finer.
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders};
use super::Recording;
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::Binding;
use crate::gpu::sync;
use crate::shaders;
use ash::vk;
use bytemuck::{Pod, Zeroable};

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct TransferConstantsGpu {
    table: [u32; 4],
    params: [f32; 4],
}

pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<TransferConstantsGpu>() as u64;

/// What one transfer needs to know about its two instances.
pub(crate) struct TransferJob {
    pub source_index: u32,
    pub target_index: u32,
    pub target_triangles: u32,
    /// Samples per target triangle at the largest resolution (the launch's y extent).
    pub samples_per_triangle: u32,
    pub distance: f32,
    pub bilinear: bool,
}

pub(crate) struct TransferPass {
    program: RtProgram,
}

impl TransferPass {
    pub fn new(device: &Device, memory: &Memory) -> Result<TransferPass> {
        let program = RtProgram::new(
            device,
            memory,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            vk::ShaderStageFlags::RAYGEN_KHR,
            Shaders {
                raygen: shaders::TRANSFER_RGEN,
                misses: &[shaders::TRANSFER_RMISS],
                closest_hits: &[shaders::TRANSFER_RCHIT],
                any_hit: Some(shaders::TRANSFER_RAHIT),
                inline: None,
            },
        )?;
        Ok(TransferPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, job: &TransferJob) {
        let t = r.instance_table;
        let constants = TransferConstantsGpu {
            table: [t as u32, (t >> 32) as u32, job.source_index, job.target_index],
            params: [job.distance, job.bilinear as u32 as f32, 0.0, 0.0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let stage = vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR;
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        self.program.trace(r, &[Slot::Tlas(r.tlas), Slot::Uniform(ubo)], job.target_triangles, job.samples_per_triangle);
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        self.program.destroy(device, memory);
    }
}
