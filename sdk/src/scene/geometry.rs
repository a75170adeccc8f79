//! A registered mesh: the SDK's compact copy of its parts and its BLAS.
//!
//! Why copy: the BLAS of a throttled geometry may be built frames after registration, and a
//! refit reads the vertices again; copying at registration lets the engine free or reuse its
//! buffers as soon as the registering ticket is back, and gives the lighting cache a vertex
//! and index source it owns. The copy is compact whatever the engine's layout: the parts'
//! vertex ranges are copied to a transient staging buffer (vkCmdCopyBuffer: the engine's
//! buffers need only TRANSFER_SRC), then `passes::geometry_pack` keeps 12 bytes of position
//! per vertex, in geometry space, and 32-bit indices into the geometry's vertices.
use crate::cache::layout::SurfelLayout;
use crate::error::{Error, Result};
use crate::gpu::commands::Commands;
use crate::gpu::memory::{Buffer, Memory, MemoryKind};
use crate::types::{BuildHint, GeometryInput, SurfelType, VertexBufferInput, MAX_ALBEDO_TEXTURE_SIZE};
use ash::vk;
use glam::{Affine3A, Mat4, Vec3};
use gpu_allocator::MemoryLocation;

/// Bytes per vertex in the SDK's copy (a position).
pub(crate) const VERTEX_STRIDE: u64 = 12;
/// Bytes per triangle in the SDK's copy (three 32-bit indices).
const TRIANGLE_BYTES: u64 = 12;

/// Bytes per vertex of the texture coordinates an alpha-tested or albedo-textured copy keeps
/// (two f32).
pub(crate) const UV_STRIDE: u64 = 8;
/// Bytes per vertex of the colours a coloured copy keeps (RGBA8 unorm, linear).
pub(crate) const COLOR_STRIDE: u64 = 4;

/// The layout of the SDK's copy of a geometry: every part's vertices (12 bytes each), then
/// every part's triangles (three u32 each), parts in order; then, each 16-byte aligned and
/// only when used: every vertex's texture coordinates (two f32; alpha-tested or
/// albedo-textured geometry), the alpha texture (one byte per texel, rows of
/// `alpha_pitch_words` u32), every vertex's colour (RGBA8) and the albedo texture (RGBA8
/// sRGB, rows of `albedo_width` texels).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct GeometryLayout {
    pub vertex_count: u32,
    pub primitive_count: u32,
    pub component_count: u32,
    pub allow_update: bool,
    pub build_hint: BuildHint,
    /// The alpha texture's size (0 x 0: opaque geometry).
    pub alpha_width: u32,
    pub alpha_height: u32,
    /// `AlphaTestInput::cutoff`'s bits (the layout stays `Eq`).
    pub alpha_cutoff_bits: u32,
    /// Texture coordinates are kept (alpha test or albedo texture).
    pub has_uvs: bool,
    /// Per-vertex colours are kept.
    pub has_colors: bool,
    /// The albedo texture's copy (0 x 0: none), at most `MAX_ALBEDO_TEXTURE_SIZE` a side.
    pub albedo_width: u32,
    pub albedo_height: u32,
}

impl GeometryLayout {
    /// The layout of `input`'s copy, with every size checked (see `CopyPlan::of`).
    pub fn of(input: &GeometryInput) -> Result<GeometryLayout> {
        Ok(CopyPlan::of(input)?.layout)
    }

    /// Byte offset of the first index.
    pub fn index_offset(&self) -> u64 {
        self.vertex_count as u64 * VERTEX_STRIDE
    }

    /// Whether rays test the geometry's alpha (its BLAS is built non-opaque).
    pub fn alpha_tested(&self) -> bool {
        self.alpha_width > 0
    }

    /// Byte offset of the texture coordinates (with `has_uvs`).
    pub fn uv_offset(&self) -> u64 {
        (self.index_offset() + self.primitive_count as u64 * TRIANGLE_BYTES).next_multiple_of(16)
    }

    fn uv_end(&self) -> u64 {
        self.uv_offset() + if self.has_uvs { self.vertex_count as u64 * UV_STRIDE } else { 0 }
    }

    /// u32 words per row of the alpha texture's copy (four texels a word).
    pub fn alpha_pitch_words(&self) -> u32 {
        self.alpha_width.div_ceil(4)
    }

    /// Byte offset of the alpha texture's copy.
    pub fn alpha_offset(&self) -> u64 {
        self.uv_end().next_multiple_of(16)
    }

    fn alpha_end(&self) -> u64 {
        self.alpha_offset() + self.alpha_pitch_words() as u64 * 4 * self.alpha_height as u64
    }

