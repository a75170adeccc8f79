//! Push-descriptor writes shared by the passes: what each binding of a set holds.
use crate::gpu::commands::{Commands, Descriptor};
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
pub(crate) fn push(cmd: &Commands, bind_point: vk::PipelineBindPoint, layout: vk::PipelineLayout, slots: &[Slot<'_>]) {
    let set = slots
        .iter()
        .map(|s| match s {
            Slot::Tlas(a) => Descriptor::Tlas(*a),
            Slot::Sampled(i) => Descriptor::Sampled(i.view, i.layout),
            Slot::Storage(i) => Descriptor::Storage(i.view, i.layout),
            Slot::Uniform(u) => Descriptor::Uniform(*u),
        })
        .collect();
    cmd.push_descriptors(bind_point, layout, set);
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
