//! BLAS building: geometry descriptions, sizes, creation, batched build/refit recording and
//! compaction. By default static geometry is built for fast tracing and compacted once the
//! compacted size has come back with a ticket (no stall: the copy happens in a later frame);
//! deformable geometry is built for fast refits and never compacted (`BuildHint` overrides the
//! preference).
use super::geometry::{Blas, GeometryLayout, VERTEX_STRIDE};
use crate::error::{Error, Result};
use crate::gpu::commands::{AsBuild, Commands};
use crate::gpu::device::Device;
use crate::gpu::memory::{Memory, MemoryKind};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// A BLAS's build flags: `BuildHint::build_flags` of its layout.
pub(crate) fn flags(layout: &GeometryLayout, provisional: bool) -> vk::BuildAccelerationStructureFlagsKHR {
    layout.build_hint.build_flags(layout.allow_update, provisional)
}

/// Whether a BLAS is compacted once its compacted size is back (see `BuildHint::compacts`).
pub(crate) fn compacts(layout: &GeometryLayout) -> bool {
    layout.build_hint.compacts(layout.allow_update)
}

pub(crate) fn triangles(
    copy_address: vk::DeviceAddress,
    layout: &GeometryLayout,
) -> vk::AccelerationStructureGeometryKHR<'static> {
    let tri = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
        .vertex_format(vk::Format::R32G32B32_SFLOAT)
        .vertex_data(vk::DeviceOrHostAddressConstKHR { device_address: copy_address })
        .vertex_stride(VERTEX_STRIDE)
        .max_vertex(layout.vertex_count.saturating_sub(1))
        .index_type(vk::IndexType::UINT32)
        .index_data(vk::DeviceOrHostAddressConstKHR { device_address: copy_address + layout.index_offset() });
    vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
        .geometry(vk::AccelerationStructureGeometryDataKHR { triangles: tri })
        // Opaque unless alpha-tested: only alpha-tested geometry ever runs an any-hit shader
        // (once per triangle and ray: the test has no side effects, but need not repeat).
        .flags(if layout.alpha_tested() {
            vk::GeometryFlagsKHR::NO_DUPLICATE_ANY_HIT_INVOCATION
        } else {
            vk::GeometryFlagsKHR::OPAQUE
        })
}

/// What a build or a refit of a geometry's BLAS needs: its triangles, flags and sizes.
/// `provisional`: the fast first build of a `BuildHint::FastThenTrace` geometry.
pub(crate) fn describe(
    device: &Device,
    copy_address: vk::DeviceAddress,
    layout: &GeometryLayout,
    provisional: bool,
) -> (
    vk::AccelerationStructureGeometryKHR<'static>,
    vk::BuildAccelerationStructureFlagsKHR,
    vk::AccelerationStructureBuildSizesInfoKHR<'static>,
) {
    let geometry = triangles(copy_address, layout);
    let flags = flags(layout, provisional);
    let sizes = build_sizes(device, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, flags, &geometry, layout.primitive_count);
    (geometry, flags, sizes)
}

pub(crate) fn build_sizes(
    device: &Device,
    ty: vk::AccelerationStructureTypeKHR,
    flags: vk::BuildAccelerationStructureFlagsKHR,
    geometry: &vk::AccelerationStructureGeometryKHR<'_>,
    primitive_count: u32,
) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    let geometries = std::slice::from_ref(geometry);
    let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(flags)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(geometries);
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    // SAFETY: host query with a well-formed description.
    unsafe {
        device.accel.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            &[primitive_count],
            &mut sizes,
        )
    };
    sizes
}

pub(crate) fn create(
    device: &Device,
    memory: &Memory,
    ty: vk::AccelerationStructureTypeKHR,
    size: u64,
    kind: MemoryKind,
) -> Result<Blas> {
    let buffer = memory.create_buffer(
        if ty == vk::AccelerationStructureTypeKHR::TOP_LEVEL { "TLAS" } else { "BLAS" },
        size,
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR,
        MemoryLocation::GpuOnly,
        kind,
    )?;
    let info = vk::AccelerationStructureCreateInfoKHR::default().buffer(buffer.raw).size(size).ty(ty);
    // SAFETY: the buffer is bound and large enough for `size` (the build-size query's).
    let accel = match unsafe { device.accel.create_acceleration_structure(&info, None) } {
        Ok(a) => a,
        Err(e) => {
            memory.destroy_buffer(buffer);
            return Err(Error::Vulkan { call: "vkCreateAccelerationStructureKHR", result: e });
        }
    };
    // SAFETY: `accel` was just created on this device.
    let address = unsafe {
        device.accel.get_acceleration_structure_device_address(
            &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(accel),
        )
    };
    device.name(accel, if ty == vk::AccelerationStructureTypeKHR::TOP_LEVEL { "TLAS" } else { "BLAS" });
    Ok(Blas { accel, buffer, address })
}

/// One BLAS operation of a batch.
pub(crate) struct BuildJob {
    pub geometry: vk::AccelerationStructureGeometryKHR<'static>,
    pub flags: vk::BuildAccelerationStructureFlagsKHR,
    pub refit: bool,
    pub dst: vk::AccelerationStructureKHR,
    pub primitive_count: u32,
    pub scratch_offset: u64,
}

/// Records every job of the batch in one vkCmdBuildAccelerationStructuresKHR, so the driver can
/// overlap them. Each job has its own scratch region at `scratch` + its offset.
pub(crate) fn record_batch(cmd: &Commands, scratch: vk::DeviceAddress, jobs: &[BuildJob]) {
    let builds = jobs
        .iter()
        .map(|j| AsBuild {
            info: vk::AccelerationStructureBuildGeometryInfoKHR::default()
                .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
                .flags(j.flags)
                .mode(if j.refit {
                    vk::BuildAccelerationStructureModeKHR::UPDATE
                } else {
                    vk::BuildAccelerationStructureModeKHR::BUILD
                })
                .src_acceleration_structure(if j.refit { j.dst } else { vk::AccelerationStructureKHR::null() })
                .dst_acceleration_structure(j.dst)
                .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch + j.scratch_offset }),
            geometry: j.geometry,
            range: vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(j.primitive_count),
        })
        .collect();
    cmd.build_acceleration_structures(builds);
}