    /// Byte offset of the per-vertex colours (with `has_colors`).
    pub fn color_offset(&self) -> u64 {
        self.alpha_end().next_multiple_of(16)
    }

    fn color_end(&self) -> u64 {
        self.color_offset() + if self.has_colors { self.vertex_count as u64 * COLOR_STRIDE } else { 0 }
    }

    /// Byte offset of the albedo texture's copy.
    pub fn albedo_offset(&self) -> u64 {
        self.color_end().next_multiple_of(16)
    }

    /// Bytes of the copy (checked when the layout was made).
    pub fn total_bytes(&self) -> u64 {
        if self.has_uvs || self.has_colors {
            self.albedo_offset() + self.albedo_width as u64 * 4 * self.albedo_height as u64
        } else {
            self.index_offset() + self.primitive_count as u64 * TRIANGLE_BYTES
        }
    }
}

/// How one part of a geometry is copied: the engine's regions that go to staging, and where
/// the part lands in the compact copy.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PartCopy {
    pub vertex_buffer: vk::Buffer,
    /// Engine byte offset of the first copied vertex's position.
    pub vertex_src_offset: u64,
    /// Bytes from the first copied vertex's position to the end of the last's.
    pub vertex_bytes: u64,
    /// Null for non-indexed parts.
    pub index_buffer: vk::Buffer,
    pub index_src_offset: u64,
    pub index_bytes: u64,
    pub stride: u32,
    pub vertex_count: u32,
    /// The first copied vertex's index in the engine's buffer.
    pub first_vertex: u32,
    /// 0 (non-indexed), 2 or 4.
    pub index_size: u32,
    pub triangle_count: u32,
    /// The part's first vertex and triangle in the geometry.
    pub vertex_base: u32,
    pub triangle_base: u32,
    pub transform: Affine3A,
    /// Offsets of the part's vertices and indices in the geometry's staging span.
    pub staging_vertices: u64,
    pub staging_indices: u64,
    /// Alpha-tested geometry: the part's texture coordinates (null buffer: none), copied to
    /// staging at `staging_uvs` like the positions.
    pub uv_buffer: vk::Buffer,
    pub uv_src_offset: u64,
    pub uv_bytes: u64,
    pub uv_stride: u32,
    pub uv_format: vk::Format,
    pub staging_uvs: u64,
    /// Coloured geometry: the part's colours (null buffer: none), staged like the positions.
    pub color_buffer: vk::Buffer,
    pub color_src_offset: u64,
    pub color_bytes: u64,
    pub color_stride: u32,
    pub color_format: vk::Format,
    pub staging_colors: u64,
}

impl PartCopy {
    /// Part to geometry space as the pack shader's three rows.
    pub fn rows(&self) -> [[f32; 4]; 3] {
        let m = Mat4::from(self.transform);
        [m.row(0).to_array(), m.row(1).to_array(), m.row(2).to_array()]
    }
}

/// Everything a geometry's copy needs: its layout, its parts, and its staging bytes.
#[derive(Debug, Clone)]
pub(crate) struct CopyPlan {
    pub layout: GeometryLayout,
    pub parts: Vec<PartCopy>,
    pub staging_bytes: u64,
}

