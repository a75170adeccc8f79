//! Specular reflections (`TraceSpecularTask`): mirror or GGX-VNDF rays shaded from the cache,
//! or on smooth pixels from the engine's lights (hit lighting) (shaders/specular.rgen).
use super::constants::LightGpu;
use super::constants::{EnvironmentGpu, TraceCommonGpu};
use super::descriptors::{optional_or, Slot};
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::shaders;
use crate::types::{ImageInput, InstanceInclusionMask, TaskKind, TraceCommon, TraceSpecularTask, MAX_SHADOW_LIGHTS};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `SpecularConstants` in shaders/specular.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct SpecularConstantsGpu {
    common: TraceCommonGpu,
    params: [f32; 4],
    miss: [f32; 4],
    counts: [u32; 4],
    specular: [f32; 4],
    environment: EnvironmentGpu,
    hit_lighting: [u32; 4],
    hit_params: [f32; 4],
    lights: [LightGpu; MAX_SHADOW_LIGHTS],
}

pub(crate) struct SpecularPass {
    pub program: RtProgram,
}

impl SpecularPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<SpecularPass> {
        let sampled = || Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) };
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                sampled(),
                sampled(),
                sampled(),
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
                sampled(),
                sampled(),
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                super::input_mask_binding(sampler),
                sampled(),
            ],
            Shaders::hit_record_trace(shaders::SPECULAR_RGEN, shaders::SPECULAR_COMP),
        )?;
        Ok(SpecularPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &TraceSpecularTask) {
        let c = &task.common;
        let table = r.instance_table;
        let m = task.miss_radiance;
        let hit = &task.hit_lighting;
        let mut lights = [LightGpu::default(); MAX_SHADOW_LIGHTS];
        for (g, l) in lights.iter_mut().zip(&hit.lights) {
            *g = LightGpu::new(l);
        }
        let constants = SpecularConstantsGpu {
            common: TraceCommonGpu::new(c, r.seed, InstanceInclusionMask::REFLECTIONS.bits()),
            params: [task.ray_length, task.firefly_clamp, 0.0, 0.0],
            miss: [m[0], m[1], m[2], 0.0],
            counts: [task.rays_per_pixel, c.enable_bilinear_sampling as u32, table as u32, (table >> 32) as u32],
            specular: [
                c.specular.global_metalness,
                (c.specular.image.image != vk::Image::null()) as u32 as f32,
                (task.demodulated_output.image != vk::Image::null()) as u32 as f32,
                0.0,
            ],
            environment: EnvironmentGpu::new(&task.environment),
            hit_lighting: [
                hit.lights.len() as u32,
                InstanceInclusionMask::SHADOWS.bits() as u32,
                hit.gather_rays,
                InstanceInclusionMask::DIFFUSE_GI.bits() as u32,
            ],
            hit_params: [hit.max_roughness, hit.indirect as u32 as f32, 0.0, 0.0],
            lights,
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        // Without a roughness image the binding still needs a valid view: the normals stand in
        // (the shader does not read it then).
        let roughness = optional_or(&c.roughness.image, &c.normals.image);
        let slots = [
            Slot::Tlas(r.tlas),
            Slot::Sampled(&c.depth.image),
            Slot::Sampled(&c.normals.image),
            Slot::Sampled(roughness),
            Slot::Storage(&task.output),
            Slot::Uniform(ubo),
            Slot::Sampled(optional_or(&c.direct_lighting, &c.normals.image)),
            // Stand-ins where there is no specular image / demodulated output (not accessed).
            Slot::Sampled(optional_or(&c.specular.image, &c.normals.image)),
            Slot::Storage(optional_or(&task.demodulated_output, &task.output)),
            super::input_mask_slot(c),
            Slot::Sampled(optional_or(&task.environment.image, &c.normals.image)),
        ];
        self.program.run(r, &slots, c.viewport.width, c.viewport.height, Writes::Storage);
    }
}

impl PassTask for TraceSpecularTask {
    fn kind(&self) -> TaskKind {
        TaskKind::Specular
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<SpecularConstantsGpu>() as u64
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        Some(&self.common)
    }
    fn debug_target(&self) -> Option<&ImageInput> {
        Some(&self.output)
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, _: &mut World<'_>) {
        passes.specular.record(r, self);
    }
}
