//! The commands of one build, kept until the build has succeeded and only then recorded into
//! the engine's command buffer.
//!
//! A build allocates as it goes (geometry copies, BLASes, scratch, caches, the upload ring), so
//! it can fail after some of its commands are known. Recording them straight into the engine's
//! buffer would leave that buffer naming objects the failed build destroyed: the engine could
//! not even end it, and would lose everything it had recorded there itself this frame. Instead
//! every pass records into a [`Commands`] list, and `build_gpu_task` replays the list into the
//! engine's buffer once nothing can fail any more — a failed build records nothing at all.
//!
//! The list owns everything a command points to (push constants, descriptor writes, barrier
//! and build structures), so recording is safe code; the one unsafe step is the replay.
use super::device::Device;
use super::sync::Use;
use crate::gpu::upload::Upload;
use ash::vk;
use std::cell::RefCell;

/// One descriptor of a push-descriptor set, owned (see `passes::descriptors`).
#[derive(Clone, Copy)]
pub(crate) enum Descriptor {
    Tlas(vk::AccelerationStructureKHR),
    Sampled(vk::ImageView, vk::ImageLayout),
    Storage(vk::ImageView, vk::ImageLayout),
    Uniform(Upload),
}

/// One acceleration-structure build of one geometry: `info` without its geometry pointer,
/// which the replay sets.
pub(crate) struct AsBuild {
    pub info: vk::AccelerationStructureBuildGeometryInfoKHR<'static>,
    pub geometry: vk::AccelerationStructureGeometryKHR<'static>,
    pub range: vk::AccelerationStructureBuildRangeInfoKHR,
}

