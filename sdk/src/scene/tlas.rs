//! A working set's TLAS. Each working set owns one so a frame in flight never reads a TLAS the
//! next frame is rebuilding; it is rebuilt only when the scene snapshot changed since that
//! working set last built it.
use super::blas;
use super::geometry::Blas;
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::{Memory, MemoryKind};
use crate::gpu::upload::Upload;
use ash::vk;

pub(crate) struct Tlas {
    pub accel: Option<Blas>,
    /// Scene snapshot version this TLAS holds (0 = never built).
    pub version: u64,
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

pub(crate) fn sizes(device: &Device, count: u32) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    blas::build_sizes(device, vk::AccelerationStructureTypeKHR::TOP_LEVEL, FLAGS, &instances_geometry(None), count)
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

    /// Records the build into storage made by `ensure_storage` (nothing without it).
    pub fn record_build(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        instances: Upload,
        count: u32,
        scratch: vk::DeviceAddress,
    ) {
        let Some(accel) = self.accel.as_ref() else { return };
        let geometry = instances_geometry(Some(instances));
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(FLAGS)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .dst_acceleration_structure(accel.accel)
            .geometries(std::slice::from_ref(&geometry))
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count)];
        unsafe { device.accel.cmd_build_acceleration_structures(cmd, &[info], &[&range[..]]) };
    }

    pub fn destroy(&mut self, device: &Device, memory: &Memory) {
        if let Some(a) = self.accel.take() {
            unsafe { device.accel.destroy_acceleration_structure(a.accel, None) };
            memory.destroy_buffer(a.buffer);
        }
    }
}
