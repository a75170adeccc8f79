//! The SDK inputs a view's G-buffer makes.
use crate::raster::{self, Targets};
use hybrid_rt::*;
use hybrid_rt_host::scene::Camera;

/// The SDK inputs a view's G-buffer makes: trace and denoise commons.
pub(super) struct Inputs {
    pub(super) common: TraceCommon,
    pub(super) denoising: DenoisingCommon,
}

impl Inputs {
    pub(super) fn of(t: &Targets, camera: &Camera) -> Inputs {
        let read = raster::READ;
        let depth = DepthInput { image: t.depth.input(read), depth_type: DepthType::ClipSpace };
        let normals = NormalInput {
            image: t.normal_roughness.input(read),
            normal_type: NormalType::RgbVector,
            space: NormalSpace::World,
            ..Default::default()
        };
        // Roughness lives in the normal target's alpha.
        let roughness =
            RoughnessInput { image: t.normal_roughness.input(read), channel_mask: [0.0, 0.0, 0.0, 1.0], ..Default::default() };
        let viewport = Viewport::full(t.width, t.height);
        let sdk_camera = camera.sdk_camera(t.width, t.height);
        let common = TraceCommon { depth, normals, roughness, viewport, camera: sdk_camera, ..Default::default() };
        let motion = MotionInput { image: t.motion.input(read), motion_type: MotionType::RgViewSpace, scale: [1.0; 3] };
        let denoising = DenoisingCommon { depth, normals, roughness, motion, viewport, camera: sdk_camera, ..Default::default() };
        Inputs { common, denoising }
    }
}
