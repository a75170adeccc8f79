//! Push-descriptor writes shared by the passes: what each binding of a set holds.
use crate::gpu::upload::Upload;
use crate::types::ImageInput;
use ash::vk;

/// One descriptor of a push-descriptor set, in binding order.
pub(crate) enum Slot<'a> {
    Tlas(vk::AccelerationStructureKHR),
    Sampled(&'a ImageInput),
    Storage(&'a ImageInput),
    Uniform(Upload),
}

/// Pushes `slots` as set 0 of `layout` at `bind_point`.
pub(crate) fn push(
    device: &crate::gpu::device::Device,
    cmd: vk::CommandBuffer,
    bind_point: vk::PipelineBindPoint,
    layout: vk::PipelineLayout,
    slots: &[Slot<'_>],
) {
    let mut tlas = Vec::new();
    let mut images = Vec::new();
    let mut buffers = Vec::new();
    for s in slots {
        match s {
            Slot::Tlas(a) => tlas.push([*a]),
            Slot::Sampled(i) | Slot::Storage(i) => images.push([vk::DescriptorImageInfo {
                sampler: vk::Sampler::null(),
                image_view: i.view,
                image_layout: i.layout,
            }]),
            Slot::Uniform(u) => buffers.push([vk::DescriptorBufferInfo { buffer: u.buffer, offset: u.offset, range: u.size }]),
        }
    }
    let mut as_writes: Vec<_> =
        tlas.iter().map(|t| vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(t)).collect();
    let (mut ii, mut bi) = (0, 0);
    let mut as_iter = as_writes.iter_mut();
    let writes: Vec<vk::WriteDescriptorSet> = slots
        .iter()
        .enumerate()
        .map(|(binding, s)| {
            let w = vk::WriteDescriptorSet::default().dst_binding(binding as u32);
            match s {
                Slot::Tlas(_) => {
                    let mut w = w
                        .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                        .push_next(as_iter.next().expect("one per TLAS slot"));
                    w.descriptor_count = 1;
                    w
                }
                Slot::Sampled(_) => {
                    ii += 1;
                    w.descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER).image_info(&images[ii - 1])
                }
                Slot::Storage(_) => {
                    ii += 1;
                    w.descriptor_type(vk::DescriptorType::STORAGE_IMAGE).image_info(&images[ii - 1])
                }
                Slot::Uniform(_) => {
                    bi += 1;
                    w.descriptor_type(vk::DescriptorType::UNIFORM_BUFFER).buffer_info(&buffers[bi - 1])
                }
            }
        })
        .collect();
    // SAFETY: every referenced array outlives this call; the layout has these bindings.
    unsafe { device.push.cmd_push_descriptor_set(cmd, bind_point, layout, 0, &writes) };
}

/// An optional input image, or a stand-in when it is absent: a push-descriptor binding must
/// hold a valid view even when the shader (told by a flag) does not read it.
pub(crate) fn optional_or<'a>(image: &'a ImageInput, stand_in: &'a ImageInput) -> &'a ImageInput {
    if image.image != vk::Image::null() {
        image
    } else {
        stand_in
    }
}
