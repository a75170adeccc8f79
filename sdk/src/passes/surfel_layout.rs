//! Surfel layouts built on the GPU from the SDK's own copy of a geometry, so registering it
//! copies only its sample count (16 bytes) to the host, not the whole geometry (the CPU
//! builder in `cache::layout` read back ~19 MB for a 1M-triangle mesh).
//!
//! Tiles: each triangle's resolution, a prefix sum of R x R, the words. Mesh colors (vertex
//! and edge samples shared between triangles): edges are counting-sorted by their lower vertex
//! (a count per vertex, a prefix sum, a fill), the entries of one vertex that share a higher
//! vertex are one edge (its first entry represents it; its resolution is the finest of its
//! triangles'), and prefix sums over the edges' R - 1 and the triangles' interiors place the
//! samples: vertices first (their own indices), then edges, then interiors — the layout the
//! CPU builder makes, numbered differently (and with a sample for every vertex of the buffer,
//! used or not).
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

/// One mesh-colors layout to build (`vertices`: the copy's vertex count).
pub(crate) struct MeshColorsJob {
    pub positions: u64,
    pub indices: u64,
    pub triangles: u32,
    pub vertices: u32,
    pub unit: f32,
    pub limit: u32,
    pub words: vk::Buffer,
    pub words_address: u64,
    pub scratch: vk::Buffer,
    pub scratch_address: u64,
    pub result: vk::Buffer,
    pub result_address: u64,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct McEdgesPush {
    positions: u64,
    indices: u64,
    res: u64,
    interior: u64,
    degree: u64,
    slot: u64,
    result: u64,
    triangles: u32,
    unit: f32,
    limit: u32,
    pad: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct McFillPush {
    indices: u64,
    start: u64,
    slot: u64,
    key: u64,
    edge: u64,
    lower: u64,
    edges: u32,
    pad: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct McDedupPush {
    start: u64,
    key: u64,
    edge: u64,
    lower: u64,
    res: u64,
    rep: u64,
    edge_res: u64,
    count: u64,
    edges: u32,
    vertices: u32,
}

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct McFinishPush {
    indices: u64,
    words: u64,
    edge: u64,
    rep: u64,
    edge_res: u64,
    edge_base: u64,
    res: u64,
    interior_base: u64,
    result: u64,
    edges: u32,
    vertices: u32,
    triangles: u32,
    mode: u32,
}

/// Where each array of a mesh-colors build lives in its scratch buffer (u32 words).
struct McScratch {
    res: u64,
    interior: u64,
    degree: u64,
    slot: u64,
    key: u64,
    edge: u64,
    lower: u64,
    rep: u64,
    edge_res: u64,
    count: u64,
    total: u64,
}

impl McScratch {
    fn new(triangles: u64, vertices: u64) -> McScratch {
        let edges = 3 * triangles;
        let mut at = 0u64;
        let mut take = |n: u64| {
            let here = at;
            at += n;
            here
        };
        let res = take(triangles);
        let interior = take(scratch_words(triangles));
        let degree = take(scratch_words(vertices));
        let (slot, key, edge, lower, rep, edge_res) =
            (take(edges), take(edges), take(edges), take(edges), take(edges), take(edges));
        let count = take(scratch_words(edges));
        McScratch { res, interior, degree, slot, key, edge, lower, rep, edge_res, count, total: at }
    }
}

/// u32 words of scratch a mesh-colors layout needs.
pub(crate) fn mesh_colors_scratch_words(triangles: u64, vertices: u64) -> u64 {
    McScratch::new(triangles, vertices).total
}

/// Largest triangle and vertex counts the mesh-colors passes take (3 entries per triangle in
/// one dispatch).
pub(crate) fn mesh_colors_fits(max_groups: u32, triangles: u64, vertices: u64) -> bool {
    let per_dispatch = max_groups as u64 * GROUP;
    triangles > 0 && 3 * triangles <= per_dispatch && vertices <= per_dispatch
}

/// The work of one layout: buffer ranges to zero, then dispatches in order.
pub(crate) struct Plan {
    fills: Vec<(vk::Buffer, u64, u64)>,
    dispatches: Vec<(vk::Pipeline, Vec<u8>, u32)>,
}

pub(crate) struct SurfelLayoutPass {
    layout: vk::PipelineLayout,
    tiles: vk::Pipeline,
    scan_block: vk::Pipeline,
    scan_add: vk::Pipeline,
    finish: vk::Pipeline,
    mc_edges: vk::Pipeline,
    mc_fill: vk::Pipeline,
    mc_dedup: vk::Pipeline,
    mc_finish: vk::Pipeline,
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
    /// Every pass is made with the G-buffer sampler (see `Passes`); this one samples nothing.
    pub fn new(b: &mut PipelineBuilder<'_>, _sampler: vk::Sampler) -> Result<SurfelLayoutPass> {
        // One layout for every pass: push constants as large as the largest pass's.
        use std::mem::size_of;
        let push = [
            size_of::<TilesPush>(),
            size_of::<ScanPush>(),
            size_of::<FinishPush>(),
            size_of::<McEdgesPush>(),
            size_of::<McFillPush>(),
            size_of::<McDedupPush>(),
            size_of::<McFinishPush>(),
        ]
        .into_iter()
        .max()
        .unwrap_or(0) as u32;
        let layout = b.layout(None, push, vk::ShaderStageFlags::COMPUTE)?;
        Ok(SurfelLayoutPass {
            layout,
            tiles: b.compute(layout, shaders::LAYOUT_TILES_COMP)?,
            scan_block: b.compute(layout, shaders::SCAN_BLOCK_COMP)?,
            scan_add: b.compute(layout, shaders::SCAN_ADD_COMP)?,
            finish: b.compute(layout, shaders::LAYOUT_TILES_FINISH_COMP)?,
            mc_edges: b.compute(layout, shaders::LAYOUT_MC_EDGES_COMP)?,
            mc_fill: b.compute(layout, shaders::LAYOUT_MC_FILL_COMP)?,
            mc_dedup: b.compute(layout, shaders::LAYOUT_MC_DEDUP_COMP)?,
            mc_finish: b.compute(layout, shaders::LAYOUT_MC_FINISH_COMP)?,
        })
    }

    /// Appends one dispatch to `plan` (each depends on the plan's previous one).
    fn run(&self, plan: &mut Plan, pipeline: vk::Pipeline, push: &[u8], groups: u64) {
        plan.dispatches.push((pipeline, push.to_vec(), groups.max(1) as u32));
    }

    /// Exclusive prefix sum of `count` u32s at `data`, block sums from `sums` on.
    fn scan(&self, plan: &mut Plan, data: u64, count: u64, sums: u64) {
        let groups = count.div_ceil(SCAN_BLOCK);
        let push = ScanPush { data, sums, count: count as u32, pad: 0 };
        self.run(plan, self.scan_block, bytemuck::bytes_of(&push), groups);
        if groups > 1 {
            self.scan(plan, sums, groups, sums + groups * 4);
            self.run(plan, self.scan_add, bytemuck::bytes_of(&push), count.div_ceil(GROUP));
        }
    }

    /// Records every plan of a recording together: their fills, then their k-th dispatches
    /// side by side behind one barrier for each k (a barrier per dispatch per layout made a
    /// frame registering 1,024 meshes spend ~50 ms of the H200's time in bubbles).
    pub fn record(&self, r: &mut Recording<'_>, plans: &[Plan]) {
        r.hazards.write(r.cmd, sync::TRANSFER_WRITE);
        for &(buffer, offset, size) in plans.iter().flat_map(|p| &p.fills) {
            // Each range lies inside its buffer (sizes from the same counts).
            r.cmd.fill_buffer(buffer, offset, size, 0);
        }
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let depth = plans.iter().map(|p| p.dispatches.len()).max().unwrap_or(0);
        for k in 0..depth {
            r.hazards.read_write(r.cmd, sync::shader_read(stage), sync::shader_write(stage));
            for (pipeline, push, groups) in plans.iter().filter_map(|p| p.dispatches.get(k)) {
                r.cmd.bind_pipeline(vk::PipelineBindPoint::COMPUTE, *pipeline);
                r.cmd.push_constants(self.layout, vk::ShaderStageFlags::COMPUTE, push);
                r.cmd.dispatch(*groups, 1, 1);
            }
        }
    }

    /// The plan of one tiles layout: three passes (the result zeroed first).
    pub fn plan_tiles(&self, job: &TilesJob) -> Plan {
        let mut plan = Plan { fills: vec![(job.result, 0, 16)], dispatches: Vec::new() };
        let r = &mut plan;
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
        plan
    }

    /// The plan of one mesh-colors layout (degrees, words and result zeroed first).
    pub fn plan_mesh_colors(&self, job: &MeshColorsJob) -> Plan {
        let (t, v) = (job.triangles as u64, job.vertices as u64);
        let e = 3 * t;
        let m = McScratch::new(t, v);
        let at = |words: u64| job.scratch_address + words * 4;
        let fills = vec![(job.scratch, m.degree * 4, v.max(1) * 4), (job.words, 0, t * 36), (job.result, 0, 16)];
        let mut plan = Plan { fills, dispatches: Vec::new() };
        let r = &mut plan;
        let edges = McEdgesPush {
            positions: job.positions,
            indices: job.indices,
            res: at(m.res),
            interior: at(m.interior),
            degree: at(m.degree),
            slot: at(m.slot),
            result: job.result_address,
            triangles: job.triangles,
            unit: job.unit,
            limit: job.limit,
            pad: 0,
        };
        self.run(r, self.mc_edges, bytemuck::bytes_of(&edges), t.div_ceil(GROUP));
        self.scan(r, at(m.degree), v, at(m.degree) + v * 4);
        let fill = McFillPush {
            indices: job.indices,
            start: at(m.degree),
            slot: at(m.slot),
            key: at(m.key),
            edge: at(m.edge),
            lower: at(m.lower),
            edges: e as u32,
            pad: 0,
        };
        self.run(r, self.mc_fill, bytemuck::bytes_of(&fill), e.div_ceil(GROUP));
        let dedup = McDedupPush {
            start: at(m.degree),
            key: at(m.key),
            edge: at(m.edge),
            lower: at(m.lower),
            res: at(m.res),
            rep: at(m.rep),
            edge_res: at(m.edge_res),
            count: at(m.count),
            edges: e as u32,
            vertices: job.vertices,
        };
        self.run(r, self.mc_dedup, bytemuck::bytes_of(&dedup), e.div_ceil(GROUP));
        self.scan(r, at(m.count), e, at(m.count) + e * 4);
        self.scan(r, at(m.interior), t, at(m.interior) + t * 4);
        let mut finish = McFinishPush {
            indices: job.indices,
            words: job.words_address,
            edge: at(m.edge),
            rep: at(m.rep),
            edge_res: at(m.edge_res),
            edge_base: at(m.count),
            res: at(m.res),
            interior_base: at(m.interior),
            result: job.result_address,
            edges: e as u32,
            vertices: job.vertices,
            triangles: job.triangles,
            mode: 0,
        };
        self.run(r, self.mc_finish, bytemuck::bytes_of(&finish), e.div_ceil(GROUP));
        finish.mode = 1;
        self.run(r, self.mc_finish, bytemuck::bytes_of(&finish), t.div_ceil(GROUP));
        plan
    }
}
