//! The instance table: one record per TLAS instance slot, indexed in shaders by
//! gl_InstanceCustomIndexEXT, holding what a hit needs by device address — the geometry copy,
//! the surfel layout and the instance's cache. Written into the working set's upload ring for
//! each recording that traces, so it always matches the TLAS that recording uses.
use super::Scene;
use bytemuck::{Pod, Zeroable};

/// `InstanceGpu` in shaders/include/cache.glsl (std430, 224 bytes).
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
    /// Alpha-tested geometry: its texture coordinates and alpha texels in the copy (0: opaque).
    pub uv_addr: u64,
    pub alpha_addr: u64,
    /// The alpha texture's width, height and row pitch in u32 words; the cutoff.
    pub alpha_width: u32,
    pub alpha_height: u32,
    pub alpha_pitch: u32,
    pub alpha_cutoff: f32,
    /// Diffuse albedo for relighting and hit lighting (rgb, unused).
    pub albedo: [f32; 4],
    /// Emission for relighting and hit lighting (rgb, unused).
    pub emission: [f32; 4],
    /// Coloured geometry: its vertex colours in the copy (RGBA8, 0: none).
    pub color_addr: u64,
    /// Albedo-textured geometry: the texture's copy (RGBA8 sRGB, 0: none) and its size.
    pub albedo_addr: u64,
    pub albedo_width: u32,
    pub albedo_height: u32,
    pub pad2: [u32; 2],
}

pub(crate) const HAS_CACHE: u32 = 1;

/// One record per instance slot (empty slots are zero).
pub(crate) fn instance_table(scene: &Scene) -> Vec<InstanceGpu> {
    let mut table = vec![InstanceGpu::default(); scene.instances.slot_count().max(1)];
    for (h, rec) in scene.instances.iter() {
        let (Some(p), Ok(i)) = (rec.placement, scene.instances.index_of(h)) else { continue };
        let Ok(g) = scene.geometries.get(p.geometry) else { continue };
        let surfel = g.surfel.as_ref();
        let c = p.initial_tile_color;
        let m = p.transform.matrix3;
        let tr = p.transform.translation;
        let copy = g.copy.as_ref().map_or(0, |b| b.address);
        table[i as usize] = InstanceGpu {
            object_to_world: [
                [m.x_axis.x, m.y_axis.x, m.z_axis.x, tr.x],
                [m.x_axis.y, m.y_axis.y, m.z_axis.y, tr.y],
                [m.x_axis.z, m.y_axis.z, m.z_axis.z, tr.z],
            ],
            vertex_addr: copy,
            // The SDK's copies are compact: 12-byte positions and 32-bit indices.
            index_addr: g.layout.map_or(0, |l| copy + l.index_offset()),
            vertex_stride: 12,
            index_size: 4,
            max_resolution: surfel.map_or(1, |s| s.max_resolution),
            pad: 0,
            uv_addr: g.layout.filter(|l| l.has_uvs).map_or(0, |l| copy + l.uv_offset()),
            alpha_addr: g.layout.filter(|l| l.alpha_tested()).map_or(0, |l| copy + l.alpha_offset()),
            alpha_width: g.layout.map_or(0, |l| l.alpha_width),
            alpha_height: g.layout.map_or(0, |l| l.alpha_height),
            alpha_pitch: g.layout.map_or(0, |l| l.alpha_pitch_words()),
            alpha_cutoff: g.layout.map_or(0.0, |l| f32::from_bits(l.alpha_cutoff_bits)),
            layout_addr: surfel.map_or(0, |s| s.buffer.address),
            cache_addr: p.cache.map_or(0, |(r, _)| r.address),
            initial_color: [c[0], c[1], c[2], 0.0],
            surfel_type: surfel.map_or(0, |s| s.surfel_type as u32),
            triangle_count: g.layout.map_or(0, |l| l.primitive_count),
            flags: if p.cache.is_some() && surfel.is_some() { HAS_CACHE } else { 0 },
            sample_count: surfel.map_or(0, |s| s.sample_count),
            albedo: [p.albedo[0], p.albedo[1], p.albedo[2], 0.0],
            emission: [p.emission[0], p.emission[1], p.emission[2], 0.0],
            color_addr: g.layout.filter(|l| l.has_colors).map_or(0, |l| copy + l.color_offset()),
            albedo_addr: g.layout.filter(|l| l.albedo_width > 0).map_or(0, |l| copy + l.albedo_offset()),
            albedo_width: g.layout.map_or(0, |l| l.albedo_width),
            albedo_height: g.layout.map_or(0, |l| l.albedo_height),
            pad2: [0; 2],
        };
    }
    table
}

/// Bytes of the table (for sizing the upload ring before it is written).
pub(crate) fn instance_table_bytes(scene: &Scene) -> u64 {
    (scene.instances.slot_count().max(1) * std::mem::size_of::<InstanceGpu>()) as u64
}

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
        assert_eq!(offset_of!(InstanceGpu, uv_addr), 128);
        assert_eq!(offset_of!(InstanceGpu, alpha_width), 144);
        assert_eq!(offset_of!(InstanceGpu, albedo), 160);
        assert_eq!(offset_of!(InstanceGpu, emission), 176);
        assert_eq!(offset_of!(InstanceGpu, color_addr), 192);
        assert_eq!(offset_of!(InstanceGpu, albedo_width), 208);
        assert_eq!(size_of::<InstanceGpu>(), 224);
    }
}
