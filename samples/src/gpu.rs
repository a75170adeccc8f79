//! Vulkan plumbing the sample's own passes (G-buffer, lighting) share: shader modules,
//! push-descriptor layouts, and constant buffers reused frame after frame.
use ash::vk;
use hybrid_rt_host::{Host, HostBuffer, HostImage, HostResult};

/// The sample's SPIR-V, compiled from shaders/sample by samples/build.rs.
pub(crate) mod spirv {
    include!(concat!(env!("OUT_DIR"), "/sample_shaders.rs"));
}

/// The layout the sample's sampled images are kept in: the G-buffer targets after their pass
/// (ready for the SDK) and the meshes' textures.
pub const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

fn vkerr(what: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{what}: {e:?}")
}

pub(crate) fn shader_module(host: &Host, spirv: &[u8]) -> HostResult<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|e| e.to_string())?;
    // SAFETY: valid SPIR-V words; the caller destroys the module after pipeline creation.
    unsafe { host.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }
        .map_err(vkerr("shader module"))
}

/// A push-descriptor set layout of `bindings` and a pipeline layout with it and `push_bytes`
/// of push constants (none when 0).
pub(crate) fn push_layout(
    host: &Host,
    bindings: &[vk::DescriptorSetLayoutBinding],
    push_bytes: u32,
    stages: vk::ShaderStageFlags,
) -> HostResult<(vk::DescriptorSetLayout, vk::PipelineLayout)> {
    let d = &host.device;
    unsafe {
        let set_layout = d
            .create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default()
                    .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
                    .bindings(bindings),
                None,
            )
            .map_err(vkerr("descriptor set layout"))?;
        let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_bytes }];
        let sets = [set_layout];
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&sets);
        let info = if push_bytes > 0 { info.push_constant_ranges(&ranges) } else { info };
        match d.create_pipeline_layout(&info, None) {
            Ok(layout) => Ok((set_layout, layout)),
            Err(e) => {
                d.destroy_descriptor_set_layout(set_layout, None);
                Err(vkerr("pipeline layout")(e))
            }
        }
    }
}

/// Host-visible buffers of one usage, one per frame slot (a frame in flight): written each
/// frame, reallocated only when the data outgrows them. A slot may be rewritten once the
/// frame that last used it has finished (its fence was waited on).
pub struct UploadSlots {
    usage: vk::BufferUsageFlags,
    slots: Vec<Option<HostBuffer>>,
}

impl UploadSlots {
    pub fn new(usage: vk::BufferUsageFlags) -> UploadSlots {
        UploadSlots { usage, slots: Vec::new() }
    }

    /// Writes `data` into `slot`'s buffer and returns it.
    pub fn write(&mut self, host: &Host, slot: usize, data: &[u8]) -> HostResult<vk::Buffer> {
        if self.slots.len() <= slot {
            self.slots.resize_with(slot + 1, || None);
        }
        let entry = &mut self.slots[slot];
        if entry.as_ref().is_some_and(|b| b.size >= data.len() as u64) {
            let b = entry.as_ref().expect("checked");
            host.write_buffer(b, data)?;
            return Ok(b.buffer);
        }
        // Grow by 1.5x so a scene that grows a little each frame does not reallocate each frame.
        let size = entry.as_ref().map_or(data.len(), |b| data.len().max(b.size as usize * 3 / 2));
        let mut padded = data.to_vec();
        padded.resize(size.max(4), 0);
        let fresh = host.buffer_with_data(&padded, self.usage)?;
        let buffer = fresh.buffer;
        if let Some(old) = entry.replace(fresh) {
            host.destroy_buffer(old);
        }
        Ok(buffer)
    }

    pub fn destroy(self, host: &Host) {
        for b in self.slots.into_iter().flatten() {
            host.destroy_buffer(b);
        }
    }
}

/// A compute shader over an image: `sampled` combined image samplers (bindings 0..), then
/// `storage` storage images, then one uniform buffer, all pushed per dispatch (no descriptor
/// pools to manage), 8x8 work groups. The lighting, composite and view passes are all this.
pub struct ComputePass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    sampler: vk::Sampler,
    push: ash::khr::push_descriptor::Device,
    constants: UploadSlots,
    sampled: u32,
    storage: u32,
}

