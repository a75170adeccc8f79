//! Cache transfer between two instances that cover the same surface (LOD switches): every
//! sample of the target takes the source's cached lighting where a ray along the sample's
//! normal meets the source (shaders/transfer.rgen). Kickstart RT traces two rays per source
//! primitive onto the destination; tracing from the destination's samples instead writes
//! every target sample exactly once per triangle, with no gaps where the target is finer.
use super::descriptors::{self, Slot};
use super::Recording;
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::{self, Binding, RtPipeline};
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
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    rt: RtPipeline,
}

impl TransferPass {
    pub fn new(device: &Device, memory: &Memory) -> Result<TransferPass> {
        let d = &device.raw;
        let set_layout = pipeline::push_set_layout(
            d,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            vk::ShaderStageFlags::RAYGEN_KHR,
        )?;
        let layout = pipeline::pipeline_layout(d, set_layout)?;
        let rt = pipeline::rt_pipeline(
            device,
            memory,
            layout,
            shaders::TRANSFER_RGEN,
            &[shaders::TRANSFER_RMISS],
            &[shaders::TRANSFER_RCHIT],
            Some(shaders::TRANSFER_RAHIT),
        )?;
        Ok(TransferPass { set_layout, layout, rt })
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
        let bind = vk::PipelineBindPoint::RAY_TRACING_KHR;
        unsafe { r.device.raw.cmd_bind_pipeline(r.cmd, bind, self.rt.pipeline) };
        descriptors::push(r.device, r.cmd, bind, self.layout, &[Slot::Tlas(r.tlas), Slot::Uniform(ubo)]);
        let p = &self.rt;
        unsafe {
            r.device.rt.cmd_trace_rays(r.cmd, &p.raygen, &p.miss, &p.hit, &p.callable, job.target_triangles, job.samples_per_triangle, 1)
        };
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        unsafe {
            device.raw.destroy_pipeline(self.rt.pipeline, None);
            device.raw.destroy_pipeline_layout(self.layout, None);
            device.raw.destroy_descriptor_set_layout(self.set_layout, None);
        }
        memory.destroy_buffer(self.rt.sbt);
    }
}
