//! Many shadowed lights: direct lighting from thousands of lights by spatiotemporal reservoir
//! resampling (ReSTIR DI), `TraceManyLightsTask`.
use super::denoise::MotionInput;
use super::handles::ManyLightsContextHandle;
use super::inputs::{ImageInput, TraceCommon};
use super::trace::LightInfo;
use ash::vk;

/// Lights a many-lights context holds at most.
pub const MAX_MANY_LIGHTS: u32 = 1 << 20;

/// Largest width or height of a many-lights context.
pub const MAX_MANY_LIGHTS_EXTENT: u32 = 16384;

/// A many-lights context: the light list on the GPU with its power distribution, and one view's
/// reservoirs (last frame's, for temporal reuse) and surfaces. Create one per view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ManyLightsContextInput {
    /// Largest viewport right edge (`x + width`) the context's tasks use, 1..=16384.
    pub max_width: u32,
    /// Largest viewport bottom edge (`y + height`), 1..=16384.
    pub max_height: u32,
    /// Lights the list may hold, 1..=`MAX_MANY_LIGHTS`. Default 65,536.
    pub max_lights: u32,
}

impl Default for ManyLightsContextInput {
    fn default() -> Self {
        ManyLightsContextInput { max_width: 0, max_height: 0, max_lights: 65_536 }
    }
}

/// How the pixels' light samples are chosen and reused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum ResamplingMode {
    /// Reservoirs merged with weights by how likely each was to produce the sample (its
    /// confidence times its unshadowed target there; no rays): one shadow ray per pixel (two
    /// with `candidate_visibility`). A neighbour or last frame's pixel that cannot *see* the
    /// light still counts, so contact shadows come out slightly dark (the tests bound it).
    /// Default.
    #[default]
    Biased = 0,
    /// The same weights with each merged reservoir's visibility of the sample in its target (a
    /// shadow ray per neighbour, and one from last frame's surface): converges to the
    /// brute-force result, at about 3 + `spatial_samples` rays per pixel.
    Unbiased = 1,
    /// No resampling and no reuse: `initial_candidates` lights drawn by power (and one
    /// directional light), a shadow ray each. The baseline resampling is measured against.
    PowerSampling = 2,
}

/// The resampling's settings (RTXDI's defaults are similar).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ManyLightsSettings {
    /// See `ResamplingMode`. Default `Biased`.
    pub mode: ResamplingMode,
    /// Local-light candidates per pixel per frame, drawn by power; one directional light is
    /// drawn besides when the list has any. 1..=32. Default 8.
    pub initial_candidates: u32,
    /// Neighbours merged per pixel, 0..=8. Default 4.
    pub spatial_samples: u32,
    /// Radius of the neighbourhood, pixels, 1..=128. Default 24.
    pub spatial_radius: f32,
    /// Last frame's reservoir counts at most this many frames (the history's length: longer is
    /// smoother frame to frame, shorter follows changes sooner and leaves the denoiser frames
    /// that share fewer samples), 1..=64. Measured against brute force after 32 denoised
    /// frames: 8 frames leave a third less error than 20. Default 8.
    pub max_history: u32,
    /// Biased mode: test whether this frame's chosen candidate reaches its light before it is
    /// merged and passed on (Bitterli et al.'s visibility reuse: one more shadow ray a pixel).
    /// Off, occluded candidates are passed on too and only the shading ray finds them out: one
    /// ray a pixel in all. Measured against brute force, off costs nothing measurable (one
    /// frame's error 0.580 vs 0.578, the mean's darkening -0.7% either way), so it is off by
    /// default. (The unbiased mode always tests.) Default false.
    pub candidate_visibility: bool,
}

impl Default for ManyLightsSettings {
    fn default() -> Self {
        ManyLightsSettings {
            mode: ResamplingMode::Biased,
            initial_candidates: 8,
            spatial_samples: 4,
            spatial_radius: 24.0,
            max_history: 8,
            candidate_visibility: false,
        }
    }
}

/// How a `TraceManyLightsTask` changes the context's light list.
///
/// A light keeps its index from frame to frame: that index is how last frame's samples find it.
/// To remove a light, `Write` it with intensity 0 (or `Replace` the list): samples of a light
/// that is gone or dark die the next frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum LightListUpdate {
    /// The lights of the context's previous task. Default.
    #[default]
    Keep,
    /// A new list (0..=`max_lights` lights).
    Replace(Vec<LightInfo>),
    /// Lights `first..first + lights.len()` overwritten (moved, recoloured, switched off); the
    /// list grows when the range ends beyond it.
    Write {
        /// The first light written; at most the list's length.
        first: u32,
        /// The new lights.
        lights: Vec<LightInfo>,
    },
}

impl LightListUpdate {
    /// The lights it uploads.
    pub fn lights(&self) -> &[LightInfo] {
        match self {
            LightListUpdate::Keep => &[],
            LightListUpdate::Replace(l) | LightListUpdate::Write { lights: l, .. } => l,
        }
    }
}

/// Shadowed direct lighting from the context's light list — point, sphere, spot and directional
/// lights, up to `MAX_MANY_LIGHTS` — by resampling: per pixel, a handful of lights drawn by
/// power, resampled by their unshadowed contribution, merged with last frame's choice (along
/// the motion vectors) and with neighbours', and shaded with one shadow ray.
///
/// Outputs are demodulated, as the denoisers take them: `diffuse_output` = irradiance / pi
/// (multiply by the diffuse albedo), `specular_output` = GGX specular without Fresnel (multiply
/// by the specular colour); A = distance to the light sample. Feed them to
/// `DenoiseSpecularAndDiffuseTask`.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceManyLightsTask {
    /// The context: light list, history.
    pub context: ManyLightsContextHandle,
    /// The G-buffer, viewport and camera (roughness from `common.roughness`). Checkerboard mode
    /// is not supported.
    pub common: TraceCommon,
    /// Motion vectors for the temporal reuse (optional: without, reprojection uses the cameras —
    /// static scenes only).
    pub motion: MotionInput,
    /// Changes to the light list, before tracing. Default `Keep`.
    pub lights: LightListUpdate,
    /// RGBA16F or RGBA32F, GENERAL, STORAGE usage.
    pub diffuse_output: ImageInput,
    /// RGBA16F or RGBA32F, GENERAL, STORAGE usage.
    pub specular_output: ImageInput,
    /// Optional (leave null): RGB = a random colour per chosen light (black: none), A = the
    /// reservoir's sample count. RGBA16F or RGBA32F, GENERAL, STORAGE usage.
    pub debug_output: ImageInput,
    /// Resampling settings.
    pub settings: ManyLightsSettings,
    /// Forget last frame's reservoirs (a camera cut). Default false.
    pub reset_history: bool,
}

impl Default for TraceManyLightsTask {
    fn default() -> Self {
        let general = ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() };
        TraceManyLightsTask {
            context: ManyLightsContextHandle::NULL,
            common: TraceCommon::default(),
            motion: MotionInput::default(),
            lights: LightListUpdate::Keep,
            diffuse_output: general,
            specular_output: general,
            debug_output: general,
            settings: ManyLightsSettings::default(),
            reset_history: false,
        }
    }
}
