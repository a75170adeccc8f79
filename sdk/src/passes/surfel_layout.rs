//! Surfel layouts built on the GPU, for the tiles layout: each triangle's resolution from its
//! edges in the SDK's own copy, a two-level prefix sum of the samples, and the layout words —
//! so registering a geometry copies only its sample count (8 bytes) to the host, not the whole
//! geometry (the CPU builder in `cache::layout` read back ~19 MB for a 1M-triangle mesh: ~6 ms
//! of the frame that registers it). Mesh colors (edge samples shared between triangles) are
//! still built on the CPU from a read-back.
use super::Recording;
use crate::error::Result;
use crate::gpu::pipeline::PipelineBuilder;
use crate::gpu::sync;
use crate::shaders;
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// Elements one scan workgroup covers (`scan_block.comp`).
const SCAN_BLOCK: u64 = 512;
const GROUP: u64 = 256;

/// One tiles layout to build: the copy's positions and indices, the settings, and where the
/// words, the scratch (`scratch_words`) and the (samples, largest R) result go.
pub(crate) struct TilesJob {
    pub positions: u64,
    pub indices: u64,
    pub triangles: u32,
    pub unit: f32,
    pub limit: u32,
    pub words: u64,
    pub scratch: u64,
    pub result: vk::Buffer,
    pub result_address: u64,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct TilesPush {
    positions: u64,
    indices: u64,
    words: u64,
    counts: u64,
    result: u64,
    triangles: u32,
    unit: f32,
    limit: u32,
    pad: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ScanPush {
    data: u64,
    sums: u64,
    count: u32,
    pad: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct FinishPush {
    words: u64,
    counts: u64,
    result: u64,
    triangles: u32,
    pad: u32,
}

pub(crate) struct SurfelLayoutPass {
    layout: vk::PipelineLayout,
    tiles: vk::Pipeline,
    scan_block: vk::Pipeline,
    scan_add: vk::Pipeline,
    finish: vk::Pipeline,
}

/// u32 words of scratch a layout of `triangles` needs: the counts and every level's sums.
pub(crate) fn scratch_words(triangles: u64) -> u64 {
    let (mut n, mut total) = (triangles, triangles);
    while n > 1 {
        n = n.div_ceil(SCAN_BLOCK);
        total += n;
    }
    total + 1
}

/// Largest triangle count the passes take in one dispatch each (past it, the CPU builds it).
pub(crate) fn max_triangles(max_groups: u32) -> u64 {
    max_groups as u64 * GROUP
}

impl SurfelLayoutPass {
    pub fn new(b: &mut PipelineBuilder<'_>) -> Result<SurfelLayoutPass> {
        let layout = b.layout(None, std::mem::size_of::<TilesPush>() as u32, vk::ShaderStageFlags::COMPUTE)?;
        Ok(SurfelLayoutPass {
            layout,
            tiles: b.compute(layout, shaders::LAYOUT_TILES_COMP)?,
            scan_block: b.compute(layout, shaders::SCAN_BLOCK_COMP)?,
            scan_add: b.compute(layout, shaders::SCAN_ADD_COMP)?,
            finish: b.compute(layout, shaders::LAYOUT_TILES_FINISH_COMP)?,
        })
    }

    fn run(&self, r: &mut Recording<'_>, pipeline: vk::Pipeline, push: &[u8], groups: u64) {
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let d = &r.device.raw;
        r.hazards.read_write(d, r.cmd, sync::shader_read(stage), sync::shader_write(stage));
        // SAFETY: the layout has a push range of this size; the command buffer is recording.
        unsafe {
            d.cmd_bind_pipeline(r.cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            d.cmd_push_constants(r.cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            d.cmd_dispatch(r.cmd, groups.max(1) as u32, 1, 1);
        }
    }

    /// Exclusive prefix sum of `count` u32s at `data`, block sums from `sums` on.
    fn scan(&self, r: &mut Recording<'_>, data: u64, count: u64, sums: u64) {
        let groups = count.div_ceil(SCAN_BLOCK);
        let push = ScanPush { data, sums, count: count as u32, pad: 0 };
        self.run(r, self.scan_block, bytemuck::bytes_of(&push), groups);
        if groups > 1 {
            self.scan(r, sums, groups, sums + groups * 4);
            self.run(r, self.scan_add, bytemuck::bytes_of(&push), count.div_ceil(GROUP));
        }
    }

    /// Records the three passes of one tiles layout (the result is zeroed first).
    pub fn record_tiles(&self, r: &mut Recording<'_>, job: &TilesJob) {
        let d = &r.device.raw;
        r.hazards.write(d, r.cmd, sync::TRANSFER_WRITE);
        // SAFETY: the result buffer holds 16 bytes.
        unsafe { d.cmd_fill_buffer(r.cmd, job.result, 0, 16, 0) };
        let t = job.triangles as u64;
        let counts = job.scratch;
        let tiles = TilesPush {
            positions: job.positions,
            indices: job.indices,
            words: job.words,
            counts,
            result: job.result_address,
            triangles: job.triangles,
            unit: job.unit,
            limit: job.limit,
            pad: 0,
        };
        self.run(r, self.tiles, bytemuck::bytes_of(&tiles), t.div_ceil(GROUP));
        self.scan(r, counts, t, counts + t * 4);
        let finish = FinishPush { words: job.words, counts, result: job.result_address, triangles: job.triangles, pad: 0 };
        self.run(r, self.finish, bytemuck::bytes_of(&finish), t.div_ceil(GROUP));
    }
}
