//! Cache samples live in large shared pages (one buffer each), not a buffer per instance:
//! an instance's cache is a contiguous range of samples, addressed by device address.
//! First-fit allocation with coalescing frees; a cache larger than a page gets a page of its
//! own. Pages grow geometrically, from 2 MiB to 32 MiB, so a small scene reserves little (a
//! room of 17 instances uses under 3 MiB of samples) and a large one few buffers.
use crate::error::Result;
use crate::gpu::memory::{Buffer, Memory, MemoryKind};
use ash::vk;
use gpu_allocator::MemoryLocation;

/// Bytes per sample: vec4 cached value (rgb, history length) + vec4 accumulator (rgb, count).
pub(crate) const SAMPLE_BYTES: u64 = 32;
/// Samples of the largest page: 1 Mi samples = 32 MiB.
pub(crate) const PAGE_SAMPLES: u64 = 1 << 20;
/// Samples of the first page (2 MiB); each new page doubles the last, up to `PAGE_SAMPLES`.
const FIRST_PAGE_SAMPLES: u64 = 1 << 16;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CacheRange {
    pub page: usize,
    pub first: u64,
    pub count: u64,
    pub address: vk::DeviceAddress,
}

struct Page {
    buffer: Buffer,
    capacity: u64,
    /// Free (first, count) runs, sorted by first.
    free: Vec<(u64, u64)>,
    /// One past the highest sample ever allocated (what the resolve pass covers).
    high_water: u64,
}

#[derive(Default)]
pub(crate) struct CachePool {
    /// None: a page given back by `trim` (its index stays, so ranges keep their page number).
    pages: Vec<Option<Page>>,
    /// Ranges out of use that a ticket in flight may still touch: (newest serial then, range).
    retired: Vec<(u64, CacheRange)>,
}

impl CachePool {
    pub fn allocate(&mut self, memory: &Memory, count: u64) -> Result<CacheRange> {
        let count = count.max(1);
        for (p, page) in self.pages.iter_mut().enumerate().filter_map(|(p, page)| Some((p, page.as_mut()?))) {
            if let Some(i) = page.free.iter().position(|&(_, n)| n >= count) {
                let (first, n) = page.free[i];
                if n == count {
                    page.free.remove(i);
                } else {
                    page.free[i] = (first + count, n - count);
                }
                page.high_water = page.high_water.max(first + count);
                return Ok(CacheRange { page: p, first, count, address: page.buffer.address + first * SAMPLE_BYTES });
            }
        }
        let live = self.pages.iter().flatten().count().min(4) as u32;
        let capacity = (FIRST_PAGE_SAMPLES << live).min(PAGE_SAMPLES).max(count);
        let buffer = memory.create_buffer(
            "direct-lighting cache page",
            capacity * SAMPLE_BYTES,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
            MemoryKind::Cache,
        )?;
        let mut free = Vec::new();
        if capacity > count {
            free.push((count, capacity - count));
        }
        let address = buffer.address;
        let page = Page { buffer, capacity, free, high_water: count };
        let index = match self.pages.iter().position(Option::is_none) {
            Some(i) => {
                self.pages[i] = Some(page);
                i
            }
            None => {
                self.pages.push(Some(page));
                self.pages.len() - 1
            }
        };
        Ok(CacheRange { page: index, first: 0, count, address })
    }

    pub fn free(&mut self, r: CacheRange) {
        let Some(Some(page)) = self.pages.get_mut(r.page) else { return };
        let at = page.free.partition_point(|&(f, _)| f < r.first);
        page.free.insert(at, (r.first, r.count));
        // Coalesce with the neighbours.
        if at + 1 < page.free.len() && page.free[at].0 + page.free[at].1 == page.free[at + 1].0 {
            page.free[at].1 += page.free[at + 1].1;
            page.free.remove(at + 1);
        }
        if at > 0 && page.free[at - 1].0 + page.free[at - 1].1 == page.free[at].0 {
            page.free[at - 1].1 += page.free[at].1;
            page.free.remove(at);
        }
        if page.free.len() == 1 && page.free[0] == (0, page.capacity) {
            page.high_water = 0;
        }
    }

    /// Frees `r` once every ticket up to `serial` has come back (see `collect`).
    pub fn free_after(&mut self, serial: u64, r: CacheRange) {
        self.retired.push((serial, r));
    }

    /// Pages, free runs, high-water marks and retired ranges, for the state digest.
    #[cfg(feature = "fault-injection")]
    pub fn digest(&self) -> String {
        let pages: Vec<_> = self.pages.iter().flatten().map(|p| (p.buffer.raw, p.capacity, &p.free, p.high_water)).collect();
        format!("{pages:?} retired {:?}", self.retired)
    }

    /// How many ranges wait for their tickets (a failed build truncates back to it).
    pub fn retired_len(&self) -> usize {
        self.retired.len()
    }

    /// Forgets retirements made after `len` was read (their ranges stay in use).
    pub fn truncate_retired(&mut self, len: usize) {
        self.retired.truncate(len);
    }

    /// Frees the retired ranges no in-flight ticket can still use.
    pub fn collect(&mut self, oldest_in_flight: Option<u64>) {
        let (free, keep): (Vec<_>, Vec<_>) =
            self.retired.drain(..).partition(|(serial, _)| oldest_in_flight.is_none_or(|o| o > *serial));
        self.retired = keep;
        for (_, r) in free {
            self.free(r);
        }
    }

    /// (address, samples) of every page's used span, for whole-cache passes (resolve).
    pub fn spans(&self) -> impl Iterator<Item = (vk::DeviceAddress, u64)> + '_ {
        self.pages.iter().flatten().filter(|p| p.high_water > 0).map(|p| (p.buffer.address, p.high_water))
    }

    /// Gives back every page no cache uses (no ticket may still use them: the caller checked
    /// none is in flight, and retired ranges were collected).
    pub fn trim(&mut self, memory: &Memory) {
        for slot in &mut self.pages {
            if slot.as_ref().is_some_and(|p| p.free.len() == 1 && p.free[0] == (0, p.capacity)) {
                if let Some(p) = slot.take() {
                    memory.destroy_buffer(p.buffer);
                }
            }
        }
    }

    pub fn destroy(&mut self, memory: &Memory) {
        for p in self.pages.drain(..).flatten() {
            memory.destroy_buffer(p.buffer);
        }
    }
}
