//! The index check (shaders/index_check.comp): after a geometry's indices are copied, every
//! triangle with an index at or past the vertex count is made degenerate and counted, so an
//! engine's bad index never reaches a BLAS build (undefined behaviour, a driver crash) or a
//! shader's vertex fetch. Kickstart RT trusts the engine here; the count comes back with the
//! ticket (`ExecuteContext::geometry_invalid_triangles`).
use super::Recording;
use crate::error::Result;
use crate::gpu::pipeline::PipelineBuilder;
use crate::gpu::sync;
use crate::shaders;
use ash::vk;
use bytemuck::{Pod, Zeroable};

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct IndexCheckPush {
    indices: u64,
    counter: u64,
    triangle_count: u32,
    vertex_count: u32,
    index_size: u32,
    pad: u32,
}

const GROUP: u32 = 256;

pub(crate) struct IndexCheck {
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

/// One geometry copy to check.
pub(crate) struct IndexCheckJob {
    /// Device address of the copy's first index.
    pub indices: vk::DeviceAddress,
    /// Where the number of bad triangles is added (a zeroed u32).
    pub counter: vk::DeviceAddress,
    pub triangle_count: u32,
    pub vertex_count: u32,
    /// 2 or 4.
    pub index_size: u32,
}

impl IndexCheck {
    pub fn new(b: &mut PipelineBuilder<'_>) -> Result<IndexCheck> {
        let layout = b.layout(None, std::mem::size_of::<IndexCheckPush>() as u32, vk::ShaderStageFlags::COMPUTE)?;
        let pipeline = b.compute(layout, shaders::INDEX_CHECK_COMP)?;
        Ok(IndexCheck { layout, pipeline })
    }

    /// Checks every job's indices in place (after their copies; before builds and read-backs).
    pub fn record(&self, r: &mut Recording<'_>, jobs: &[IndexCheckJob]) {
        if jobs.is_empty() {
            return;
        }
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        r.hazards.read_write(&r.device.raw, r.cmd, sync::shader_read(stage), sync::shader_atomic(stage));
        let d = &r.device.raw;
        let max_groups = r.device.limits.max_dispatch_groups[0].max(1);
        unsafe { d.cmd_bind_pipeline(r.cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline) };
        for j in jobs {
            // Split so no dispatch exceeds the group-count limit.
            let per_dispatch = max_groups as u64 * GROUP as u64;
            let mut first = 0u64;
            while first < j.triangle_count as u64 {
                let n = (j.triangle_count as u64 - first).min(per_dispatch) as u32;
                let push = IndexCheckPush {
                    indices: j.indices + first * 3 * j.index_size as u64,
                    counter: j.counter,
                    triangle_count: n,
                    vertex_count: j.vertex_count,
                    index_size: j.index_size,
                    pad: 0,
                };
                unsafe {
                    d.cmd_push_constants(r.cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, bytemuck::bytes_of(&push));
                    d.cmd_dispatch(r.cmd, n.div_ceil(GROUP), 1, 1);
                }
                first += n as u64;
            }
        }
    }
}
