//! One module per GPU pass. A pass owns its pipelines and records itself: it declares what it
//! reads and writes to the hazard tracker (which emits the barriers) and never reaches into
//! another pass.
pub(crate) mod ao;
pub(crate) mod cache_ops;
pub(crate) mod constants;
pub(crate) mod debug;
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
}
