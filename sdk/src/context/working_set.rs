//! A working set: what one ticket in flight owns, so frames in flight never share mutable GPU
//! memory — its upload ring, timestamp and compaction query pools, build scratch, the geometry
//! read-backs it carries home, and its own TLAS.
use super::journal::{Held, Journal, Slot};
use super::record::Recorder;
use crate::error::{Error, Result};
use crate::gpu::device::Device;
use crate::gpu::memory::{self, Buffer, Memory, MemoryKind};
use crate::gpu::timestamps::Timer;
use crate::gpu::upload::UploadRing;
use crate::scene::tlas::Tlas;
use crate::types::{GeometryHandle, InitSettings, SurfelType};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// A ticket's read-back for a geometry's surfel layout (geometry, build id of the copy).
pub(super) enum Readback {
    /// The whole copy, for the CPU builders (mesh colors, or a mesh too big for the GPU pass).
    Geometry { geometry: GeometryHandle, build_id: u64, buffer: Buffer },
    /// A layout the GPU built into `words`; `result` holds its (samples, largest R), counted
    /// with resolution limit `limit`.
    Counted { geometry: GeometryHandle, build_id: u64, surfel_type: SurfelType, words: Buffer, result: Buffer, limit: u32 },
}

impl Readback {
    pub fn destroy(self, memory: &Memory) {
        match self {
            Readback::Geometry { buffer, .. } => memory.destroy_buffer(buffer),
            Readback::Counted { words, result, .. } => {
                memory.destroy_buffer(words);
                memory.destroy_buffer(result);
            }
        }
    }
}

pub(super) struct WorkingSet {
    /// The serial of the ticket using it, while one is in flight.
    pub in_flight: Option<u64>,
    pub ring: UploadRing,
    pub scratch: Option<Buffer>,
    pub timer: Timer,
    /// The labels of the ticket's tasks (task index, label), for its `CompletedTask`.
    pub labels: Vec<(u32, String)>,
    pub compaction_pool: vk::QueryPool,
    pub compaction_slots: u32,
    /// Geometries whose compacted size this ticket queries: (geometry, build id).
    pub compactions: Vec<(GeometryHandle, u64)>,
    /// What this ticket sends home to size surfel layouts.
    pub readbacks: Vec<Readback>,
    /// Host-visible counters of the index checks: one u32 per checked copy.
    pub index_counters: Option<Buffer>,
    /// Copies this ticket checked: (geometry, the copy's buffer, counter slot).
    pub index_checks: Vec<(GeometryHandle, vk::Buffer, u32)>,
    /// With a cache budget: one flag per instance slot that the ticket's shaders set when they
    /// use the instance (device-local), and its copy for the host.
    pub usage: Option<Buffer>,
    pub usage_readback: Option<Buffer>,
    /// Instance slots the ticket's flags cover (0: it recorded none).
    pub usage_slots: u32,
    pub tlas: Tlas,
    /// Host-visible: the last command of every recording writes its ticket's serial here, so
    /// a ticket handed back before its commands ran is recognised (`TicketNotComplete`).
    pub marker: Buffer,
}

impl WorkingSet {
    pub fn new(device: &Device, memory: &Memory, settings: &InitSettings) -> Result<WorkingSet> {
        let d = &device.raw;
        let timer = Timer::new(d, settings.max_timed_tasks, device.timestamp_period_ns.is_some(), settings.time_passes)?;
        let ring = match UploadRing::new(memory, settings.upload_ring_bytes.max(4096)) {
            Ok(r) => r,
            Err(e) => {
                timer.destroy(d);
                return Err(e);
            }
        };
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        let mut marker =
            match memory.create_buffer("completion marker", 16, usage, MemoryLocation::GpuToCpu, MemoryKind::Readback) {
                Ok(m) => m,
                Err(e) => {
                    timer.destroy(d);
                    memory.destroy_buffer(ring.buffer);
                    return Err(e);
                }
            };
        // No ticket has serial 0.
        marker.mapped().fill(0);
        Ok(WorkingSet {
            in_flight: None,
            ring,
            scratch: None,
            timer,
            labels: Vec::new(),
            compaction_pool: vk::QueryPool::null(),
            compaction_slots: 0,
            compactions: Vec::new(),
            readbacks: Vec::new(),
            index_counters: None,
            index_checks: Vec::new(),
            usage: None,
            usage_readback: None,
            usage_slots: 0,
            tlas: Tlas { accel: None, version: 0, refit: None },
            marker,
        })
    }

    /// The TLAS to bind (null before the first build).
    pub fn tlas_handle(&self) -> vk::AccelerationStructureKHR {
        self.tlas.accel.as_ref().map(|a| a.accel).unwrap_or_default()
    }

    /// Makes the compaction query pool hold at least `n` queries. The set is idle (its ticket
    /// came back), so the old pool can go at once.
    pub fn ensure_compaction_slots(&mut self, d: &ash::Device, n: u32) -> Result<()> {
        if self.compaction_slots >= n {
            return Ok(());
        }
        if self.compaction_pool != vk::QueryPool::null() {
            // SAFETY: no ticket of this working set is in flight (its owner checked); destroyed once.
            unsafe { d.destroy_query_pool(self.compaction_pool, None) };
            self.compaction_pool = vk::QueryPool::null();
            self.compaction_slots = 0;
        }
        let slots = n.max(16).checked_next_power_of_two().unwrap_or(n);
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
            .query_count(slots);
        // SAFETY: valid create info; destroyed in `destroy` or when replaced.
        self.compaction_pool = unsafe { d.create_query_pool(&info, None) }.map_err(Error::vk("vkCreateQueryPool"))?;
        self.compaction_slots = slots;
        Ok(())
    }