impl CopyPlan {
    /// The plan of `input`'s copy, in checked arithmetic: counts or strides that overflow are
    /// an error here, never a wrapped size that reaches the driver. (`validate` has checked
    /// each field; this checks what they add up to.)
    pub fn of(input: &GeometryInput) -> Result<CopyPlan> {
        let overflow = |what: &str| {
            Error::invalid("GeometryInput.vertices / indices (counts, strides, offsets)", format!("{what} overflows"))
        };
        let (mut vertices, mut triangles, mut staging) = (0u32, 0u32, 0u64);
        let mut parts = Vec::with_capacity(1 + input.extra_components.len());
        for c in input.components() {
            let v = &c.vertices;
            let indexed = c.indices.buffer != vk::Buffer::null();
            let (first, count) = match c.vertex_range.filter(|_| indexed) {
                Some(r) => (r.first, r.last.saturating_sub(r.first).saturating_add(1)),
                None => (0, v.count),
            };
            let position_bytes = if v.format == vk::Format::R32G32B32A32_SFLOAT { 16 } else { 12 };
            let vertex_bytes = v
                .stride
                .checked_mul(u64::from(count.max(1)) - 1)
                .and_then(|b| b.checked_add(position_bytes))
                .ok_or_else(|| overflow("a part's vertex bytes"))?;
            let vertex_src_offset = v
                .stride
                .checked_mul(u64::from(first))
                .and_then(|b| b.checked_add(v.offset))
                .ok_or_else(|| overflow("a vertex offset"))?;
            let index_size = match (indexed, c.indices.format) {
                (false, _) => 0u32,
                (true, vk::Format::R16_UINT) => 2,
                (true, _) => 4,
            };
            let triangle_count = if indexed { c.indices.count / 3 } else { v.count / 3 };
            let index_bytes = u64::from(index_size) * u64::from(if indexed { c.indices.count } else { 0 });
            let staging_vertices = staging;
            let staging_indices = staging
                .checked_add(vertex_bytes)
                .and_then(|b| b.checked_next_multiple_of(16))
                .ok_or_else(|| overflow("staging"))?;
            staging = staging_indices
                .checked_add(index_bytes)
                .and_then(|b| b.checked_next_multiple_of(16))
                .ok_or_else(|| overflow("staging"))?;
            // Alpha-tested or albedo-textured geometry: the texture coordinates of the same
            // vertices; coloured geometry: their colours. Each staged after the indices.
            let uv = c.uvs.filter(|_| input.alpha_test.is_some() || input.albedo_texture.is_some());
            let staging_uvs = staging;
            let (uv_src_offset, uv_bytes) = match uv {
                Some(u) => {
                    attribute_region(&u, first, count, if u.format == vk::Format::R32G32_SFLOAT { 8 } else { 4 }, &mut staging)
                        .ok_or_else(|| overflow("a part's texture coordinates"))?
                }
                None => (0, 0),
            };
            let staging_colors = staging;
            let (color_src_offset, color_bytes) = match c.colors {
                Some(u) => attribute_region(&u, first, count, color_element_bytes(u.format), &mut staging)
                    .ok_or_else(|| overflow("a part's colours"))?,
                None => (0, 0),
            };
            parts.push(PartCopy {
                vertex_buffer: v.buffer,
                vertex_src_offset,
                vertex_bytes,
                index_buffer: c.indices.buffer,
                index_src_offset: c.indices.offset,
                index_bytes,
                stride: u32::try_from(v.stride).map_err(|_| overflow("a stride"))?,
                vertex_count: count,
                first_vertex: first,
                index_size,
                triangle_count,
                vertex_base: vertices,
                triangle_base: triangles,
                transform: c.transform.unwrap_or(Affine3A::IDENTITY),
                staging_vertices,
                staging_indices,
                uv_buffer: uv.map_or(vk::Buffer::null(), |u| u.buffer),
                uv_src_offset,
                uv_bytes,
                uv_stride: uv.map_or(Ok(0), |u| u32::try_from(u.stride)).map_err(|_| overflow("a stride"))?,
                uv_format: uv.map_or(vk::Format::UNDEFINED, |u| u.format),
                staging_uvs,
                color_buffer: c.colors.map_or(vk::Buffer::null(), |u| u.buffer),
                color_src_offset,
                color_bytes,
                color_stride: c.colors.map_or(Ok(0), |u| u32::try_from(u.stride)).map_err(|_| overflow("a stride"))?,
                color_format: c.colors.map_or(vk::Format::UNDEFINED, |u| u.format),
                staging_colors,
            });
            vertices = vertices.checked_add(count).ok_or_else(|| overflow("the vertex count"))?;
            triangles = triangles.checked_add(triangle_count).ok_or_else(|| overflow("the triangle count"))?;
        }
        let alpha = input.alpha_test.as_ref();
        let layout = GeometryLayout {
            vertex_count: vertices,
            primitive_count: triangles,
            component_count: parts.len() as u32,
            allow_update: input.allow_update,
            build_hint: input.build_hint,
            alpha_width: alpha.map_or(0, |a| a.texture.width),
            alpha_height: alpha.map_or(0, |a| a.texture.height),
            alpha_cutoff_bits: alpha.map_or(0, |a| a.cutoff.to_bits()),
            has_uvs: parts.first().is_some_and(|p| p.uv_buffer != vk::Buffer::null()),
            has_colors: parts.first().is_some_and(|p| p.color_buffer != vk::Buffer::null()),
            albedo_width: input.albedo_texture.map_or(0, |a| a.texture.width.min(MAX_ALBEDO_TEXTURE_SIZE)),
            albedo_height: input.albedo_texture.map_or(0, |a| a.texture.height.min(MAX_ALBEDO_TEXTURE_SIZE)),
        };
        // The copy's bytes (u32 counts times 12, textures of u32 x u32 bytes: cannot overflow
        // u64, but say so).
        (vertices as u64 * VERTEX_STRIDE)
            .checked_add(triangles as u64 * TRIANGLE_BYTES)
            .and_then(|b| b.checked_add(vertices as u64 * (UV_STRIDE + COLOR_STRIDE) + 64))
            .and_then(|b| b.checked_add(layout.alpha_pitch_words() as u64 * 4 * layout.alpha_height as u64))
            .and_then(|b| b.checked_add(layout.albedo_width as u64 * 4 * layout.albedo_height as u64))
            .ok_or_else(|| overflow("the copy"))?;
        Ok(CopyPlan { layout, parts, staging_bytes: staging })
    }

