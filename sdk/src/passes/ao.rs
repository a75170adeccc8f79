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
use super::Recording;
use crate::api::tasks::{InstanceInclusionMask, TraceAmbientOcclusionTask};
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::{self, Binding, RtPipeline};
use crate::gpu::sync;
use crate::shaders;
use ash::vk;

pub(crate) struct AoPass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    rt: RtPipeline,
    /// Same raygen, empty hit and miss shaders: the bench's bare-ray floor.
    floor: RtPipeline,
    /// Compute + ray query variant, when the device has ray queries.
    inline: Option<vk::Pipeline>,
}

impl AoPass {
    pub fn new(device: &Device, memory: &Memory, sampler: vk::Sampler) -> Result<AoPass> {
        let d = &device.raw;
        let stages = vk::ShaderStageFlags::RAYGEN_KHR | vk::ShaderStageFlags::COMPUTE;
        let set_layout = pipeline::push_set_layout(
            d,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            stages,
        )?;
        let layout = pipeline::pipeline_layout(d, set_layout)?;
        let rt = pipeline::rt_pipeline(device, memory, layout, shaders::AO_RGEN, &[shaders::HIT_T_RMISS], &[shaders::HIT_T_RCHIT], None)?;
        let floor =
            pipeline::rt_pipeline(device, memory, layout, shaders::AO_RGEN, &[shaders::EMPTY_RMISS], &[shaders::EMPTY_RCHIT], None)?;
        let inline = if device.ray_query { Some(pipeline::compute_pipeline(d, layout, shaders::AO_COMP)?) } else { None };
        Ok(AoPass { set_layout, layout, rt, floor, inline })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceAmbientOcclusionTask, inline: bool, floor: bool) {
        let constants = AoConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::AMBIENT_OCCLUSION.0),
            params: [task.ray_length, task.falloff_power, 0.0, 0.0],
            counts: [task.rays_per_pixel, 0, 0, 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);

        let inline_pipeline = self.inline.filter(|_| inline && !floor);
        let (bind_point, stage) = if inline_pipeline.is_some() {
            (vk::PipelineBindPoint::COMPUTE, vk::PipelineStageFlags2::COMPUTE_SHADER)
        } else {
            (vk::PipelineBindPoint::RAY_TRACING_KHR, vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR)
        };
        let d = &r.device.raw;
        r.hazards.read_write(d, r.cmd, sync::shader_read(stage), sync::shader_write(stage));

        let tlas = [r.tlas];
        let mut as_write = vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&tlas);
        let image = |i: &crate::api::tasks::ImageInput| {
            [vk::DescriptorImageInfo { sampler: vk::Sampler::null(), image_view: i.view, image_layout: i.layout }]
        };
        let depth = image(&task.common.depth.image);
        let normals = image(&task.common.normals.image);
        let out = image(&task.output);
        let buffer = [vk::DescriptorBufferInfo { buffer: ubo.buffer, offset: ubo.offset, range: ubo.size }];
        let mut writes = [
            vk::WriteDescriptorSet::default()
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                .descriptor_count(1)
                .push_next(&mut as_write),
            vk::WriteDescriptorSet::default()
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(&depth),
            vk::WriteDescriptorSet::default()
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(&normals),
            vk::WriteDescriptorSet::default()
                .dst_binding(3)
                .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                .image_info(&out),
            vk::WriteDescriptorSet::default()
                .dst_binding(4)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&buffer),
        ];
        writes[0].descriptor_count = 1;
        let vp = &task.common.viewport;
        // SAFETY: inputs validated at scheduling; the command buffer is recording.
        unsafe {
            match inline_pipeline {
                Some(p) => {
                    d.cmd_bind_pipeline(r.cmd, bind_point, p);
                    r.device.push.cmd_push_descriptor_set(r.cmd, bind_point, self.layout, 0, &writes);
                    d.cmd_dispatch(r.cmd, vp.width.div_ceil(8), vp.height.div_ceil(8), 1);
                }
                None => {
                    let p = if floor { &self.floor } else { &self.rt };
                    d.cmd_bind_pipeline(r.cmd, bind_point, p.pipeline);
                    r.device.push.cmd_push_descriptor_set(r.cmd, bind_point, self.layout, 0, &writes);
                    r.device.rt.cmd_trace_rays(r.cmd, &p.raygen, &p.miss, &p.hit, &p.callable, vp.width, vp.height, 1);
                }
            }
        }
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        let d = &device.raw;
        unsafe {
            for p in [self.rt, self.floor] {
                d.destroy_pipeline(p.pipeline, None);
                memory.destroy_buffer(p.sbt);
            }
            if let Some(p) = self.inline {
                d.destroy_pipeline(p, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Upload-ring bytes one AO task needs (its constants, aligned).
pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<AoConstantsGpu>() as u64;
