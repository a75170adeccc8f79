//! One module per GPU pass. A pass owns its pipelines and records itself: it declares what it
//! reads and writes to the hazard tracker (which emits the barriers) and never reaches into
//! another pass.
pub(crate) mod ao;
pub(crate) mod cache_ops;
pub(crate) mod constants;
pub(crate) mod debug;
pub(crate) mod denoise;
pub(crate) mod descriptors;
pub(crate) mod diffuse;
pub(crate) mod inject;
pub(crate) mod program;
pub(crate) mod shadow;
pub(crate) mod specular;
pub(crate) mod transfer;

use crate::gpu::sync::Hazards;
use crate::gpu::upload::UploadRing;
use ash::vk;

/// What a pass needs while it records.
pub(crate) struct Recording<'a> {
    pub device: &'a crate::gpu::device::Device,
    pub cmd: vk::CommandBuffer,
    pub ring: &'a mut UploadRing,
    pub hazards: &'a mut Hazards,
    pub tlas: vk::AccelerationStructureKHR,
    /// Per-ticket random seed (the ticket serial), so successive frames get fresh samples.
    pub seed: u32,
    /// Device address of this recording's instance table (0 when the recording has none).
    pub instance_table: u64,
    /// Bench only: trace with the programs' floor pipelines (empty hit and miss shaders).
    pub floor: bool,
}

/// The bindings a G-buffer trace starts with: TLAS, depth, normals, output image, constants;
/// a pass appends its own after them.
pub(crate) fn gbuffer_bindings(
    sampler: ash::vk::Sampler,
    extra: &[crate::gpu::pipeline::Binding],
) -> Vec<crate::gpu::pipeline::Binding> {
    use crate::gpu::pipeline::Binding;
    use ash::vk::DescriptorType as T;
    let mut b = vec![
        Binding { ty: T::ACCELERATION_STRUCTURE_KHR, sampler: None },
        Binding { ty: T::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
        Binding { ty: T::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
        Binding { ty: T::STORAGE_IMAGE, sampler: None },
        Binding { ty: T::UNIFORM_BUFFER, sampler: None },
    ];
    b.extend(extra.iter().map(|x| Binding { ty: x.ty, sampler: x.sampler }));
    b
}

/// The slots matching `gbuffer_bindings`.
pub(crate) fn gbuffer_slots<'a>(
    tlas: ash::vk::AccelerationStructureKHR,
    common: &'a crate::types::TraceCommon,
    output: &'a crate::types::ImageInput,
    constants: crate::gpu::upload::Upload,
) -> Vec<descriptors::Slot<'a>> {
    use descriptors::Slot;
    vec![
        Slot::Tlas(tlas),
        Slot::Sampled(&common.depth.image),
        Slot::Sampled(&common.normals.image),
        Slot::Storage(output),
        Slot::Uniform(constants),
    ]
}
