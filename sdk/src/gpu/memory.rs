//! Device memory: buffers sub-allocated by gpu-allocator, each tagged with the kind of data it
//! holds so `ExecuteContext::resource_allocations` can report bytes and counts per kind.
use super::allocation_log::AllocationLog;
use crate::error::{Error, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc};
use gpu_allocator::MemoryLocation;
use parking_lot::Mutex;

/// What a piece of SDK memory holds (the rows of [`ResourceAllocations`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
#[non_exhaustive]
pub enum MemoryKind {
    /// The SDK's copies of geometry vertices and indices (BLAS build inputs).
    GeometryCopy = 0,
    /// Bottom-level acceleration structures.
    Blas = 1,
    /// Scratch memory for BLAS/TLAS builds, one per working set.
    BuildScratch = 2,
    /// Top-level acceleration structures, one per working set.
    Tlas = 3,
    /// Per-working-set upload rings (TLAS instances, task constants).
    UploadRing = 4,
    /// Shader binding tables and other fixed pipeline data.
    Pipeline = 5,
    /// Direct-lighting cache pages and surfel layouts.
    Cache = 6,
    /// Transient geometry data of a registration (the staging copy of the engine's vertices
    /// and indices, the read-back for the cache layout), alive until its ticket returns;
    /// completion markers and bad-triangle counters.
    Readback = 7,
    /// Denoising contexts' history and intermediate images.
    Denoiser = 8,
    /// Many-lights contexts: light lists, their power distributions and resampling history.
    ManyLights = 9,
}

/// Number of `MemoryKind`s.
pub const MEMORY_KIND_COUNT: usize = 10;

/// Bytes and counts of live SDK allocations, per kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[repr(C)]
#[non_exhaustive]
pub struct AllocationCount {
    /// Live allocations.
    pub count: u64,
    /// Their bytes (of device memory, as allocated).
    pub bytes: u64,
}

/// A snapshot of the SDK's device memory use, for budgeting.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[repr(C)]
#[non_exhaustive]
pub struct ResourceAllocations {
    /// The SDK's copies of geometry (`MemoryKind::GeometryCopy`).
    pub geometry_copies: AllocationCount,
    /// BLASes.
    pub blas: AllocationCount,
    /// Build scratch.
    pub build_scratch: AllocationCount,
    /// TLASes (one per working set).
    pub tlas: AllocationCount,
    /// Upload rings (one per working set).
    pub upload_rings: AllocationCount,
    /// Shader binding tables.
    pub pipelines: AllocationCount,
    /// Direct-lighting cache pages and surfel layouts.
    pub cache: AllocationCount,
    /// Geometry staging and read-backs, completion markers and bad-triangle counters.
    pub readback: AllocationCount,
    /// Denoiser history.
    pub denoiser: AllocationCount,
    /// Many-lights contexts (light lists, resampling history).
    pub many_lights: AllocationCount,
}

impl ResourceAllocations {
    /// Every row with its kind, in `MemoryKind` order (the kinds the allocation log names).
    pub fn by_kind(&self) -> [(MemoryKind, AllocationCount); MEMORY_KIND_COUNT] {
        use MemoryKind::*;
        [
            (GeometryCopy, self.geometry_copies),
            (Blas, self.blas),
            (BuildScratch, self.build_scratch),
            (Tlas, self.tlas),
            (UploadRing, self.upload_rings),
            (Pipeline, self.pipelines),
            (Cache, self.cache),
            (Readback, self.readback),
            (Denoiser, self.denoiser),
            (ManyLights, self.many_lights),
        ]
    }

    /// Bytes over every kind.
    pub fn total_bytes(&self) -> u64 {
        self.by_kind().iter().map(|(_, c)| c.bytes).sum()
    }
}

pub(crate) struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    pub address: vk::DeviceAddress,
    pub kind: MemoryKind,
    /// What it holds (debug names, the allocation log).
    name: &'static str,
    allocation: Option<Allocation>,
}

impl Buffer {
    /// The mapped bytes of a host-visible buffer (read-back buffers too).
    pub fn mapped_bytes(&self) -> Option<&[u8]> {
        self.allocation.as_ref().and_then(|a| a.mapped_slice())
    }

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&mut self) -> &mut [u8] {
        self.allocation.as_mut().and_then(|a| a.mapped_slice_mut()).expect("buffer is host visible")
    }
}

