//! A placed geometry and its TLAS record.
use crate::cache::pool::CacheRange;
use crate::types::GeometryHandle;
use ash::vk;
use glam::Affine3A;

pub(crate) struct InstanceRecord {
    /// Some once a register task has been built (and until a remove task).
    pub placement: Option<Placement>,
    /// The engine's debug name (`ExecuteContext::set_instance_name`).
    pub name: Option<String>,
    /// The serial of the last ticket that used it (see `InitSettings::cache_budget_bytes`),
    /// or of the build that placed it.
    pub last_used: u64,
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct Placement {
    pub geometry: GeometryHandle,
    pub transform: Affine3A,
    pub mask: u8,
    /// Kept for the direct-lighting cache, which fills a new instance's cache with it.
    pub initial_tile_color: [f32; 3],
    /// What `RelightCacheTask` lights its cache with.
    pub albedo: [f32; 3],
    /// What relighting and hit lighting add as its emission.
    pub emission: [f32; 3],
    /// This instance's cache and the layout id it was made for.
    pub cache: Option<(CacheRange, u64)>,
    /// The cache budget took its cache (it gets one again when it is used).
    pub evicted: bool,
}

/// The TLAS record of an instance. `custom_index` is the instance's slot, so shaders can find
/// per-instance data in a table indexed by gl_InstanceCustomIndexEXT.
pub(crate) fn tlas_record(
    p: &Placement,
    custom_index: u32,
    blas_address: vk::DeviceAddress,
) -> vk::AccelerationStructureInstanceKHR {
    let m = p.transform.matrix3;
    let t = p.transform.translation;
    // Row-major 3x4, as VkTransformMatrixKHR wants.
    let matrix = [
        m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x, m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y, m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z,
    ];
    vk::AccelerationStructureInstanceKHR {
        transform: vk::TransformMatrixKHR { matrix },
        instance_custom_index_and_mask: vk::Packed24_8::new(custom_index & 0xff_ffff, p.mask),
        instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
            0,
            vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
        ),
        acceleration_structure_reference: vk::AccelerationStructureReferenceKHR { device_handle: blas_address },
    }
}

pub(crate) fn instance_bytes(records: &[vk::AccelerationStructureInstanceKHR]) -> &[u8] {
    // SAFETY: VkAccelerationStructureInstanceKHR is 64 bytes of plain data with no padding.
    unsafe { std::slice::from_raw_parts(records.as_ptr() as *const u8, std::mem::size_of_val(records)) }
}