    /// Records the copies of the engine's regions into `staging` at `base` (the geometry's span).
    pub fn record_staging(&self, cmd: &Commands, staging: vk::Buffer, base: u64) {
        for p in &self.parts {
            let v =
                [vk::BufferCopy { src_offset: p.vertex_src_offset, dst_offset: base + p.staging_vertices, size: p.vertex_bytes }];
            // Regions validated against the buffers' sizes at scheduling.
            cmd.copy_buffer(p.vertex_buffer, staging, &v);
            if p.index_size > 0 {
                let i = [vk::BufferCopy {
                    src_offset: p.index_src_offset,
                    dst_offset: base + p.staging_indices,
                    size: p.index_bytes,
                }];
                cmd.copy_buffer(p.index_buffer, staging, &i);
            }
            if p.uv_buffer != vk::Buffer::null() {
                let u = [vk::BufferCopy { src_offset: p.uv_src_offset, dst_offset: base + p.staging_uvs, size: p.uv_bytes }];
                cmd.copy_buffer(p.uv_buffer, staging, &u);
            }
            if p.color_buffer != vk::Buffer::null() {
                let c =
                    [vk::BufferCopy { src_offset: p.color_src_offset, dst_offset: base + p.staging_colors, size: p.color_bytes }];
                cmd.copy_buffer(p.color_buffer, staging, &c);
            }
        }
    }
}

/// Bytes of one vertex colour in the engine's buffer (formats checked by validation).
pub(crate) fn color_element_bytes(f: vk::Format) -> u64 {
    match f {
        vk::Format::R8G8B8A8_UNORM => 4,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32B32_SFLOAT => 12,
        _ => 16,
    }
}

