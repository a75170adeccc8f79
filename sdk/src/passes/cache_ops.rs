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
    /// Every pass is made with the G-buffer sampler (see `Passes`); this one samples nothing.
    pub fn new(b: &mut PipelineBuilder<'_>, _sampler: vk::Sampler) -> Result<CacheOps> {
        let layout = b.layout(None, 32, vk::ShaderStageFlags::COMPUTE)?;
        let fill = b.compute(layout, shaders::CACHE_FILL_COMP)?;
        let resolve = b.compute(layout, shaders::CACHE_RESOLVE_COMP)?;
        Ok(CacheOps { layout, fill, resolve })
    }

    /// Runs `pipeline` over `count` samples from `address`, in as many dispatches as the
    /// device's group-count limit needs (each with its part's address and count).
    fn dispatch(
        &self,
        r: &mut Recording<'_>,
        pipeline: vk::Pipeline,
        address: u64,
        count: u64,
        push: impl Fn(u64, u32) -> Vec<u8>,
    ) {
        let per_dispatch = r.device.limits.max_dispatch_groups[0].max(1) as u64 * GROUP;
        r.cmd.bind_pipeline(vk::PipelineBindPoint::COMPUTE, pipeline);
        let mut first = 0u64;
        while first < count {
            let n = (count - first).min(per_dispatch);
            let bytes = push(address + first * crate::cache::pool::SAMPLE_BYTES, n as u32);
            r.cmd.push_constants(self.layout, vk::ShaderStageFlags::COMPUTE, &bytes);
            r.cmd.dispatch(n.div_ceil(GROUP) as u32, 1, 1);
            first += n;
        }
    }

    /// Sets `count` samples at `address` to `color` with no history.
    pub fn fill(&self, r: &mut Recording<'_>, address: u64, count: u64, color: [f32; 3]) {
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        r.hazards.write(r.cmd, sync::shader_write(stage));
        let color = [color[0], color[1], color[2], 0.0];
        self.dispatch(r, self.fill, address, count, |samples, count| {
            bytemuck::bytes_of(&FillPush { samples, count, pad: 0, color }).to_vec()
        });
    }

    /// Folds accumulated injections of `count` samples at `address` into their averages.
    pub fn resolve(&self, r: &mut Recording<'_>, address: u64, count: u64, average_window: f32) {
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        r.hazards.read_write(r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        self.dispatch(r, self.resolve, address, count, |samples, count| {
            bytemuck::bytes_of(&ResolvePush { samples, count, average_window }).to_vec()
        });
    }
}
