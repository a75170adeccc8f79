//! The geometry pack (shaders/geometry_pack.comp): turns the staging copy of an engine's mesh
//! parts — vertices at the engine's stride and offset, 16- or 32-bit indices, or none — into
//! the SDK's compact copy: 12-byte positions in geometry space, then 32-bit triangle indices.
//!
//! Why a compute pass rather than one vkCmdCopyBuffer: an interleaved 32-byte vertex would
//! otherwise be kept whole for the geometry's life (and read at that stride by every BLAS
//! build, refit and cache lookup); parts of one mesh need their transforms applied and their
//! indices offset into one vertex array; and a bad index must never reach a BLAS build. Each
//! triangle with an index outside its part's vertices is made degenerate and counted; the
//! count comes back with the ticket (`ExecuteContext::geometry_invalid_triangles`).
//! Kickstart RT trusts the engine's indices.
//!
//! Alpha-tested and albedo-textured geometry also gets its texture coordinates packed (the
//! same shader, a UV mode), coloured geometry its vertex colours (a colour mode), and the alpha
//! texture (shaders/alpha_pack.comp) and albedo texture (shaders/albedo_pack.comp) are copied
//! into the copy, so traces read them through the instance table's addresses and bind no
//! texture per geometry.
use super::descriptors::{self, Slot};
use super::Recording;
use crate::error::Result;
use crate::gpu::pipeline::PipelineBuilder;
use crate::gpu::sync;
use crate::shaders;
use ash::vk;
use bytemuck::{Pod, Zeroable};

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct PackPush {
    /// First: std430 aligns vec4 to 16 bytes (GLSL's layout must match this one).
    rows: [[f32; 4]; 3],
    src_vertices: u64,
    dst_vertices: u64,
    src_indices: u64,
    dst_indices: u64,
    counter: u64,
    stride_words: u32,
    vertex_count: u32,
    triangle_count: u32,
    index_size: u32,
    first_vertex: u32,
    vertex_base: u32,
    first_item: u32,
    mode: u32,
}

/// `Push` of shaders/albedo_pack.comp.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct AlbedoPush {
    dst: u64,
    width: u32,
    height: u32,
    src_width: u32,
    src_height: u32,
}

/// `Push` of shaders/alpha_pack.comp.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct AlphaPush {
    dst: u64,
    width: u32,
    height: u32,
    pitch: u32,
    channel: u32,
}

const GROUP: u32 = 256;

/// Texture copies into geometry copies through one of the copy pipelines: each its texture
/// pushed as the set's one binding, its push constants, its 2D dispatch.
fn record_texture_copies<'j, P: Pod>(
    r: &mut Recording<'_>,
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    copies: impl ExactSizeIterator<Item = (&'j crate::types::ImageInput, P, [u32; 2])>,
) {
    if copies.len() == 0 {
        return;
    }
    let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
    r.hazards.read_write(r.cmd, sync::shader_read(stage), sync::shader_write(stage));
    let bind = vk::PipelineBindPoint::COMPUTE;
    r.cmd.bind_pipeline(bind, pipeline);
    for (texture, push, [x, y]) in copies {
        descriptors::push(r.cmd, bind, layout, &[Slot::Sampled(texture)]);
        r.cmd.push_constants(layout, vk::ShaderStageFlags::COMPUTE, bytemuck::bytes_of(&push));
        r.cmd.dispatch(x, y, 1);
    }
}

pub(crate) struct GeometryPack {
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    alpha_layout: vk::PipelineLayout,
    alpha_pipeline: vk::Pipeline,
    albedo_layout: vk::PipelineLayout,
    albedo_pipeline: vk::Pipeline,
}

/// What a pack job copies.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum PackMode {
    /// Positions and indices.
    Positions,
    /// A part's texture coordinates, from this format.
    Uvs(vk::Format),
    /// A part's vertex colours, from this format.
    Colors(vk::Format),
}

/// One albedo texture to copy (box-filtered to `width` x `height`) into a geometry's copy.
pub(crate) struct AlbedoJob {
    pub texture: crate::types::ImageInput,
    pub dst: vk::DeviceAddress,
    pub width: u32,
    pub height: u32,
}

/// One alpha texture to copy into a geometry's copy.
pub(crate) struct AlphaJob {
    pub texture: crate::types::ImageInput,
    pub channel: u32,
    pub dst: vk::DeviceAddress,
    pub width: u32,
    pub height: u32,
    pub pitch_words: u32,
}

/// One part to pack (addresses already offset to the part's first vertex, index, triangle).
pub(crate) struct PackJob {
    pub src_vertices: vk::DeviceAddress,
    pub dst_vertices: vk::DeviceAddress,
    /// Unused when `index_size` is 0.
    pub src_indices: vk::DeviceAddress,
    pub dst_indices: vk::DeviceAddress,
    /// Where bad triangles are counted (a zeroed u32).
    pub counter: vk::DeviceAddress,
    /// The engine's stride in bytes (a multiple of 4).
    pub stride: u32,
    pub vertex_count: u32,
    pub triangle_count: u32,
    /// 0 (non-indexed), 2 or 4.
    pub index_size: u32,
    /// Subtracted from the engine's indices (the part's vertex range starts there).
    pub first_vertex: u32,
    /// The part's first vertex in the geometry (added to its indices).
    pub vertex_base: u32,
    /// Part to geometry space, row-major 3x4.
    pub rows: [[f32; 4]; 3],
    pub mode: PackMode,
}

