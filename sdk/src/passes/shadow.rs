//! Shadows from one light (`TraceShadowTask`): rays from the G-buffer surface towards random
//! points of the light's extent (shaders/shadow.rgen).
use super::constants::TraceCommonGpu;
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders};
use super::Recording;
use crate::api::tasks::{InstanceInclusionMask, LightType, TraceShadowTask};
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::Binding;
use crate::gpu::sync;
use crate::shaders;
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `ShadowConstants` in shaders/shadow.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ShadowConstantsGpu {
    common: TraceCommonGpu,
    position: [f32; 4],
    direction: [f32; 4],
    shape: [f32; 4],
    counts: [u32; 4],
}

pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<ShadowConstantsGpu>() as u64;

pub(crate) struct ShadowPass {
    program: RtProgram,
}

impl ShadowPass {
    pub fn new(device: &Device, memory: &Memory, sampler: vk::Sampler) -> Result<ShadowPass> {
        let program = RtProgram::new(
            device,
            memory,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            vk::ShaderStageFlags::RAYGEN_KHR | vk::ShaderStageFlags::COMPUTE,
            Shaders {
                raygen: shaders::SHADOW_RGEN,
                misses: &[shaders::HIT_RECORD_RMISS],
                closest_hits: &[shaders::HIT_RECORD_RCHIT],
                any_hit: None,
                inline: Some(shaders::SHADOW_COMP),
            },
        )?;
        Ok(ShadowPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, inline: bool, task: &TraceShadowTask) {
        let l = &task.light;
        let constants = ShadowConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::SHADOWS.0),
            position: [l.position.x, l.position.y, l.position.z, l.light_type as u32 as f32],
            direction: [l.direction.x, l.direction.y, l.direction.z, (l.angular_extent * 0.5).tan()],
            shape: [if l.light_type == LightType::Directional { 0.0 } else { l.radius }, 0.0, 0.0, 0.0],
            counts: [task.rays_per_pixel, 0, 0, 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let stage = self.program.stage(inline);
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        let slots = [
            Slot::Tlas(r.tlas),
            Slot::Sampled(&task.common.depth.image),
            Slot::Sampled(&task.common.normals.image),
            Slot::Storage(&task.output),
            Slot::Uniform(ubo),
        ];
        let vp = &task.common.viewport;
        self.program.run(r, &slots, vp.width, vp.height, inline);
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        self.program.destroy(device, memory);
    }
}
