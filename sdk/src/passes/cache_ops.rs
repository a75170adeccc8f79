//! Whole-range cache operations as compute passes with push constants only (the data is
//! reached by device address): fill a range with a colour (new and cleared caches), and
//! resolve accumulated injections into the running average.
use super::Recording;
use crate::error::Result;
use crate::gpu::pipeline::PipelineBuilder;
use crate::gpu::sync;
use crate::shaders;
use ash::vk;
use bytemuck::{Pod, Zeroable};

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct FillPush {
    samples: u64,
    count: u32,
    pad: u32,
    color: [f32; 4],
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ResolvePush {
    samples: u64,
    count: u32,
    average_window: f32,
}

pub(crate) struct CacheOps {
    layout: vk::PipelineLayout,
    fill: vk::Pipeline,
    resolve: vk::Pipeline,
}

const GROUP: u64 = 256;

impl CacheOps {
    pub fn new(b: &mut PipelineBuilder<'_>) -> Result<CacheOps> {
        let layout = b.layout(None, 32, vk::ShaderStageFlags::COMPUTE)?;
        let fill = b.compute(layout, shaders::CACHE_FILL_COMP)?;
        let resolve = b.compute(layout, shaders::CACHE_RESOLVE_COMP)?;
        Ok(CacheOps { layout, fill, resolve })
    }

    fn dispatch(&self, r: &mut Recording<'_>, pipeline: vk::Pipeline, push: &[u8], count: u64) {
        let d = &r.device.raw;
        unsafe {
            d.cmd_bind_pipeline(r.cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            d.cmd_push_constants(r.cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            // Large ranges: the x dimension is enough up to 16M groups (4G samples).
            d.cmd_dispatch(r.cmd, count.div_ceil(GROUP) as u32, 1, 1);
        }
    }

    /// Sets `count` samples at `address` to `color` with no history.
    pub fn fill(&self, r: &mut Recording<'_>, address: u64, count: u64, color: [f32; 3]) {
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        r.hazards.write(&r.device.raw, r.cmd, sync::shader_write(stage));
        let push = FillPush { samples: address, count: count as u32, pad: 0, color: [color[0], color[1], color[2], 0.0] };
        self.dispatch(r, self.fill, bytemuck::bytes_of(&push), count);
    }

    /// Folds accumulated injections of `count` samples at `address` into their averages.
    pub fn resolve(&self, r: &mut Recording<'_>, address: u64, count: u64, average_window: f32) {
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        let push = ResolvePush { samples: address, count: count as u32, average_window };
        self.dispatch(r, self.resolve, bytemuck::bytes_of(&push), count);
    }
}
