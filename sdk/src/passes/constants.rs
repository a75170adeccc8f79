//! GPU twins of the std140 blocks in shaders/include/*.glsl. Each struct here has exactly one
//! GLSL counterpart; the tests at the bottom pin sizes and offsets.
use crate::types::{DepthType, EnvironmentInput, LightInfo, LightType, NormalSpace, RayOffsetType, TraceCommon};
use bytemuck::{Pod, Zeroable};

/// `TraceCommon` in shaders/include/common.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct TraceCommonGpu {
    pub clip_to_world: [f32; 16],
    pub view_to_world: [f32; 16],
    pub viewport: [f32; 4],
    pub depth_range: [f32; 4],
    pub modes: [u32; 4],
    pub offset_world: [f32; 4],
    pub offset_camera: [f32; 4],
    pub frame: [u32; 4],
    pub world_to_clip: [f32; 16],
    pub normal_to_world: [f32; 16],
    pub roughness_mask: [f32; 4],
    pub roughness: [f32; 4],
}

/// `EnvironmentGpu` in shaders/include/environment.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct EnvironmentGpu {
    pub world_to_env: [f32; 16],
    pub params: [f32; 4],
}

impl EnvironmentGpu {
    pub fn new(e: &EnvironmentInput) -> EnvironmentGpu {
        EnvironmentGpu {
            world_to_env: glam::Mat4::from_mat3(e.rotation.transpose()).to_cols_array(),
            params: [e.intensity, e.has_image() as u32 as f32, 0.0, 0.0],
        }
    }
}

/// `AoConstants` in shaders/include/ao.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct AoConstantsGpu {
    pub common: TraceCommonGpu,
    pub params: [f32; 4],
    pub counts: [u32; 4],
}

impl TraceCommonGpu {
    /// `seed` varies per ticket; `mask` selects which instances the rays see.
    pub fn new(c: &TraceCommon, seed: u32, mask: u8) -> TraceCommonGpu {
        let view_to_world = c.camera.world_to_view.inverse();
        let clip_to_world = (c.camera.view_to_clip * c.camera.world_to_view).inverse();
        let vp = &c.viewport;
        let (min_d, max_d) = if vp.min_depth == 0.0 && vp.max_depth == 0.0 { (0.0, 1.0) } else { (vp.min_depth, vp.max_depth) };
        let o = &c.ray_offset;
        let normal_to_world = match c.normals.space {
            NormalSpace::World => None,
            NormalSpace::View => Some(glam::Mat3::from_mat4(view_to_world)),
            NormalSpace::Custom => Some(c.normals.normal_to_world),
        };
        let r = &c.roughness;
        TraceCommonGpu {
            clip_to_world: clip_to_world.to_cols_array(),
            view_to_world: view_to_world.to_cols_array(),
            viewport: [vp.x as f32, vp.y as f32, vp.width as f32, vp.height as f32],
            depth_range: [
                min_d,
                max_d,
                background_depth(&c.camera.view_to_clip, min_d, max_d),
                (c.input_mask.image != ash::vk::Image::null()) as u32 as f32,
            ],
            modes: [
                match c.depth.depth_type {
                    DepthType::ClipSpace => 0,
                    DepthType::WorldPosition => 1,
                },
                c.normals.normal_type as u32,
                normal_to_world.is_some() as u32,
                match o.offset_type {
                    RayOffsetType::Disabled => 0,
                    RayOffsetType::WorldPosition => 1,
                    RayOffsetType::CameraDistance => 2,
                },
            ],
            offset_world: [o.world_threshold, o.world_float_scale, o.world_int_scale, c.random_numbers as u32 as f32],
            offset_camera: [o.cam_constant, o.cam_linear, o.cam_quadratic, r.roughness_multiplier],
            frame: [seed, mask as u32, c.half_resolution_mode as u32, (c.direct_lighting.image != ash::vk::Image::null()) as u32],
            world_to_clip: (c.camera.view_to_clip * c.camera.world_to_view).to_cols_array(),
            normal_to_world: glam::Mat4::from_mat3(normal_to_world.unwrap_or(glam::Mat3::IDENTITY)).to_cols_array(),
            roughness_mask: r.channel_mask,
            roughness: [r.global_roughness, r.has_image() as u32 as f32, r.min_roughness, r.max_roughness],
        }
    }
}

/// The depth texel of a pixel where nothing was drawn: the far end of the viewport's depth
/// range, which is `min_depth` for a reversed-Z projection. Found by projecting a near and a far
/// point, so standard, reversed, finite and infinite projections all work.
fn background_depth(view_to_clip: &glam::Mat4, min_d: f32, max_d: f32) -> f32 {
    let depth = |z: f32| {
        let c = *view_to_clip * glam::Vec4::new(0.0, 0.0, z, 1.0);
        c.z / c.w
    };
    if depth(-1.0) > depth(-1.0e4) {
        min_d
    } else {
        max_d
    }
}

/// `LightGpu` in shaders/include/light_sampling.glsl.
#[derive(Clone, Copy, Pod, Zeroable, Default)]
#[repr(C)]
pub(crate) struct LightGpu {
    position: [f32; 4],
    direction: [f32; 4],
    shape: [f32; 4],
    power: [f32; 4],
}

impl LightGpu {
    pub fn new(l: &LightInfo) -> LightGpu {
        LightGpu {
            position: [l.position.x, l.position.y, l.position.z, l.light_type as u32 as f32],
            direction: [l.direction.x, l.direction.y, l.direction.z, (l.angular_extent * 0.5).tan()],
            shape: [
                if l.light_type == LightType::Directional { 0.0 } else { l.radius },
                if l.light_type == LightType::Directional { 0.0 } else { l.range },
                l.inner_cone.cos(),
                l.outer_cone.cos(),
            ],
            power: [l.intensity, l.color[0], l.color[1], l.color[2]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    /// Offsets as std140 lays out the GLSL blocks (mat4 = 64 bytes, vec4/uvec4 = 16).
    #[test]
    fn layouts_match_glsl_std140() {
        assert_eq!(offset_of!(TraceCommonGpu, view_to_world), 64);
        assert_eq!(offset_of!(TraceCommonGpu, viewport), 128);
        assert_eq!(offset_of!(TraceCommonGpu, depth_range), 144);
        assert_eq!(offset_of!(TraceCommonGpu, modes), 160);
        assert_eq!(offset_of!(TraceCommonGpu, offset_world), 176);
        assert_eq!(offset_of!(TraceCommonGpu, offset_camera), 192);
        assert_eq!(offset_of!(TraceCommonGpu, frame), 208);
        assert_eq!(offset_of!(TraceCommonGpu, world_to_clip), 224);
        assert_eq!(offset_of!(TraceCommonGpu, normal_to_world), 288);
        assert_eq!(offset_of!(TraceCommonGpu, roughness_mask), 352);
        assert_eq!(offset_of!(TraceCommonGpu, roughness), 368);
        assert_eq!(size_of::<TraceCommonGpu>(), 384);
        assert_eq!(offset_of!(AoConstantsGpu, params), 384);
        assert_eq!(offset_of!(AoConstantsGpu, counts), 400);
        assert_eq!(size_of::<AoConstantsGpu>(), 416);
        assert_eq!(offset_of!(EnvironmentGpu, params), 64);
        assert_eq!(size_of::<EnvironmentGpu>(), 80);
    }
}
