//! The instance table: one record per TLAS instance slot, indexed in shaders by
//! gl_InstanceCustomIndexEXT. Written into the working set's upload ring for each recording
//! that traces, so it always matches the TLAS that recording uses.
use bytemuck::{Pod, Zeroable};

/// `InstanceGpu` in shaders/include/cache.glsl (std430, 128 bytes).
#[derive(Clone, Copy, Pod, Zeroable, Default)]
#[repr(C)]
pub(crate) struct InstanceGpu {
    pub layout_addr: u64,
    pub cache_addr: u64,
    pub initial_color: [f32; 4],
    pub surfel_type: u32,
    pub triangle_count: u32,
    pub flags: u32,
    pub sample_count: u32,
    /// Rows of the object-to-world 3x4 transform.
    pub object_to_world: [[f32; 4]; 3],
    pub vertex_addr: u64,
    pub index_addr: u64,
    pub vertex_stride: u32,
    /// 0 (non-indexed), 2 or 4.
    pub index_size: u32,
    pub max_resolution: u32,
    pub pad: u32,
}

pub(crate) const HAS_CACHE: u32 = 1;

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[test]
    fn layout_matches_glsl_std430() {
        assert_eq!(offset_of!(InstanceGpu, cache_addr), 8);
        assert_eq!(offset_of!(InstanceGpu, initial_color), 16);
        assert_eq!(offset_of!(InstanceGpu, surfel_type), 32);
        assert_eq!(offset_of!(InstanceGpu, sample_count), 44);
        assert_eq!(offset_of!(InstanceGpu, object_to_world), 48);
        assert_eq!(offset_of!(InstanceGpu, vertex_addr), 96);
        assert_eq!(offset_of!(InstanceGpu, vertex_stride), 112);
        assert_eq!(size_of::<InstanceGpu>(), 128);
    }
}