enum Command {
    CopyBuffer { src: vk::Buffer, dst: vk::Buffer, regions: Vec<vk::BufferCopy> },
    FillBuffer { buffer: vk::Buffer, offset: u64, size: u64, data: u32 },
    BindPipeline { bind_point: vk::PipelineBindPoint, pipeline: vk::Pipeline },
    PushConstants { layout: vk::PipelineLayout, stages: vk::ShaderStageFlags, bytes: Vec<u8> },
    PushDescriptors { bind_point: vk::PipelineBindPoint, layout: vk::PipelineLayout, set: Vec<Descriptor> },
    Dispatch([u32; 3]),
    TraceRays { regions: Box<[vk::StridedDeviceAddressRegionKHR; 4]>, size: [u32; 3] },
    MemoryBarrier(vk::MemoryBarrier2<'static>),
    ImageBarriers(Vec<vk::ImageMemoryBarrier2<'static>>),
    ClearColorImage { image: vk::Image, layout: vk::ImageLayout, color: vk::ClearColorValue, range: vk::ImageSubresourceRange },
    BuildAccelerationStructures(Vec<AsBuild>),
    CopyAccelerationStructure(vk::CopyAccelerationStructureInfoKHR<'static>),
    WriteCompactedSizes { structures: Vec<vk::AccelerationStructureKHR>, pool: vk::QueryPool },
    ResetQueryPool { pool: vk::QueryPool, first: u32, count: u32 },
    WriteTimestamp { pool: vk::QueryPool, query: u32 },
    BeginLabel(std::ffi::CString),
    EndLabel,
}

/// The commands of one build, in order (see the module doc). Recording takes `&self`, so the
/// passes share one list as they shared the command buffer handle.
#[derive(Default)]
pub(crate) struct Commands {
    list: RefCell<Vec<Command>>,
}

impl Commands {
    fn push(&self, c: Command) {
        self.list.borrow_mut().push(c);
    }

    pub fn copy_buffer(&self, src: vk::Buffer, dst: vk::Buffer, regions: &[vk::BufferCopy]) {
        if !regions.is_empty() {
            self.push(Command::CopyBuffer { src, dst, regions: regions.to_vec() });
        }
    }

    pub fn fill_buffer(&self, buffer: vk::Buffer, offset: u64, size: u64, data: u32) {
        self.push(Command::FillBuffer { buffer, offset, size, data });
    }

    pub fn bind_pipeline(&self, bind_point: vk::PipelineBindPoint, pipeline: vk::Pipeline) {
        self.push(Command::BindPipeline { bind_point, pipeline });
    }

    /// Push constants at offset 0 of `layout`.
    pub fn push_constants(&self, layout: vk::PipelineLayout, stages: vk::ShaderStageFlags, bytes: &[u8]) {
        self.push(Command::PushConstants { layout, stages, bytes: bytes.to_vec() });
    }

    /// Pushes `set` as set 0 of `layout`, in binding order.
    pub fn push_descriptors(&self, bind_point: vk::PipelineBindPoint, layout: vk::PipelineLayout, set: Vec<Descriptor>) {
        self.push(Command::PushDescriptors { bind_point, layout, set });
    }

    pub fn dispatch(&self, x: u32, y: u32, z: u32) {
        self.push(Command::Dispatch([x, y, z]));
    }

    /// Raygen, miss, hit and callable regions, then the launch size.
    pub fn trace_rays(&self, regions: [vk::StridedDeviceAddressRegionKHR; 4], width: u32, height: u32) {
        self.push(Command::TraceRays { regions: Box::new(regions), size: [width, height, 1] });
    }

    /// A global memory barrier from `src` to `dst`.
    pub fn barrier(&self, src: Use, dst: Use) {
        self.push(Command::MemoryBarrier(
            vk::MemoryBarrier2::default()
                .src_stage_mask(src.stages)
                .src_access_mask(src.access)
                .dst_stage_mask(dst.stages)
                .dst_access_mask(dst.access),
        ));
    }

    pub fn image_barriers(&self, barriers: Vec<vk::ImageMemoryBarrier2<'static>>) {
        if !barriers.is_empty() {
            self.push(Command::ImageBarriers(barriers));
        }
    }

    pub fn clear_color_image(
        &self,
        image: vk::Image,
        layout: vk::ImageLayout,
        color: vk::ClearColorValue,
        range: vk::ImageSubresourceRange,
    ) {
        self.push(Command::ClearColorImage { image, layout, color, range });
    }

    /// Builds in one call, so the driver can overlap them.
    pub fn build_acceleration_structures(&self, builds: Vec<AsBuild>) {
        if !builds.is_empty() {
            self.push(Command::BuildAccelerationStructures(builds));
        }
    }

    pub fn copy_acceleration_structure(&self, info: vk::CopyAccelerationStructureInfoKHR<'static>) {
        self.push(Command::CopyAccelerationStructure(info));
    }

    /// Writes the compacted sizes of `structures` to queries 0.. of `pool`.
    pub fn write_compacted_sizes(&self, structures: Vec<vk::AccelerationStructureKHR>, pool: vk::QueryPool) {
        self.push(Command::WriteCompactedSizes { structures, pool });
    }

    pub fn reset_query_pool(&self, pool: vk::QueryPool, first: u32, count: u32) {
        self.push(Command::ResetQueryPool { pool, first, count });
    }

    /// A timestamp once earlier work has finished (BOTTOM_OF_PIPE).
    pub fn write_timestamp(&self, pool: vk::QueryPool, query: u32) {
        self.push(Command::WriteTimestamp { pool, query });
    }

    pub fn begin_label(&self, text: std::ffi::CString) {
        self.push(Command::BeginLabel(text));
    }

    pub fn end_label(&self) {
        self.push(Command::EndLabel);
    }

    /// Records the list into `cmd`, in order, and empties it.
    ///
    /// # Safety
    /// `cmd` is in the recording state, outside a render pass, and from a pool whose queue
    /// family supports compute; every object the commands name is alive (the build that made
    /// the list succeeded and its objects are kept until its ticket comes back).
    pub unsafe fn replay(&self, device: &Device, cmd: vk::CommandBuffer) {
        let d = &device.raw;
        for c in self.list.borrow_mut().drain(..) {
            // SAFETY: each call — the caller's contract above; every pointer passed is into
            // the command's own data, alive for the call.
            unsafe {
                match c {
                    Command::CopyBuffer { src, dst, regions } => d.cmd_copy_buffer(cmd, src, dst, &regions),
                    Command::FillBuffer { buffer, offset, size, data } => d.cmd_fill_buffer(cmd, buffer, offset, size, data),
                    Command::BindPipeline { bind_point, pipeline } => d.cmd_bind_pipeline(cmd, bind_point, pipeline),
                    Command::PushConstants { layout, stages, bytes } => d.cmd_push_constants(cmd, layout, stages, 0, &bytes),
                    Command::PushDescriptors { bind_point, layout, set } => {
                        push_descriptors(device, cmd, bind_point, layout, &set)
                    }
                    Command::Dispatch([x, y, z]) => d.cmd_dispatch(cmd, x, y, z),
                    Command::TraceRays { regions, size: [w, h, depth] } => {
                        let [raygen, miss, hit, callable] = &*regions;
                        device.rt.cmd_trace_rays(cmd, raygen, miss, hit, callable, w, h, depth)
                    }
                    Command::MemoryBarrier(b) => {
                        d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(std::slice::from_ref(&b)))
                    }
                    Command::ImageBarriers(b) => {
                        d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b))
                    }
                    Command::ClearColorImage { image, layout, color, range } => {
                        d.cmd_clear_color_image(cmd, image, layout, &color, std::slice::from_ref(&range))
                    }
                    Command::BuildAccelerationStructures(builds) => {
                        let infos: Vec<_> = builds.iter().map(|b| b.info.geometries(std::slice::from_ref(&b.geometry))).collect();
                        let ranges: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> =
                            builds.iter().map(|b| std::slice::from_ref(&b.range)).collect();
                        device.accel.cmd_build_acceleration_structures(cmd, &infos, &ranges)
                    }
                    Command::CopyAccelerationStructure(info) => device.accel.cmd_copy_acceleration_structure(cmd, &info),
                    Command::WriteCompactedSizes { structures, pool } => {
                        device.accel.cmd_write_acceleration_structures_properties(
                            cmd,
                            &structures,
                            vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                            pool,
                            0,
                        )
                    }
                    Command::ResetQueryPool { pool, first, count } => d.cmd_reset_query_pool(cmd, pool, first, count),
                    Command::WriteTimestamp { pool, query } => {
                        // BOTTOM_OF_PIPE: the stamp is written once earlier work has finished,
                        // so intervals measure their own work. (ALL_COMMANDS means the same
                        // here but draws a best-practices warning.)
                        d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, pool, query)
                    }
                    Command::BeginLabel(text) => {
                        if let Some(debug) = &device.debug {
                            debug.cmd_begin_debug_utils_label(cmd, &vk::DebugUtilsLabelEXT::default().label_name(&text))
                        }
                    }
                    Command::EndLabel => {
                        if let Some(debug) = &device.debug {
                            debug.cmd_end_debug_utils_label(cmd)
                        }
                    }
                }
            }
        }
    }
}