/// The one subresource of the SDK's images.
pub(crate) const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// The usage of every SDK-owned image.
const IMAGE_USAGE: vk::ImageUsageFlags = vk::ImageUsageFlags::from_raw(
    vk::ImageUsageFlags::STORAGE.as_raw() | vk::ImageUsageFlags::SAMPLED.as_raw() | vk::ImageUsageFlags::TRANSFER_DST.as_raw(),
);

/// An SDK-owned image (denoiser history), always used in GENERAL layout after creation.
pub(crate) struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub kind: MemoryKind,
    /// What it holds (debug names, the allocation log).
    name: &'static str,
    allocation: Option<Allocation>,
}

impl Image {
    /// As an `ImageInput` in GENERAL layout, for descriptor slots.
    pub fn input(&self) -> crate::types::ImageInput {
        crate::types::ImageInput {
            image: self.raw,
            view: self.view,
            format: self.format,
            width: self.width,
            height: self.height,
            layout: vk::ImageLayout::GENERAL,
            usage: IMAGE_USAGE,
        }
    }
}

pub(crate) struct Memory {
    device: ash::Device,
    allocator: Mutex<Option<Allocator>>,
    counts: Mutex<[AllocationCount; MEMORY_KIND_COUNT]>,
    /// The allocation log, while one is open.
    log: Mutex<Option<AllocationLog>>,
    /// The device's maxBufferSize: a larger buffer is refused before it reaches the driver.
    max_buffer_size: u64,
    /// Names buffers and images (VK_EXT_debug_utils), when the engine has it.
    debug: Option<ash::ext::debug_utils::Device>,
    /// Distinct queue families that use SDK memory: two or more make every buffer and image
    /// CONCURRENT over them (`InitSettings::queue_family_indices`).
    families: Vec<u32>,
    /// Test builds: allocations left before one fails (u64::MAX: none fails).
    #[cfg(feature = "fault-injection")]
    fail_in: std::sync::atomic::AtomicU64,
}

