//! Direct-lighting injection (see `DirectLightingInjectionTask`): a ray-tracing pass that adds
//! each lit pixel's radiance to the cache sample under it (float atomics), followed by the
//! cache resolve (passes::cache_ops) that applies the running average.
use super::constants::TraceCommonGpu;
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::shaders;
use crate::types::{DirectLightingInjectionTask, InstanceInclusionMask, TaskKind, TraceCommon};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `InjectConstants` in shaders/inject.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct InjectConstantsGpu {
    pub common: TraceCommonGpu,
    pub table: [u32; 4],
}

pub(crate) struct InjectPass {
    program: RtProgram,
}

impl InjectPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<InjectPass> {
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            Shaders::hit_record(shaders::INJECT_RGEN),
        )?;
        Ok(InjectPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &DirectLightingInjectionTask) {
        let common = TraceCommon { depth: task.depth, viewport: task.viewport, camera: task.camera, ..Default::default() };
        let table = r.instance_table;
        let constants = InjectConstantsGpu {
            common: TraceCommonGpu::new(&common, r.seed, InstanceInclusionMask::LIGHT_INJECTION.bits()),
            table: [table as u32, (table >> 32) as u32, 0, 0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let slots = [Slot::Tlas(r.tlas), Slot::Sampled(&task.depth.image), Slot::Sampled(&task.lit), Slot::Uniform(ubo)];
        self.program.run(r, &slots, task.viewport.width, task.viewport.height, Writes::Atomics);
    }
}

/// Injection, then the resolve of every cache page in use.
impl PassTask for DirectLightingInjectionTask {
    fn kind(&self) -> TaskKind {
        TaskKind::DirectLightingInjection
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<InjectConstantsGpu>() as u64
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        passes.inject.record(r, self);
        for (address, count) in world.cache_pool.spans() {
            passes.cache_ops.resolve(r, address, count, self.average_window);
        }
    }
}