impl GeometryPack {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<GeometryPack> {
        let layout = b.layout(None, std::mem::size_of::<PackPush>() as u32, vk::ShaderStageFlags::COMPUTE)?;
        let pipeline = b.compute(layout, shaders::GEOMETRY_PACK_COMP)?;
        let texture = crate::gpu::pipeline::Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) };
        let set = b.set_layout(&[texture], vk::ShaderStageFlags::COMPUTE)?;
        let alpha_layout = b.layout(Some(set), std::mem::size_of::<AlphaPush>() as u32, vk::ShaderStageFlags::COMPUTE)?;
        let alpha_pipeline = b.compute(alpha_layout, shaders::ALPHA_PACK_COMP)?;
        let albedo_layout = b.layout(Some(set), std::mem::size_of::<AlbedoPush>() as u32, vk::ShaderStageFlags::COMPUTE)?;
        let albedo_pipeline = b.compute(albedo_layout, shaders::ALBEDO_PACK_COMP)?;
        Ok(GeometryPack { layout, pipeline, alpha_layout, alpha_pipeline, albedo_layout, albedo_pipeline })
    }

    /// Copies albedo textures into their geometries' copies (with the packs: same hazards).
    pub fn record_albedo(&self, r: &mut Recording<'_>, jobs: &[AlbedoJob]) {
        let copies = jobs.iter().map(|j| {
            let push = AlbedoPush {
                dst: j.dst,
                width: j.width,
                height: j.height,
                src_width: j.texture.width,
                src_height: j.texture.height,
            };
            // The copy is at most MAX_ALBEDO_TEXTURE_SIZE a side: 32 x 32 groups at most.
            (&j.texture, push, [j.width.div_ceil(8), j.height.div_ceil(8)])
        });
        record_texture_copies(r, self.albedo_pipeline, self.albedo_layout, copies);
    }

    /// Copies alpha textures into their geometries' copies (with the packs: same hazards).
    pub fn record_alpha(&self, r: &mut Recording<'_>, jobs: &[AlphaJob]) {
        let copies = jobs.iter().map(|j| {
            let push = AlphaPush { dst: j.dst, width: j.width, height: j.height, pitch: j.pitch_words, channel: j.channel };
            // Validated: width and height within maxImageDimension2D, so the groups fit.
            (&j.texture, push, [j.pitch_words.div_ceil(8), j.height.div_ceil(8)])
        });
        record_texture_copies(r, self.alpha_pipeline, self.alpha_layout, copies);
    }

    /// Packs every job (after the staging copies and the counters' fill; before BLAS builds
    /// and read-backs, which the recorder orders through its hazards).
    pub fn record(&self, r: &mut Recording<'_>, jobs: &[PackJob]) {
        if jobs.is_empty() {
            return;
        }
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        r.hazards.read_write(r.cmd, sync::shader_read(stage), sync::shader_atomic(stage));
        let max_groups = r.device.limits.max_dispatch_groups[0].max(1);
        r.cmd.bind_pipeline(vk::PipelineBindPoint::COMPUTE, self.pipeline);
        for j in jobs {
            // One invocation per vertex and per triangle; split so no dispatch exceeds the
            // group-count limit.
            let items = if j.mode == PackMode::Positions { j.vertex_count.max(j.triangle_count) } else { j.vertex_count } as u64;
            let per_dispatch = max_groups as u64 * GROUP as u64;
            let mut first = 0u64;
            while first < items {
                let n = (items - first).min(per_dispatch) as u32;
                let push = PackPush {
                    rows: j.rows,
                    src_vertices: j.src_vertices,
                    dst_vertices: j.dst_vertices,
                    src_indices: j.src_indices,
                    dst_indices: j.dst_indices,
                    counter: j.counter,
                    stride_words: j.stride / 4,
                    vertex_count: j.vertex_count,
                    triangle_count: j.triangle_count,
                    index_size: j.index_size,
                    first_vertex: j.first_vertex,
                    vertex_base: j.vertex_base,
                    first_item: first as u32,
                    mode: match j.mode {
                        PackMode::Positions => 0,
                        PackMode::Uvs(vk::Format::R32G32_SFLOAT) => 1,
                        PackMode::Uvs(vk::Format::R16G16_SFLOAT) => 2,
                        PackMode::Uvs(_) => 3,
                        PackMode::Colors(vk::Format::R8G8B8A8_UNORM) => 4,
                        PackMode::Colors(vk::Format::R16G16B16A16_SFLOAT) => 5,
                        PackMode::Colors(vk::Format::R32G32B32_SFLOAT) => 6,
                        PackMode::Colors(_) => 7,
                    },
                };
                r.cmd.push_constants(self.layout, vk::ShaderStageFlags::COMPUTE, bytemuck::bytes_of(&push));
                r.cmd.dispatch(n.div_ceil(GROUP), 1, 1);
                first += n as u64;
            }
        }
    }
}
