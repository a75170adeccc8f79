//! Diffuse GI (`TraceDiffuseTask`): cosine-distributed rays shaded from the direct-lighting
//! cache (shaders/diffuse.rgen).
use super::constants::{EnvironmentGpu, TraceCommonGpu};
use super::descriptors::{optional_or, Slot};
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::shaders;
use crate::types::{ImageInput, InstanceInclusionMask, TaskKind, TraceCommon, TraceDiffuseTask};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `DiffuseConstants` in shaders/diffuse.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct DiffuseConstantsGpu {
    common: TraceCommonGpu,
    miss: [f32; 4],
    params: [u32; 4],
    brdf: [f32; 4],
    environment: EnvironmentGpu,
}

pub(crate) struct DiffusePass {
    pub program: RtProgram,
}

impl DiffusePass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<DiffusePass> {
        let sampled = || Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) };
        let program = RtProgram::new(
            b,
            // + roughness, direct lighting, environment
            &super::gbuffer_bindings(sampler, &[sampled(), sampled(), sampled()]),
            Shaders::hit_record_trace(shaders::DIFFUSE_RGEN, shaders::DIFFUSE_COMP),
        )?;
        Ok(DiffusePass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceDiffuseTask) {
        let table = r.instance_table;
        let m = task.miss_radiance;
        let constants = DiffuseConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::DIFFUSE_GI.bits()),
            miss: [m[0], m[1], m[2], task.ray_length],
            params: [task.rays_per_pixel, task.common.enable_bilinear_sampling as u32, table as u32, (table >> 32) as u32],
            brdf: [task.brdf as u32 as f32, 0.0, 0.0, 0.0],
            environment: EnvironmentGpu::new(&task.environment),
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let mut slots = super::gbuffer_slots(r.tlas, &task.common, &task.output, ubo);
        // Without a roughness image the normals stand in (not read then).
        slots.push(Slot::Sampled(optional_or(&task.common.roughness.image, &task.common.normals.image)));
        slots.push(Slot::Sampled(optional_or(&task.common.direct_lighting, &task.common.normals.image)));
        slots.push(Slot::Sampled(optional_or(&task.environment.image, &task.common.normals.image)));
        slots.push(super::input_mask_slot(&task.common));
        let vp = &task.common.viewport;
        self.program.run(r, &slots, vp.width, vp.height, Writes::Storage);
    }
}

impl PassTask for TraceDiffuseTask {
    fn kind(&self) -> TaskKind {
        TaskKind::Diffuse
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<DiffuseConstantsGpu>() as u64
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        Some(&self.common)
    }
    fn debug_target(&self) -> Option<&ImageInput> {
        Some(&self.output)
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, _: &mut World<'_>) {
        passes.diffuse.record(r, self);
    }
}
