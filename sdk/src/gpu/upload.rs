//! A working set's upload ring: host-visible memory the GPU reads directly (TLAS instance
//! records, per-task constants). Reset each time its working set is recorded; safe because a
//! working set is recorded only when its previous ticket has come back.
use super::memory::{Buffer, Memory, MemoryKind};
use crate::error::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;

pub(crate) struct UploadRing {
    pub buffer: Buffer,
    cursor: u64,
}

/// Where an upload landed.
#[derive(Clone, Copy)]
pub(crate) struct Upload {
    pub buffer: vk::Buffer,
    pub offset: u64,
    pub address: vk::DeviceAddress,
    pub size: u64,
}

impl UploadRing {
    pub fn new(memory: &Memory, size: u64) -> Result<UploadRing> {
        let buffer = memory.create_buffer(
            "upload ring",
            size,
            vk::BufferUsageFlags::UNIFORM_BUFFER
                | vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
            MemoryLocation::CpuToGpu,
            MemoryKind::UploadRing,
        )?;
        Ok(UploadRing { buffer, cursor: 0 })
    }

    pub fn reset(&mut self) {
        self.cursor = 0;
    }

    pub fn remaining(&self) -> u64 {
        self.buffer.size.saturating_sub(self.cursor.div_ceil(256) * 256)
    }

    pub fn capacity(&self) -> u64 {
        self.buffer.size
    }

    /// Copies `bytes` in at the next `align`-ed offset. The caller sized the ring beforehand
    /// (see `ExecuteContext::build_gpu_task`), so running out is an SDK bug.
    pub fn push(&mut self, bytes: &[u8], align: u64) -> Upload {
        let offset = self.cursor.div_ceil(align) * align;
        let end = offset + bytes.len() as u64;
        assert!(end <= self.buffer.size, "upload ring sized too small: SDK bug");
        self.buffer.mapped()[offset as usize..end as usize].copy_from_slice(bytes);
        self.cursor = end;
        Upload { buffer: self.buffer.raw, offset, address: self.buffer.address + offset, size: bytes.len() as u64 }
    }
}
