//! What the sample can show: the composite, every intermediate image of the frame (G-buffer,
//! direct light, each SDK output noisy and denoised, the lidar camera's view) and every debug
//! visualisation of the SDK. Each mode says how its source image becomes something to look at.
use glam::{Mat4, Vec4};
use hybrid_rt::DebugOutput;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Direct + GI x albedo x AO + reflections: the frame.
    Composite,
    /// The engine's direct lighting (sun and point light, shadowed by the SDK).
    Direct,
    Albedo,
    Normals,
    Roughness,
    Metalness,
    /// Motion vectors (pixels, previous - current), 0.5 = still.
    Motion,
    /// Emitted radiance (the G-buffer's emissive target, added into `Direct`).
    Emissive,
    SunShadowNoisy,
    SunShadow,
    PointShadowNoisy,
    PointShadow,
    /// The file's lights' shadows (glTF `KHR_lights_punctual`): the multi-light trace's
    /// weighted mean visibility, raw and denoised (both the sun's denoised shadow in a scene
    /// without such lights).
    LightsShadowNoisy,
    LightsShadow,
    AoNoisy,
    Ao,
    DiffuseNoisy,
    Diffuse,
    SpecularNoisy,
    Specular,
    /// The secondary low-resolution camera's lit view (what it injects).
    Lidar,
    /// `--many-lights`: the resampled lights' diffuse output (E/pi), raw and denoised, and the
    /// task's debug output (a colour per chosen light). The composite without the switch.
    ManyLightsNoisy,
    ManyLights,
    ManyLightsDebug,
    /// An SDK debug visualisation from the main camera.
    Debug(DebugOutput),
}

pub const ALL: [Mode; 29] = [
    Mode::Composite,
    Mode::Direct,
    Mode::Albedo,
    Mode::Normals,
    Mode::Roughness,
    Mode::Metalness,
    Mode::Motion,
    Mode::Emissive,
    Mode::SunShadowNoisy,
    Mode::SunShadow,
    Mode::PointShadowNoisy,
    Mode::PointShadow,
    Mode::LightsShadowNoisy,
    Mode::LightsShadow,
    Mode::AoNoisy,
    Mode::Ao,
    Mode::DiffuseNoisy,
    Mode::Diffuse,
    Mode::SpecularNoisy,
    Mode::Specular,
    Mode::Lidar,
    Mode::ManyLightsNoisy,
    Mode::ManyLights,
    Mode::ManyLightsDebug,
    Mode::Debug(DebugOutput::DirectLightingCache),
    Mode::Debug(DebugOutput::RandomTileColor),
    Mode::Debug(DebugOutput::RandomMeshColor),
    Mode::Debug(DebugOutput::HitT),
    Mode::Debug(DebugOutput::Barycentrics),
];

/// How the view pass maps a source texel: `swizzle * texel + bias`, then (for radiance)
/// exposure and tone mapping on the display copy.
pub struct ViewMapping {
    pub swizzle: Mat4,
    pub bias: Vec4,
    pub tone_map: bool,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Composite => "composite",
            Mode::Direct => "direct",
            Mode::Albedo => "albedo",
            Mode::Normals => "normals",
            Mode::Roughness => "roughness",
            Mode::Metalness => "metalness",
            Mode::Motion => "motion",
            Mode::Emissive => "emissive",
            Mode::SunShadowNoisy => "sun_shadow_noisy",
            Mode::SunShadow => "sun_shadow",
            Mode::PointShadowNoisy => "point_shadow_noisy",
            Mode::PointShadow => "point_shadow",
            Mode::LightsShadowNoisy => "lights_shadow_noisy",
            Mode::LightsShadow => "lights_shadow",
            Mode::AoNoisy => "ao_noisy",
            Mode::Ao => "ao",
            Mode::DiffuseNoisy => "diffuse_noisy",
            Mode::Diffuse => "diffuse",
            Mode::SpecularNoisy => "specular_noisy",
            Mode::Specular => "specular",
            Mode::Lidar => "lidar",
            Mode::ManyLightsNoisy => "many_lights_noisy",
            Mode::ManyLights => "many_lights",
            Mode::ManyLightsDebug => "many_lights_debug",
            Mode::Debug(DebugOutput::DirectLightingCache) => "debug_cache",
            Mode::Debug(DebugOutput::RandomTileColor) => "debug_random_tile",
            Mode::Debug(DebugOutput::RandomMeshColor) => "debug_random_mesh",
            Mode::Debug(DebugOutput::HitT) => "debug_hit_t",
            Mode::Debug(DebugOutput::Barycentrics) => "debug_barycentrics",
            Mode::Debug(DebugOutput::Default) => "debug_none",
            // A visualisation this sample does not list yet.
            Mode::Debug(_) => "debug_other",
        }
    }

    pub fn parse(name: &str) -> Option<Mode> {
        ALL.into_iter().find(|m| m.name() == name)
    }

    pub fn mapping(self) -> ViewMapping {
        let grey = |channel: usize| {
            let mut m = Mat4::ZERO;
            for row in 0..3 {
                m.col_mut(channel)[row] = 1.0;
            }
            m
        };
        let (swizzle, bias, tone_map) = match self {
            Mode::Composite
            | Mode::Direct
            | Mode::Emissive
            | Mode::Diffuse
            | Mode::DiffuseNoisy
            | Mode::Specular
            | Mode::SpecularNoisy
            | Mode::Lidar
            | Mode::ManyLightsNoisy
            | Mode::ManyLights => (Mat4::IDENTITY, Vec4::ZERO, true),
            Mode::Debug(DebugOutput::DirectLightingCache) => (Mat4::IDENTITY, Vec4::ZERO, true),
            Mode::Normals => (Mat4::from_diagonal(Vec4::new(0.5, 0.5, 0.5, 0.0)), Vec4::new(0.5, 0.5, 0.5, 1.0), false),
            Mode::Roughness | Mode::Metalness => (grey(3), Vec4::W, false),
            Mode::Motion => (Mat4::from_diagonal(Vec4::new(0.05, 0.05, 0.0, 0.0)), Vec4::new(0.5, 0.5, 0.0, 1.0), false),
            // A raw shadow trace keeps the visible fraction in G; denoised ones in every channel.
            Mode::SunShadowNoisy | Mode::PointShadowNoisy => (grey(1), Vec4::W, false),
            // The multi-light trace's packed output: the weighted visibility in R.
            Mode::LightsShadowNoisy => (grey(0), Vec4::W, false),
            Mode::Debug(DebugOutput::HitT) => (grey(0) * 0.1, Vec4::W, false),
            _ => (Mat4::IDENTITY, Vec4::ZERO, false),
        };
        ViewMapping { swizzle, bias, tone_map }
    }
}
