//! Vulkan plumbing the sample's own passes (G-buffer, lighting) share: shader modules,
//! push-descriptor layouts, and constant buffers reused frame after frame.
use ash::vk;
use hybrid_rt_testkit::host::{Host, HostBuffer, HostResult};

/// The sample's SPIR-V, compiled from shaders/sample by samples/build.rs.
pub(crate) mod spirv {
    include!(concat!(env!("OUT_DIR"), "/sample_shaders.rs"));
}

fn vkerr(what: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{what}: {e:?}")
}

pub(crate) fn shader_module(host: &Host, spirv: &[u8]) -> HostResult<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|e| e.to_string())?;
    // SAFETY: valid SPIR-V words; the caller destroys the module after pipeline creation.
    unsafe { host.device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }.map_err(vkerr("shader module"))
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
                &vk::DescriptorSetLayoutCreateInfo::default().flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR).bindings(bindings),
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