impl Memory {
    pub fn new(
        instance: &ash::Instance,
        device: &ash::Device,
        pdev: vk::PhysicalDevice,
        max_buffer_size: u64,
        debug: Option<ash::ext::debug_utils::Device>,
        families: Vec<u32>,
    ) -> Result<Memory> {
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: pdev,
            debug_settings: Default::default(),
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        })
        .map_err(|e| Error::OutOfMemory { what: "allocator", detail: e.to_string() })?;
        Ok(Memory {
            device: device.clone(),
            allocator: Mutex::new(Some(allocator)),
            counts: Mutex::new([AllocationCount::default(); MEMORY_KIND_COUNT]),
            log: Mutex::new(None),
            max_buffer_size,
            debug,
            families,
            #[cfg(feature = "fault-injection")]
            fail_in: std::sync::atomic::AtomicU64::new(u64::MAX),
        })
    }

    /// Test builds: the allocation after `after` more succeed fails with `OutOfMemory`
    /// (None: none fails).
    #[cfg(feature = "fault-injection")]
    pub fn inject_failure(&self, after: Option<u64>) {
        self.fail_in.store(after.unwrap_or(u64::MAX), std::sync::atomic::Ordering::SeqCst);
    }

    /// Counts an allocation down to an injected failure (test builds; a no-op otherwise).
    fn injected_failure(&self, what: &'static str) -> Result<()> {
        #[cfg(feature = "fault-injection")]
        {
            use std::sync::atomic::Ordering;
            let left = self.fail_in.load(Ordering::SeqCst);
            if left != u64::MAX {
                if left == 0 {
                    self.fail_in.store(u64::MAX, Ordering::SeqCst);
                    return Err(Error::OutOfMemory { what, detail: "injected failure".into() });
                }
                self.fail_in.store(left - 1, Ordering::SeqCst);
            }
        }
        let _ = what;
        Ok(())
    }

    pub fn create_buffer(
        &self,
        name: &'static str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        kind: MemoryKind,
    ) -> Result<Buffer> {
        self.injected_failure(name)?;
        let size = size.max(16);
        if size > self.max_buffer_size {
            return Err(Error::OutOfMemory {
                what: name,
                detail: format!("{size} bytes exceed the device's maxBufferSize {}", self.max_buffer_size),
            });
        }
        let usage = usage | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        let info = if self.families.len() >= 2 {
            info.sharing_mode(vk::SharingMode::CONCURRENT).queue_family_indices(&self.families)
        } else {
            info.sharing_mode(vk::SharingMode::EXCLUSIVE)
        };
        // SAFETY: valid create info; the buffer is destroyed in `destroy_buffer`.
        let raw = unsafe { self.device.create_buffer(&info, None) }.map_err(Error::vk("vkCreateBuffer"))?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { self.device.get_buffer_memory_requirements(raw) };
        let allocation = {
            let mut guard = self.allocator.lock();
            let allocator = guard.as_mut().ok_or_else(|| Error::Internal("allocator gone".into()))?;
            allocator.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
        };
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: `raw` was never bound or used.
                unsafe { self.device.destroy_buffer(raw, None) };
                return Err(Error::OutOfMemory { what: name, detail: e.to_string() });
            }
        };
        // SAFETY: the allocation was made for `raw`'s requirements and is unbound.
        if let Err(e) = unsafe { self.device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            // SAFETY: `raw` was never used.
            unsafe { self.device.destroy_buffer(raw, None) };
            let _ = self.allocator.lock().as_mut().map(|a| a.free(allocation));
            return Err(Error::Vulkan { call: "vkBindBufferMemory", result: e });
        }
        // SAFETY: `raw` is bound and was created with SHADER_DEVICE_ADDRESS usage.
        let address = unsafe { self.device.get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(raw)) };
        crate::gpu::device::name_object(self.debug.as_ref(), raw, name);
        self.note(true, kind, name, allocation.size());
        Ok(Buffer { raw, size, address, kind, name, allocation: Some(allocation) })
    }

    pub fn destroy_buffer(&self, mut buffer: Buffer) {
        // The buffer goes before the memory bound to it (a buffer must not outlive its memory).
        // SAFETY: the caller guarantees no pending GPU use (deferred destruction).
        unsafe { self.device.destroy_buffer(buffer.raw, None) };
        if let Some(allocation) = buffer.allocation.take() {
            self.note(false, buffer.kind, buffer.name, allocation.size());
            if let Some(a) = self.allocator.lock().as_mut() {
                if let Err(e) = a.free(allocation) {
                    log::error!("freeing a buffer failed: {e}");
                }
            }
        }
    }

    /// A 2D storage image in device memory, with its view (layout UNDEFINED until its first
    /// recording transitions it).
    pub fn create_image(
        &self,
        name: &'static str,
        format: vk::Format,
        width: u32,
        height: u32,
        kind: MemoryKind,
    ) -> Result<Image> {
        self.injected_failure(name)?;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width, height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(IMAGE_USAGE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let info = if self.families.len() >= 2 {
            info.sharing_mode(vk::SharingMode::CONCURRENT).queue_family_indices(&self.families)
        } else {
            info
        };
        // SAFETY: valid create info; destroyed in `destroy_image`.
        let raw = unsafe { self.device.create_image(&info, None) }.map_err(Error::vk("vkCreateImage"))?;
        // SAFETY: `raw` was just created on this device.
        let requirements = unsafe { self.device.get_image_memory_requirements(raw) };
        let allocation = self.allocator.lock().as_mut().ok_or_else(|| Error::Internal("allocator gone".into())).and_then(|a| {
            a.allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| Error::OutOfMemory { what: name, detail: e.to_string() })
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: `raw` was never bound or used.
                unsafe { self.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: the allocation was made for `raw`'s requirements and is unbound.
        let bound = unsafe { self.device.bind_image_memory(raw, allocation.memory(), allocation.offset()) }
            .map_err(Error::vk("vkBindImageMemory"))
            .and_then(|_| {
                let view_info = vk::ImageViewCreateInfo::default()
                    .image(raw)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(format)
                    .subresource_range(COLOR_RANGE);
                // SAFETY: `raw` is bound to memory; the view matches its format and one subresource.
                unsafe { self.device.create_image_view(&view_info, None) }.map_err(Error::vk("vkCreateImageView"))
            });
        let view = match bound {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: `raw` was never used (its view failed or was never made).
                unsafe { self.device.destroy_image(raw, None) };
                let _ = self.allocator.lock().as_mut().map(|a| a.free(allocation));
                return Err(e);
            }
        };
        crate::gpu::device::name_object(self.debug.as_ref(), raw, name);
        crate::gpu::device::name_object(self.debug.as_ref(), view, name);
        self.note(true, kind, name, allocation.size());
        Ok(Image { raw, view, format, width, height, kind, name, allocation: Some(allocation) })
    }

    pub fn destroy_image(&self, mut image: Image) {
        // View, then image, then the memory bound to it.
        // SAFETY: the caller guarantees no pending GPU use (deferred destruction).
        unsafe {
            self.device.destroy_image_view(image.view, None);
            self.device.destroy_image(image.raw, None);
        }
        if let Some(allocation) = image.allocation.take() {
            self.note(false, image.kind, image.name, allocation.size());
            if let Some(a) = self.allocator.lock().as_mut() {
                if let Err(e) = a.free(allocation) {
                    log::error!("freeing an image failed: {e}");
                }
            }
        }
    }

    /// Counts an allocation (`allocated`) or a free of `bytes` of `kind`, and logs it when a
    /// log is open.
    fn note(&self, allocated: bool, kind: MemoryKind, name: &str, bytes: u64) {
        let live = {
            let mut counts = self.counts.lock();
            let c = &mut counts[kind as usize];
            if allocated {
                c.count += 1;
                c.bytes += bytes;
            } else {
                c.count = c.count.saturating_sub(1);
                c.bytes = c.bytes.saturating_sub(bytes);
            }
            c.bytes
        };
        if let Some(log) = self.log.lock().as_mut() {
            log.event(if allocated { "alloc" } else { "free" }, kind, name, bytes, live);
        }
    }

    /// Opens the allocation log (false: one is open already).
    pub fn begin_log(&self, out: Box<dyn std::io::Write + Send>) -> bool {
        let mut log = self.log.lock();
        if log.is_some() {
            return false;
        }
        *log = Some(AllocationLog::new(out));
        true
    }

    /// Closes the allocation log and hands its writer back, or the first write error (None:
    /// none was open).
    pub fn end_log(&self) -> Option<std::io::Result<Box<dyn std::io::Write + Send>>> {
        self.log.lock().take().map(AllocationLog::finish)
    }

    pub fn allocations(&self) -> ResourceAllocations {
        let c = *self.counts.lock();
        ResourceAllocations {
            geometry_copies: c[MemoryKind::GeometryCopy as usize],
            blas: c[MemoryKind::Blas as usize],
            build_scratch: c[MemoryKind::BuildScratch as usize],
            tlas: c[MemoryKind::Tlas as usize],
            upload_rings: c[MemoryKind::UploadRing as usize],
            pipelines: c[MemoryKind::Pipeline as usize],
            cache: c[MemoryKind::Cache as usize],
            readback: c[MemoryKind::Readback as usize],
            denoiser: c[MemoryKind::Denoiser as usize],
            many_lights: c[MemoryKind::ManyLights as usize],
        }
    }

    /// Drops the allocator (its memory blocks) before the device goes away.
    pub fn shutdown(&self) {
        self.allocator.lock().take();
    }

    /// Forgets the allocator without freeing its memory: what a context dropped while the GPU
    /// may still use that memory does (a leak, never a use after free).
    pub fn leak(&self) {
        if let Some(a) = self.allocator.lock().take() {
            std::mem::forget(a);
        }
    }
}

/// A buffer that grows on demand; the old one is handed to `retire` (deferred destruction
/// when the GPU may still read it, immediate when the owner knows it is idle).
pub(crate) fn ensure_capacity(
    slot: &mut Option<Buffer>,
    needed: u64,
    make: impl FnOnce(u64) -> Result<Buffer>,
    retire: impl FnOnce(Buffer),
) -> Result<()> {
    if slot.as_ref().is_some_and(|b| b.size >= needed) {
        return Ok(());
    }
    // Grow by 1.5x so a scene that grows a little each frame does not reallocate each frame.
    let size = slot.as_ref().map_or(needed, |b| needed.max(b.size + b.size / 2));
    let fresh = make(size)?;
    if let Some(old) = slot.replace(fresh) {
        retire(old);
    }
    Ok(())
}