/// Records one push-descriptor set.
///
/// # Safety
/// As [`Commands::replay`]; `layout`'s set 0 has these bindings, in this order.
unsafe fn push_descriptors(
    device: &Device,
    cmd: vk::CommandBuffer,
    bind_point: vk::PipelineBindPoint,
    layout: vk::PipelineLayout,
    set: &[Descriptor],
) {
    // Every write points into these arrays, one element per descriptor.
    let tlas: Vec<[vk::AccelerationStructureKHR; 1]> =
        set.iter().map(|s| [if let Descriptor::Tlas(a) = s { *a } else { vk::AccelerationStructureKHR::null() }]).collect();
    let images: Vec<[vk::DescriptorImageInfo; 1]> = set
        .iter()
        .map(|s| match *s {
            Descriptor::Sampled(view, layout) | Descriptor::Storage(view, layout) => {
                [vk::DescriptorImageInfo { sampler: vk::Sampler::null(), image_view: view, image_layout: layout }]
            }
            _ => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = set
        .iter()
        .map(|s| match *s {
            Descriptor::Uniform(u) => [vk::DescriptorBufferInfo { buffer: u.buffer, offset: u.offset, range: u.size }],
            _ => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let mut as_writes: Vec<_> =
        tlas.iter().map(|t| vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(t)).collect();
    let writes: Vec<vk::WriteDescriptorSet> = set
        .iter()
        .zip(as_writes.iter_mut())
        .enumerate()
        .map(|(binding, (s, as_write))| {
            let w = vk::WriteDescriptorSet::default().dst_binding(binding as u32);
            match s {
                Descriptor::Tlas(_) => {
                    let mut w = w.descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR).push_next(as_write);
                    w.descriptor_count = 1;
                    w
                }
                Descriptor::Sampled(..) => {
                    w.descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER).image_info(&images[binding])
                }
                Descriptor::Storage(..) => w.descriptor_type(vk::DescriptorType::STORAGE_IMAGE).image_info(&images[binding]),
                Descriptor::Uniform(_) => w.descriptor_type(vk::DescriptorType::UNIFORM_BUFFER).buffer_info(&buffers[binding]),
            }
        })
        .collect();
    // SAFETY: every referenced array outlives this call; the caller vouches for the layout.
    unsafe { device.push.cmd_push_descriptor_set(cmd, bind_point, layout, 0, &writes) };
}
