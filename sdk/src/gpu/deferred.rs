//! Deferred destruction keyed by ticket serial: a resource retired while tickets are in flight
//! is freed once every ticket issued up to then has come back.
use super::memory::{Buffer, Memory};
use ash::vk;

pub(crate) enum Garbage {
    Buffer(Buffer),
    AccelerationStructure(vk::AccelerationStructureKHR, Buffer),
    Image(super::memory::Image),
}

#[derive(Default)]
pub(crate) struct DeferredFrees {
    /// (newest serial issued when retired, resource)
    items: Vec<(u64, Garbage)>,
}

impl DeferredFrees {
    /// The serials of the resources waiting, for the state digest.
    #[cfg(feature = "fault-injection")]
    pub fn serials(&self) -> Vec<u64> {
        self.items.iter().map(|(s, _)| *s).collect()
    }

    pub fn retire(&mut self, last_issued_serial: u64, g: Garbage) {
        self.items.push((last_issued_serial, g));
    }

    /// Frees what no in-flight ticket can still use: tickets issued after a retirement never
    /// saw the resource, so only in-flight serials <= the retirement serial hold it.
    pub fn collect(&mut self, device: &super::device::Device, memory: &Memory, oldest_in_flight: Option<u64>) {
        let mut keep = Vec::with_capacity(self.items.len());
        for (serial, g) in self.items.drain(..) {
            if oldest_in_flight.is_some_and(|oldest| oldest <= serial) {
                keep.push((serial, g));
            } else {
                destroy(device, memory, g);
            }
        }
        self.items = keep;
    }
}

pub(crate) fn destroy(device: &super::device::Device, memory: &Memory, g: Garbage) {
    match g {
        Garbage::Buffer(b) => memory.destroy_buffer(b),
        Garbage::Image(i) => memory.destroy_image(i),
        Garbage::AccelerationStructure(a, b) => {
            // SAFETY: no in-flight ticket uses it (see collect).
            unsafe { device.accel.destroy_acceleration_structure(a, None) };
            memory.destroy_buffer(b);
        }
    }
}