    /// Whether the GPU has run the recording of ticket `serial` to its end (its marker).
    pub fn completed(&self, serial: u64) -> bool {
        self.marker
            .mapped_bytes()
            .and_then(|b| b.get(..8))
            .is_some_and(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])) == serial)
    }

    /// Destroys everything it owns (no ticket of it may be in flight).
    pub fn destroy(mut self, device: &Device, memory: &Memory) {
        self.tlas.destroy(device, memory);
        for r in self.readbacks.drain(..) {
            r.destroy(memory);
        }
        memory.destroy_buffer(self.ring.buffer);
        memory.destroy_buffer(self.marker);
        for b in
            [self.scratch.take(), self.index_counters.take(), self.usage.take(), self.usage_readback.take()].into_iter().flatten()
        {
            memory.destroy_buffer(b);
        }
        self.timer.destroy(&device.raw);
        if self.compaction_pool != vk::QueryPool::null() {
            // SAFETY: the context is being destroyed after its tickets came back; destroyed once.
            unsafe { device.raw.destroy_query_pool(self.compaction_pool, None) };
        }
    }
}

/// Grows a working set's buffer to `size` bytes through the journal: a buffer it replaces is
/// retired after this ticket (the recording may already use it), and a first one is noted so
/// a failed build gives it back.
fn ensure_journaled(
    journal: &mut Journal,
    slot: Slot,
    target: &mut Option<Buffer>,
    size: u64,
    make: impl FnOnce(u64) -> Result<Buffer>,
) -> Result<()> {
    let had = target.is_some();
    memory::ensure_capacity(target, size, make, |old| journal.replaced(slot, Some(Held::Buffer(old))))?;
    if !had && target.is_some() {
        journal.replaced(slot, None);
    }
    Ok(())
}

impl Recorder<'_> {
    /// Build scratch of at least `bytes` (plus alignment slack), returned for binding. Scratch
    /// written earlier in this recording may still be in use by the GPU when a larger one
    /// replaces it, so the old one is retired after this ticket (through the journal); within
    /// one recording, scratch is only reused after a barrier.
    pub fn ensure_scratch(&mut self, bytes: u64) -> Result<vk::DeviceAddress> {
        let memory = self.memory;
        let ws = &mut self.st.working_sets[self.ws];
        ensure_journaled(&mut self.journal, Slot::Scratch, &mut ws.scratch, bytes + self.device.scratch_alignment, |size| {
            memory.create_buffer(
                "build scratch",
                size,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
                MemoryKind::BuildScratch,
            )
        })?;
        // The slack above lets the base meet minAccelerationStructureScratchOffsetAlignment.
        let align = self.device.scratch_alignment.max(1);
        Ok(ws.scratch.as_ref().map_or(0, |s| s.address.div_ceil(align) * align))
    }

    /// Grows the ring so `more` bytes fit after what this recording already wrote. Data
    /// already pushed stays valid: the old ring is retired (through the journal), not freed,
    /// until this ticket is back.
    pub fn ensure_ring(&mut self, more: u64) -> Result<()> {
        let ws = &mut self.st.working_sets[self.ws];
        if ws.ring.remaining() >= more {
            return Ok(());
        }
        let size = (ws.ring.capacity() + more).max(ws.ring.capacity() * 3 / 2);
        let fresh = UploadRing::new(self.memory, size)?;
        let old = std::mem::replace(&mut ws.ring, fresh);
        self.journal.replaced(Slot::Ring, Some(Held::Ring(old)));
        Ok(())
    }

    /// Host-visible index-check counters for `n` copies (zeroed by the caller's fill), their
    /// buffer returned.
    pub fn ensure_index_counters(&mut self, n: u32) -> Result<vk::Buffer> {
        let memory = self.memory;
        let ws = &mut self.st.working_sets[self.ws];
        ensure_journaled(&mut self.journal, Slot::IndexCounters, &mut ws.index_counters, n as u64 * 4, |size| {
            memory.create_buffer(
                "index check counters",
                size.max(256),
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                MemoryKind::Readback,
            )
        })?;
        Ok(ws.index_counters.as_ref().map_or(vk::Buffer::null(), |b| b.raw))
    }

    /// The usage flags for `slots` instance slots (device-local) and their read-back, both
    /// `slots` words at least; returns (flags, read-back).
    pub fn ensure_usage(&mut self, slots: u32) -> Result<(vk::Buffer, u64, vk::Buffer)> {
        let memory = self.memory;
        let ws = &mut self.st.working_sets[self.ws];
        let size = slots as u64 * 4;
        ensure_journaled(&mut self.journal, Slot::Usage, &mut ws.usage, size, |size| {
            memory.create_buffer(
                "cache usage flags",
                size.max(256),
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
                MemoryKind::Cache,
            )
        })?;
        ensure_journaled(&mut self.journal, Slot::UsageReadback, &mut ws.usage_readback, size, |size| {
            memory.create_buffer(
                "cache usage read-back",
                size.max(256),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                MemoryKind::Readback,
            )
        })?;
        let (Some(flags), Some(readback)) = (ws.usage.as_ref(), ws.usage_readback.as_ref()) else {
            return Err(crate::Error::invalid("InitSettings.cache_budget_bytes", "usage buffers missing: SDK bug"));
        };
        Ok((flags.raw, flags.address, readback.raw))
    }

    pub fn working_set(&mut self) -> &mut WorkingSet {
        &mut self.st.working_sets[self.ws]
    }
}