/// A per-vertex attribute's region in the engine's buffer (source offset, bytes) for the
/// part's `count` vertices from `first`, and its staging span, placed at `*staging` (which
/// moves past it, 16-byte aligned). None on overflow.
fn attribute_region(a: &VertexBufferInput, first: u32, count: u32, element: u64, staging: &mut u64) -> Option<(u64, u64)> {
    let bytes = a.stride.checked_mul(u64::from(count.max(1)) - 1)?.checked_add(element)?;
    let offset = a.stride.checked_mul(u64::from(first))?.checked_add(a.offset)?;
    *staging = staging.checked_add(bytes)?.checked_next_multiple_of(16)?;
    Some((offset, bytes))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BlasState {
    /// Registered, waiting in the build queue.
    Queued,
    /// Built (maybe compacted); instances using it go into the TLAS.
    Ready,
}

pub(crate) struct Blas {
    pub accel: vk::AccelerationStructureKHR,
    pub buffer: Buffer,
    pub address: vk::DeviceAddress,
}

pub(crate) struct GeometryRecord {
    /// None until a register task for it has been built.
    pub layout: Option<GeometryLayout>,
    pub copy: Option<Buffer>,
    pub blas: Option<Blas>,
    pub state: BlasState,
    /// Refit at the next BVH build (allow_update geometry that was updated).
    pub needs_refit: bool,
    /// Bumped at every (re)build, so a compaction size measured for an older build is ignored.
    pub build_id: u64,
    /// Compacted size read back from a completed ticket, waiting for the compaction copy.
    pub compacted_size: Option<u64>,
    /// Registered instances that use this geometry.
    pub instance_refs: usize,
    pub input: GeometryInput,
    /// The surfel layout on the GPU, once its read-back came home.
    pub surfel: Option<SurfelGpu>,
    /// A layout built from a read-back, to upload at the next recording.
    pub pending_layout: Option<SurfelLayout>,
    /// Triangles of the current copy whose indices went past the vertex count (made
    /// degenerate by the index check; known once the copying ticket is back).
    pub invalid_triangles: u32,
    /// The engine's debug name (`ExecuteContext::set_geometry_name`): in errors, logs and the
    /// Vulkan names of its BLAS and copy.
    pub name: Option<String>,
    /// Its BLAS is the fast first build of `BuildHint::FastThenTrace` (rebuilt for fast trace
    /// from `Scene::quality_queue`).
    pub provisional: bool,
}

/// A geometry's surfel layout on the GPU. `id` changes with every new layout, so instance
/// caches made for an older one are reallocated.
pub(crate) struct SurfelGpu {
    pub buffer: Buffer,
    pub sample_count: u32,
    pub surfel_type: SurfelType,
    pub id: u64,
    pub max_resolution: u32,
}

/// Everything of a geometry record but its GPU objects and pending layout: what a failed build
/// puts back (the GPU objects go back through the build's journal).
#[derive(Debug, Clone)]
pub(crate) struct GeometryMeta {
    layout: Option<GeometryLayout>,
    state: BlasState,
    needs_refit: bool,
    build_id: u64,
    compacted_size: Option<u64>,
    instance_refs: usize,
    input: GeometryInput,
    provisional: bool,
}

impl GeometryRecord {
    pub fn meta(&self) -> GeometryMeta {
        GeometryMeta {
            layout: self.layout,
            state: self.state,
            needs_refit: self.needs_refit,
            build_id: self.build_id,
            compacted_size: self.compacted_size,
            instance_refs: self.instance_refs,
            input: self.input.clone(),
            provisional: self.provisional,
        }
    }

    pub fn restore(&mut self, m: GeometryMeta) {
        let GeometryMeta { layout, state, needs_refit, build_id, compacted_size, instance_refs, input, provisional } = m;
        (self.layout, self.state, self.needs_refit, self.build_id) = (layout, state, needs_refit, build_id);
        (self.compacted_size, self.instance_refs, self.input, self.provisional) =
            (compacted_size, instance_refs, input, provisional);
    }

    pub fn new() -> GeometryRecord {
        GeometryRecord {
            layout: None,
            copy: None,
            blas: None,
            state: BlasState::Queued,
            needs_refit: false,
            build_id: 0,
            compacted_size: None,
            instance_refs: 0,
            input: GeometryInput::default(),
            surfel: None,
            pending_layout: None,
            invalid_triangles: 0,
            name: None,
            provisional: false,
        }
    }

    pub fn registered(&self) -> bool {
        self.layout.is_some()
    }

    /// " \"name\"" for messages, or nothing.
    pub fn label(&self) -> String {
        self.name.as_ref().map(|n| format!(" \"{n}\"")).unwrap_or_default()
    }
}

/// Creates a geometry's copy buffer (filled by `passes::geometry_pack`).
pub(crate) fn create_copy(memory: &Memory, layout: &GeometryLayout) -> Result<Buffer> {
    memory.create_buffer(
        "geometry copy",
        layout.total_bytes(),
        vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
        MemoryLocation::GpuOnly,
        MemoryKind::GeometryCopy,
    )
}

/// The bytes a buffer can hold at most (its memory requirement, which is >= its size). Used to
/// catch regions that surely overrun an engine buffer; Vulkan offers no exact size query.
pub(crate) fn buffer_capacity(device: &ash::Device, buffer: vk::Buffer) -> u64 {
    // SAFETY: the engine's buffer is live: the contract of the entry points that take it.
    unsafe { device.get_buffer_memory_requirements(buffer) }.size
}

pub(crate) fn check_region(device: &ash::Device, what: &'static str, buffer: vk::Buffer, offset: u64, bytes: u64) -> Result<()> {
    let available = buffer_capacity(device, buffer);
    let needed = offset.saturating_add(bytes);
    if needed > available {
        return Err(Error::BufferTooSmall { what, needed, available });
    }
    Ok(())
}

/// Positions and triangles from a read-back geometry copy (12-byte vertices, then u32
/// triangles at `index_offset`).
pub(crate) fn read_geometry(bytes: &[u8], g: &GeometryLayout) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let word = |o: usize| bytes.get(o..o + 4).map_or([0; 4], |b| [b[0], b[1], b[2], b[3]]);
    let f = |o: usize| f32::from_le_bytes(word(o));
    let positions = (0..g.vertex_count as usize).map(|v| Vec3::new(f(12 * v), f(12 * v + 4), f(12 * v + 8))).collect();
    let io = g.index_offset() as usize;
    let index = |i: usize| u32::from_le_bytes(word(io + 4 * i));
    let triangles = (0..g.primitive_count as usize).map(|t| [index(3 * t), index(3 * t + 1), index(3 * t + 2)]).collect();
    (positions, triangles)
}
