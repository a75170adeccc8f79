//! Shadows from one light (`TraceShadowTask`): rays from the G-buffer surface towards random
//! points of the light's extent (shaders/shadow.rgen).
use super::constants::{LightGpu, TraceCommonGpu};
use super::descriptors::{optional_or, Slot};
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::shaders;
use crate::types::{
    ImageInput, InstanceInclusionMask, TaskKind, TraceCommon, TraceMultiShadowTask, TraceShadowTask, MAX_LIGHT_OUTPUTS,
    MAX_SHADOW_LIGHTS,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `ShadowConstants` in shaders/include/shadow.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ShadowConstantsGpu {
    common: TraceCommonGpu,
    light: LightGpu,
    counts: [u32; 4],
}

pub(crate) struct ShadowPass {
    pub program: RtProgram,
}

impl ShadowPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<ShadowPass> {
        let program = RtProgram::new(
            b,
            &super::gbuffer_bindings(sampler, &[]),
            Shaders::hit_record_trace(shaders::SHADOW_RGEN, shaders::SHADOW_COMP),
        )?;
        Ok(ShadowPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceShadowTask) {
        let constants = ShadowConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::SHADOWS.bits()),
            light: LightGpu::new(&task.light),
            counts: [task.rays_per_pixel, task.first_hit as u32, task.max_ray_length.to_bits(), 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let mut slots = super::gbuffer_slots(r.tlas, &task.common, &task.output, ubo);
        slots.push(super::input_mask_slot(&task.common));
        let vp = &task.common.viewport;
        self.program.run(r, &slots, vp.width, vp.height, Writes::Storage);
    }
}

/// `MultiShadowConstants` in shaders/include/multi_shadow.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct MultiShadowConstantsGpu {
    common: TraceCommonGpu,
    counts: [u32; 4],
    outputs: [u32; 4],
    /// x: the task's max_ray_length.
    limits: [f32; 4],
    lights: [LightGpu; MAX_SHADOW_LIGHTS],
}

/// Shadows from several lights in one pass (`TraceMultiShadowTask`).
pub(crate) struct MultiShadowPass {
    pub program: RtProgram,
}

impl MultiShadowPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<MultiShadowPass> {
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
                super::input_mask_binding(sampler),
                // visibility_high, then the per-light outputs
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
            ],
            Shaders::hit_record_trace(shaders::MULTI_SHADOW_RGEN, shaders::MULTI_SHADOW_COMP),
        )?;
        Ok(MultiShadowPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceMultiShadowTask) {
        let mut lights = [LightGpu::default(); MAX_SHADOW_LIGHTS];
        for (g, l) in lights.iter_mut().zip(&task.lights) {
            *g = LightGpu::new(l);
        }
        let has_high = task.visibility_high.image != vk::Image::null();
        let mut outputs = [u32::MAX; MAX_LIGHT_OUTPUTS];
        for (o, l) in outputs.iter_mut().zip(&task.light_outputs) {
            *o = l.light;
        }
        let constants = MultiShadowConstantsGpu {
            common: TraceCommonGpu::new(&task.common, r.seed, InstanceInclusionMask::SHADOWS.bits()),
            counts: [task.rays_per_pixel, task.lights.len() as u32, task.first_hit as u32, has_high as u32],
            outputs,
            limits: [task.max_ray_length, 0.0, 0.0, 0.0],
            lights,
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let slots = [
            Slot::Tlas(r.tlas),
            Slot::Sampled(&task.common.depth.image),
            Slot::Sampled(&task.common.normals.image),
            Slot::Storage(&task.visibility),
            Slot::Storage(&task.packed),
            Slot::Uniform(ubo),
            super::input_mask_slot(&task.common),
            // Stand-ins where there is no such image (the shader does not write them then).
            Slot::Storage(optional_or(&task.visibility_high, &task.visibility)),
            Slot::Storage(task.light_outputs.first().map_or(&task.packed, |o| &o.output)),
            Slot::Storage(task.light_outputs.get(1).map_or(&task.packed, |o| &o.output)),
            Slot::Storage(task.light_outputs.get(2).map_or(&task.packed, |o| &o.output)),
            Slot::Storage(task.light_outputs.get(3).map_or(&task.packed, |o| &o.output)),
        ];
        let vp = &task.common.viewport;
        self.program.run(r, &slots, vp.width, vp.height, Writes::Storage);
    }
}

impl PassTask for TraceShadowTask {
    fn kind(&self) -> TaskKind {
        TaskKind::Shadow
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<ShadowConstantsGpu>() as u64
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        Some(&self.common)
    }
    fn debug_target(&self) -> Option<&ImageInput> {
        Some(&self.output)
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, _: &mut World<'_>) {
        passes.shadow.record(r, self);
    }
}

impl PassTask for TraceMultiShadowTask {
    fn kind(&self) -> TaskKind {
        TaskKind::MultiShadow
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<MultiShadowConstantsGpu>() as u64
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        Some(&self.common)
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, _: &mut World<'_>) {
        passes.multi_shadow.record(r, self);
    }
}