impl ComputePass {
    pub(crate) fn new(host: &Host, spirv: &[u8], sampled: u32, storage: u32) -> HostResult<ComputePass> {
        let d = &host.device;
        // Nearest filtering: passes read texels at pixel centres (same size) or pick the
        // nearest texel of a smaller image (the view of the lidar camera).
        // SAFETY: plain object creation; everything is destroyed in `destroy`.
        let sampler = unsafe { d.create_sampler(&vk::SamplerCreateInfo::default(), None) }.map_err(vkerr("sampler"))?;
        let samplers = [sampler];
        let bindings: Vec<_> = (0..sampled + storage + 1)
            .map(|i| {
                let b = vk::DescriptorSetLayoutBinding::default()
                    .binding(i)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE);
                if i < sampled {
                    b.descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER).immutable_samplers(&samplers)
                } else if i < sampled + storage {
                    b.descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                } else {
                    b.descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                }
            })
            .collect();
        let (set_layout, layout) = push_layout(host, &bindings, 0, vk::ShaderStageFlags::COMPUTE)?;
        let module = shader_module(host, spirv)?;
        let stage =
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(module).name(c"main");
        // SAFETY: valid create info; the module is destroyed once the pipeline exists.
        let pipeline = unsafe {
            let p = d.create_compute_pipelines(
                vk::PipelineCache::null(),
                &[vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)],
                None,
            );
            d.destroy_shader_module(module, None);
            p.map_err(|(_, e)| format!("compute pipeline: {e:?}"))?[0]
        };
        let push = ash::khr::push_descriptor::Device::new(&host.instance, d);
        Ok(ComputePass {
            set_layout,
            layout,
            pipeline,
            sampler,
            push,
            constants: UploadSlots::new(vk::BufferUsageFlags::UNIFORM_BUFFER),
            sampled,
            storage,
        })
    }

    /// Records one dispatch over `width` x `height` pixels. `sampled` images are read in their
    /// given layouts, `storage` images are in GENERAL. `slot`: the frame-in-flight index whose
    /// constant buffer is rewritten (several dispatches of one frame: distinct slots).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn dispatch(
        &mut self,
        host: &Host,
        cmd: vk::CommandBuffer,
        slot: usize,
        sampled: &[(&HostImage, vk::ImageLayout)],
        storage: &[&HostImage],
        constants: &[u8],
        width: u32,
        height: u32,
    ) -> HostResult<()> {
        assert_eq!((sampled.len() as u32, storage.len() as u32), (self.sampled, self.storage), "bindings of the pass");
        let ubo = self.constants.write(host, slot, constants)?;
        let infos: Vec<[vk::DescriptorImageInfo; 1]> = sampled
            .iter()
            .map(|(i, layout)| [vk::DescriptorImageInfo { sampler: self.sampler, image_view: i.view, image_layout: *layout }])
            .chain(storage.iter().map(|i| {
                [vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: i.view,
                    image_layout: vk::ImageLayout::GENERAL,
                }]
            }))
            .collect();
        let ubo_info = [vk::DescriptorBufferInfo { buffer: ubo, offset: 0, range: constants.len() as u64 }];
        let mut writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                let ty = if (i as u32) < self.sampled {
                    vk::DescriptorType::COMBINED_IMAGE_SAMPLER
                } else {
                    vk::DescriptorType::STORAGE_IMAGE
                };
                vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(ty).image_info(info)
            })
            .collect();
        writes.push(
            vk::WriteDescriptorSet::default()
                .dst_binding(self.sampled + self.storage)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&ubo_info),
        );
        // SAFETY: cmd is recording; the images and buffer outlive the frame.
        unsafe {
            host.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            self.push.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &writes);
            host.device.cmd_dispatch(cmd, width.div_ceil(8), height.div_ceil(8), 1);
        }
        Ok(())
    }

    pub fn destroy(self, host: &Host) {
        self.constants.destroy(host);
        // SAFETY: the caller waited for every frame that used the pass.
        unsafe {
            host.device.destroy_pipeline(self.pipeline, None);
            host.device.destroy_pipeline_layout(self.layout, None);
            host.device.destroy_descriptor_set_layout(self.set_layout, None);
            host.device.destroy_sampler(self.sampler, None);
        }
    }
}

/// Timestamp queries around the sample's own passes in one frame slot (the SDK times its
/// tasks itself): `begin` at the start of the command buffer, `mark(label)` after each pass.
pub struct GpuTimer {
    pool: vk::QueryPool,
    labels: Vec<&'static str>,
    period_ns: f64,
}

const MAX_MARKS: u32 = 16;

impl GpuTimer {
    pub fn new(host: &Host) -> HostResult<GpuTimer> {
        // SAFETY: plain object creation, destroyed in `destroy`.
        let pool = unsafe {
            host.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(MAX_MARKS + 1),
                None,
            )
        }
        .map_err(vkerr("query pool"))?;
        let props = unsafe { host.instance.get_physical_device_properties(host.physical_device) };
        Ok(GpuTimer { pool, labels: Vec::new(), period_ns: props.limits.timestamp_period as f64 })
    }

    pub fn begin(&mut self, host: &Host, cmd: vk::CommandBuffer) {
        self.labels.clear();
        // SAFETY: cmd is recording, outside a render pass.
        unsafe {
            host.device.cmd_reset_query_pool(cmd, self.pool, 0, MAX_MARKS + 1);
            host.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, self.pool, 0);
        }
    }

    /// The time since the previous mark is `label`'s.
    pub fn mark(&mut self, host: &Host, cmd: vk::CommandBuffer, label: &'static str) {
        if self.labels.len() as u32 >= MAX_MARKS {
            return;
        }
        self.labels.push(label);
        // SAFETY: cmd is recording; the query was reset in `begin`.
        unsafe {
            host.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, self.pool, self.labels.len() as u32)
        };
    }

    /// After the frame's fence: (label, milliseconds) per mark; empty when nothing was timed.
    /// Forgets the marks, so a submission that recorded none (a skipped frame) reads nothing.
    pub fn read(&mut self, host: &Host) -> Vec<(&'static str, f64)> {
        if self.labels.is_empty() {
            return Vec::new();
        }
        let mut stamps = vec![0u64; self.labels.len() + 1];
        // SAFETY: the frame finished (its fence was waited on), so every query is available.
        let ok = unsafe { host.device.get_query_pool_results(self.pool, 0, &mut stamps, vk::QueryResultFlags::TYPE_64) };
        let labels = std::mem::take(&mut self.labels);
        if ok.is_err() {
            return Vec::new();
        }
        labels
            .iter()
            .enumerate()
            .map(|(i, l)| (*l, stamps[i + 1].saturating_sub(stamps[i]) as f64 * self.period_ns * 1e-6))
            .collect()
    }

    pub fn destroy(self, host: &Host) {
        // SAFETY: no frame using the pool is in flight.
        unsafe { host.device.destroy_query_pool(self.pool, None) };
    }
}
