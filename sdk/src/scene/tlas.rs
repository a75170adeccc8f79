//! A working set's TLAS. Each working set owns one so a frame in flight never reads a TLAS the
//! next frame is rebuilding; it is rebuilt only when the scene snapshot changed since that
//! working set last built it.
use super::blas;
use super::geometry::Blas;
use crate::error::Result;
use crate::gpu::commands::{AsBuild, Commands};
use crate::gpu::device::Device;
use crate::gpu::memory::{Memory, MemoryKind};
use crate::gpu::upload::Upload;
use ash::vk;

pub(crate) struct Tlas {
    pub accel: Option<Blas>,
    /// Scene snapshot version this TLAS holds (0 = never built).
    pub version: u64,
    /// Set when the TLAS was built refittable: what it can be refit from.
    pub refit: Option<Refit>,
}

/// How `Tlas::record_build` builds.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Build {
    /// From scratch; `refittable` adds ALLOW_UPDATE so later frames may refit it.
    Full { refittable: bool },
    /// In place, from the TLAS's own last build (which was refittable).
    Refit,
}

/// A refittable TLAS: the topology of its last full build and the refits since.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Refit {
    /// `topology_key` of the snapshot of its last full build.
    pub key: u64,
    /// Refits since that build.
    pub done: u32,
}

/// What a refit must keep: the instance count and, per instance, everything but the
/// transform (BLAS, custom index, mask, hit-group offset, flags).
pub(crate) fn topology_key(snapshot: &[vk::AccelerationStructureInstanceKHR]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    snapshot.len().hash(&mut h);
    for i in snapshot {
        (i.instance_custom_index_and_mask.low_24(), i.instance_custom_index_and_mask.high_8()).hash(&mut h);
        let o = &i.instance_shader_binding_table_record_offset_and_flags;
        (o.low_24(), o.high_8()).hash(&mut h);
        // SAFETY: the SDK writes every instance's reference as a device address.
        unsafe { i.acceleration_structure_reference.device_handle }.hash(&mut h);
    }
    h.finish()
}

pub(crate) fn instances_geometry(instances: Option<Upload>) -> vk::AccelerationStructureGeometryKHR<'static> {
    let data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
        .array_of_pointers(false)
        .data(vk::DeviceOrHostAddressConstKHR { device_address: instances.map_or(0, |u| u.address) });
    vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::INSTANCES)
        .geometry(vk::AccelerationStructureGeometryDataKHR { instances: data })
}

pub(crate) const FLAGS: vk::BuildAccelerationStructureFlagsKHR = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE;

/// The build flags: refittable TLASes also allow updates.
pub(crate) fn flags(refittable: bool) -> vk::BuildAccelerationStructureFlagsKHR {
    if refittable {
        FLAGS | vk::BuildAccelerationStructureFlagsKHR::ALLOW_UPDATE
    } else {
        FLAGS
    }
}

pub(crate) fn sizes(device: &Device, count: u32, refittable: bool) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    blas::build_sizes(device, vk::AccelerationStructureTypeKHR::TOP_LEVEL, flags(refittable), &instances_geometry(None), count)
}

impl Tlas {
    /// Makes sure the TLAS storage fits `size` bytes; returns the storage it replaced (None
    /// when it fits already) for the caller to retire — or put back, should the build fail.
    pub fn ensure_storage(&mut self, device: &Device, memory: &Memory, size: u64) -> Result<Option<Option<Blas>>> {
        if self.accel.as_ref().is_some_and(|a| a.buffer.size >= size) {
            return Ok(None);
        }
        // Headroom so a slowly growing scene does not recreate the TLAS every frame.
        let size = size + size / 2;
        let fresh = blas::create(device, memory, vk::AccelerationStructureTypeKHR::TOP_LEVEL, size, MemoryKind::Tlas)?;
        Ok(Some(self.accel.replace(fresh)))
    }

    /// Records the build into storage made by `ensure_storage` (nothing without it): a full
    /// build, or an in-place refit of a TLAS built refittable from as many instances of the
    /// same topology.
    pub fn record_build(&self, cmd: &Commands, instances: Upload, count: u32, scratch: vk::DeviceAddress, how: Build) {
        let Some(accel) = self.accel.as_ref() else { return };
        let geometry = instances_geometry(Some(instances));
        let (mode, refittable, src) = match how {
            Build::Full { refittable } => {
                (vk::BuildAccelerationStructureModeKHR::BUILD, refittable, vk::AccelerationStructureKHR::null())
            }
            Build::Refit => (vk::BuildAccelerationStructureModeKHR::UPDATE, true, accel.accel),
        };
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(flags(refittable))
            .mode(mode)
            .src_acceleration_structure(src)
            .dst_acceleration_structure(accel.accel)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch });
        let range = vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count);
        cmd.build_acceleration_structures(vec![AsBuild { info, geometry, range }]);
    }

    pub fn destroy(&mut self, device: &Device, memory: &Memory) {
        if let Some(a) = self.accel.take() {
            // SAFETY: the working set is idle (no ticket in flight); destroyed once.
            unsafe { device.accel.destroy_acceleration_structure(a.accel, None) };
            memory.destroy_buffer(a.buffer);
        }
    }
}
