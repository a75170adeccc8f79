//! The BLAS-build floor of the bench: `vkCmdBuildAccelerationStructuresKHR` alone, on the same
//! triangles the SDK registers, with each set of build flags — what the driver does without
//! the SDK around it, so the bench can say how much of a registration frame is ours.
//!
//! Kept apart from the SDK on purpose: its own buffers (device-local, compact 12-byte
//! positions and 32-bit indices, as the SDK's geometry copy), its own scratch, one build per
//! command buffer between two timestamps. The bench interleaves these builds with the SDK's
//! registration frames, so clock drift hits both alike (single short submissions with waits
//! between them run at whatever clock the GPU has fallen to). Building into fresh memory
//! every time measured the same as building one BLAS again on the H200 (2.62 / 2.61 ms fast
//! build), so a BLAS is kept per flag set.
use ash::vk;
use hybrid_rt_host::{Host, HostBuffer, HostResult};
use hybrid_rt_samples::gpu::GpuTimer;

struct Target {
    flags: vk::BuildAccelerationStructureFlagsKHR,
    blas: vk::AccelerationStructureKHR,
    storage: HostBuffer,
    scratch: HostBuffer,
}

/// The triangles, and a BLAS (with its scratch) per flag set built so far.
pub struct BlasFloor {
    accel: ash::khr::acceleration_structure::Device,
    vertices: HostBuffer,
    indices: HostBuffer,
    vertex_count: u32,
    primitive_count: u32,
    targets: Vec<Target>,
    timer: GpuTimer,
}

fn address(host: &Host, b: &HostBuffer) -> vk::DeviceAddress {
    // SAFETY: the buffer was created with SHADER_DEVICE_ADDRESS usage.
    unsafe { host.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(b.buffer)) }
}

impl BlasFloor {
    pub fn new(host: &Host, positions: &[glam::Vec3], indices: &[u32]) -> HostResult<BlasFloor> {
        let input =
            vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR;
        let vertices = host.device_buffer_with_data(bytemuck::cast_slice(positions), input)?;
        let index_buffer = match host.device_buffer_with_data(bytemuck::cast_slice(indices), input) {
            Ok(b) => b,
            Err(e) => {
                host.destroy_buffer(vertices);
                return Err(e);
            }
        };
        let timer = match GpuTimer::new(host) {
            Ok(t) => t,
            Err(e) => {
                host.destroy_buffer(vertices);
                host.destroy_buffer(index_buffer);
                return Err(e);
            }
        };
        Ok(BlasFloor {
            accel: ash::khr::acceleration_structure::Device::new(&host.instance, &host.device),
            vertices,
            indices: index_buffer,
            vertex_count: positions.len() as u32,
            primitive_count: (indices.len() / 3) as u32,
            targets: Vec::new(),
            timer,
        })
    }

    fn geometry(&self, host: &Host) -> vk::AccelerationStructureGeometryKHR<'static> {
        let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR { device_address: address(host, &self.vertices) })
            .vertex_stride(12)
            .max_vertex(self.vertex_count.saturating_sub(1))
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR { device_address: address(host, &self.indices) });
        vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
            .flags(vk::GeometryFlagsKHR::OPAQUE)
    }

    /// The BLAS of `flags`, made on first use: storage and scratch as the size query says
    /// (256 bytes of slack: minAccelerationStructureScratchOffsetAlignment is at most that).
    fn target(&mut self, host: &Host, flags: vk::BuildAccelerationStructureFlagsKHR) -> HostResult<usize> {
        if let Some(i) = self.targets.iter().position(|t| t.flags == flags) {
            return Ok(i);
        }
        let geometry = [self.geometry(host)];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
            .flags(flags)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometry);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        // SAFETY: a host query on a well-formed description.
        unsafe {
            self.accel.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[self.primitive_count],
                &mut sizes,
            )
        };
        let storage = host.create_buffer(
            sizes.acceleration_structure_size,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            vk::MemoryPropertyFlags::DEVICE_LOCAL,
        )?;
        let scratch = match host.create_buffer(
            sizes.build_scratch_size + 256,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            vk::MemoryPropertyFlags::DEVICE_LOCAL,
        ) {
            Ok(s) => s,
            Err(e) => {
                host.destroy_buffer(storage);
                return Err(e);
            }
        };
        let create = vk::AccelerationStructureCreateInfoKHR::default()
            .buffer(storage.buffer)
            .size(sizes.acceleration_structure_size)
            .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL);
        // SAFETY: the storage buffer is live and as large as the query said.
        match unsafe { self.accel.create_acceleration_structure(&create, None) } {
            Ok(blas) => {
                self.targets.push(Target { flags, blas, storage, scratch });
                Ok(self.targets.len() - 1)
            }
            Err(e) => {
                host.destroy_buffer(storage);
                host.destroy_buffer(scratch);
                Err(format!("create BLAS: {e:?}"))
            }
        }
    }

    /// One build with `flags` in its own submission (waited on): its GPU time in ms.
    pub fn build(&mut self, host: &Host, flags: vk::BuildAccelerationStructureFlagsKHR) -> HostResult<f64> {
        let t = self.target(host, flags)?;
        let geometry = [self.geometry(host)];
        let target = &self.targets[t];
        let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL)
            .flags(flags)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(&geometry)
            .dst_acceleration_structure(target.blas)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: address(host, &target.scratch).next_multiple_of(256) });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(self.primitive_count)];
        let (accel, timer) = (&self.accel, &mut self.timer);
        host.run(|cmd| {
            timer.begin(host, cmd);
            // SAFETY: every address points into a live buffer sized by the query.
            unsafe { accel.cmd_build_acceleration_structures(cmd, std::slice::from_ref(&info), &[&range[..]]) };
            timer.mark(host, cmd, "BLAS floor");
        })?;
        Ok(timer.read(host).first().map_or(0.0, |(_, ms)| *ms))
    }

    pub fn destroy(self, host: &Host) {
        for t in self.targets {
            // SAFETY: every build using it has completed (`build` waits).
            unsafe { self.accel.destroy_acceleration_structure(t.blas, None) };
            host.destroy_buffer(t.storage);
            host.destroy_buffer(t.scratch);
        }
        self.timer.destroy(host);
        host.destroy_buffer(self.vertices);
        host.destroy_buffer(self.indices);
    }
}
