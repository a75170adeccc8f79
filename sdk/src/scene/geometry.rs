//! A registered mesh: the SDK's copy of its vertices/indices and its BLAS.
//!
//! Why copy: the BLAS of a throttled geometry may be built frames after registration, and a
//! refit reads the vertices again; copying at registration (one vkCmdCopyBuffer) lets the
//! engine free or reuse its buffers as soon as the registering ticket is back, and gives the
//! lighting cache a vertex/index source it owns.
use crate::cache::layout::SurfelLayout;
use crate::error::{Error, Result};
use crate::gpu::memory::{Buffer, Memory, MemoryKind};
use crate::types::{GeometryInput, SurfelType};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;

/// The layout of the SDK's copy of a geometry: vertices as the engine laid them out (its
/// stride), then indices.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GeometryLayout {
    pub vertex_count: u32,
    pub vertex_stride: u64,
    pub vertex_bytes: u64,
    /// None for non-indexed triangles.
    pub index_type: Option<vk::IndexType>,
    pub index_offset: u64,
    pub index_count: u32,
    pub primitive_count: u32,
    pub allow_update: bool,
}

impl GeometryLayout {
    /// The copy's layout, with every size computed in checked arithmetic: an engine's stride
    /// or count that overflows is an error here, never a wrapped size that reaches the driver.
    pub fn of(input: &GeometryInput) -> Result<GeometryLayout> {
        let v = &input.vertices;
        let overflow =
            || Error::invalid("GeometryInput.vertices", format!("{} vertices of stride {} overflow 64 bits", v.count, v.stride));
        let position_bytes = if v.format == vk::Format::R32G32B32A32_SFLOAT { 16 } else { 12 };
        let vertex_bytes = v
            .stride
            .checked_mul(u64::from(v.count.max(1)) - 1)
            .and_then(|b| b.checked_add(position_bytes))
            .ok_or_else(overflow)?;
        let indexed = input.indices.buffer != vk::Buffer::null();
        let index_type = indexed.then(|| {
            if input.indices.format == vk::Format::R16_UINT {
                vk::IndexType::UINT16
            } else {
                vk::IndexType::UINT32
            }
        });
        let layout = GeometryLayout {
            vertex_count: v.count,
            vertex_stride: v.stride,
            vertex_bytes,
            index_type,
            index_offset: vertex_bytes.checked_next_multiple_of(4).ok_or_else(overflow)?,
            index_count: if indexed { input.indices.count } else { 0 },
            primitive_count: if indexed { input.indices.count / 3 } else { v.count / 3 },
            allow_update: input.allow_update,
        };
        // The whole copy (rounded up to words) must be addressable too.
        let end = layout.index_offset.checked_add(layout.index_size() * layout.index_count as u64);
        end.and_then(|e| e.checked_next_multiple_of(4)).ok_or_else(overflow)?;
        Ok(layout)
    }

    pub fn index_size(&self) -> u64 {
        match self.index_type {
            Some(vk::IndexType::UINT16) => 2,
            Some(_) => 4,
            None => 0,
        }
    }

    /// Bytes of the copy (checked when the layout was made), rounded up to whole words so the
    /// index check can read 16-bit indices a word at a time.
    pub fn total_bytes(&self) -> u64 {
        (self.index_offset + self.index_size() * self.index_count as u64).next_multiple_of(4)
    }
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
#[derive(Debug, Clone, Copy)]
pub(crate) struct GeometryMeta {
    layout: Option<GeometryLayout>,
    state: BlasState,
    needs_refit: bool,
    build_id: u64,
    compacted_size: Option<u64>,
    instance_refs: usize,
    input: GeometryInput,
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
            input: self.input,
        }
    }

    pub fn restore(&mut self, m: GeometryMeta) {
        let GeometryMeta { layout, state, needs_refit, build_id, compacted_size, instance_refs, input } = m;
        (self.layout, self.state, self.needs_refit, self.build_id) = (layout, state, needs_refit, build_id);
        (self.compacted_size, self.instance_refs, self.input) = (compacted_size, instance_refs, input);
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
        }
    }

    pub fn registered(&self) -> bool {
        self.layout.is_some()
    }
}

/// Creates the copy buffer and records the copy of the engine's vertices and indices into it.
pub(crate) fn record_copy(
    device: &ash::Device,
    memory: &Memory,
    cmd: vk::CommandBuffer,
    input: &GeometryInput,
    layout: &GeometryLayout,
) -> Result<Buffer> {
    let copy = memory.create_buffer(
        "geometry copy",
        layout.total_bytes(),
        vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
        MemoryLocation::GpuOnly,
        MemoryKind::GeometryCopy,
    )?;
    let v = [vk::BufferCopy { src_offset: input.vertices.offset, dst_offset: 0, size: layout.vertex_bytes }];
    // SAFETY: regions validated against the buffers' sizes at scheduling.
    unsafe { device.cmd_copy_buffer(cmd, input.vertices.buffer, copy.raw, &v) };
    if layout.index_type.is_some() {
        let i = [vk::BufferCopy {
            src_offset: input.indices.offset,
            dst_offset: layout.index_offset,
            size: layout.index_size() * layout.index_count as u64,
        }];
        unsafe { device.cmd_copy_buffer(cmd, input.indices.buffer, copy.raw, &i) };
    }
    Ok(copy)
}

/// The bytes a buffer can hold at most (its memory requirement, which is >= its size). Used to
/// catch regions that surely overrun an engine buffer; Vulkan offers no exact size query.
pub(crate) fn buffer_capacity(device: &ash::Device, buffer: vk::Buffer) -> u64 {
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

/// Positions and triangles from a read-back geometry copy (vertices with their stride, then
/// indices at `index_offset`).
pub(crate) fn read_geometry(bytes: &[u8], g: &GeometryLayout) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap_or([0; 4]));
    let positions: Vec<Vec3> = (0..g.vertex_count as usize)
        .map(|v| {
            let o = v * g.vertex_stride as usize;
            if o + 12 <= bytes.len() {
                Vec3::new(f(o), f(o + 4), f(o + 8))
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let io = g.index_offset as usize;
    let index = |i: usize| -> u32 {
        match g.index_size() {
            2 => bytes.get(io + i * 2..io + i * 2 + 2).map_or(0, |b| u16::from_le_bytes([b[0], b[1]]) as u32),
            4 => bytes.get(io + i * 4..io + i * 4 + 4).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            _ => i as u32,
        }
    };
    let triangles = (0..g.primitive_count as usize).map(|t| [index(3 * t), index(3 * t + 1), index(3 * t + 2)]).collect();
    (positions, triangles)
}
