//! Debug visualisations (`DebugOutput`): primary rays from the task's camera through the TLAS,
//! shaded by what they hit (cache colour, random sample/mesh colour, distance, barycentrics).
use super::constants::TraceCommonGpu;
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders, Writes};
use super::Recording;
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
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

/// Upload-ring bytes of one visualisation (a trace task's own constants are larger).
pub(crate) const UPLOAD_BYTES: u64 = std::mem::size_of::<DebugConstantsGpu>() as u64;

pub(crate) struct DebugPass {
    program: RtProgram,
}

impl DebugPass {
    /// Every pass is made with the G-buffer sampler (see `Passes`); this one samples nothing.
    pub fn new(b: &mut PipelineBuilder<'_>, _sampler: vk::Sampler) -> Result<DebugPass> {
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            Shaders::hit_record(shaders::DEBUG_RGEN),
        )?;
        Ok(DebugPass { program })
    }

    /// Records the visualisation `common.debug_output` into `output`.
    pub fn record(&self, r: &mut Recording<'_>, common: &TraceCommon, output: &ImageInput) {
        let table = r.instance_table;
        let constants = DebugConstantsGpu {
            // Debug rays see every instance.
            common: TraceCommonGpu::new(common, r.seed, InstanceInclusionMask::ALL.bits()),
            mode: [common.debug_output as u32, common.enable_bilinear_sampling as u32, table as u32, (table >> 32) as u32],
        };
        debug_assert!(common.debug_output != DebugOutput::Default);
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let vp = &common.viewport;
        let slots = [Slot::Tlas(r.tlas), Slot::Storage(output), Slot::Uniform(ubo)];
        self.program.run(r, &slots, vp.width, vp.height, Writes::Storage);
    }
}
