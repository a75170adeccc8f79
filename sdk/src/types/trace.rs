//! Trace tasks: ambient occlusion, shadows from one or many lights, diffuse GI and specular
//! reflections. Each traces secondary rays from the G-buffer (`TraceCommon`).
use super::inputs::{ImageInput, TraceCommon};
use ash::vk;

/// Ray-traced ambient occlusion. Output: visibility in [0, 1] (1 = unoccluded) written to
/// every channel of `output` (RGB = AO, A = 1) inside the viewport.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceAmbientOcclusionTask {
    /// The G-buffer the rays start from, the viewport and camera.
    pub common: TraceCommon,
    /// GENERAL layout, STORAGE usage; R8_UNORM, R16_SFLOAT, R32_SFLOAT, R16G16B16A16_SFLOAT,
    /// R32G32B32A32_SFLOAT or R8G8B8A8_UNORM.
    pub output: ImageInput,
    /// World-space length of AO rays. Default 1.0.
    pub ray_length: f32,
    /// Rays per pixel, 1..=64. Default 1 (denoise it) — use more for a clean raw image.
    pub rays_per_pixel: u32,
    /// A hit at distance t counts (t / ray_length)^power of a miss: near occluders darken more
    /// than far ones. Larger powers approach binary AO. > 0. Default 1.0.
    pub falloff_power: f32,
}

impl Default for TraceAmbientOcclusionTask {
    fn default() -> Self {
        TraceAmbientOcclusionTask {
            common: TraceCommon::default(),
            output: ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() },
            ray_length: 1.0,
            rays_per_pixel: 1,
            falloff_power: 1.0,
        }
    }
}

/// The kind of a light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
#[non_exhaustive]
pub enum LightType {
    /// Parallel rays (the sun). Default.
    #[default]
    Directional = 0,
    /// An emitting sphere of `radius` at `position`.
    Point = 1,
    /// A point light with a cone (`inner_cone`, `outer_cone`): surfaces outside the outer cone
    /// are unlit (visibility 0, no rays traced); the smoothstep from outer to inner weighs the
    /// light in the multi-light mean.
    Spot = 2,
}

/// A light, as the engine converts its own to. Size makes soft shadows: the SDK samples the
/// light's extent.
///
/// Where a light does not reach — beyond `range`, outside a spot's outer cone — the SDK
/// traces no rays and reports the surface unlit (the single-light output R = 0, G = 0; 0 in
/// the multi-light visibility). The multi-light `packed` visibility weighs each light by its
/// unshadowed irradiance at the surface: `intensity` x cone and range falloff x cos(theta)
/// (/ d² for point and spot lights), so a bright light's shadow is not diluted by a dim one's
/// light (Kickstart RT averages its lights unweighted).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightInfo {
    /// Directional (default), point or spot.
    pub light_type: LightType,
    /// Point and spot: world-space centre.
    pub position: glam::Vec3,
    /// Directional and spot: the direction the light travels (need not be normalized).
    pub direction: glam::Vec3,
    /// Directional: apparent diameter in radians (the sun: about 0.0093). 0 = hard shadows.
    pub angular_extent: f32,
    /// Point and spot: radius of the emitting sphere. 0 = hard shadows.
    pub radius: f32,
    /// Spot: the inner cone's half-angle in radians (full strength inside), 0..=outer_cone.
    /// Default 0.5.
    pub inner_cone: f32,
    /// Spot: the outer cone's half-angle in radians (nothing outside), < pi/2. Default 0.6.
    pub outer_cone: f32,
    /// Point and spot: the distance at which the light's influence ends (a windowed falloff
    /// (1 - (d/range)^4)^2 weighs it before that); 0 = unlimited (default).
    pub range: f32,
    /// Relative brightness (>= 0), the light's weight in the multi-light mean; for
    /// `RelightCacheTask`, its absolute brightness (see there). Default 1.
    pub intensity: f32,
    /// Linear RGB colour (each >= 0), multiplied into `intensity` by `RelightCacheTask`
    /// (shadow tasks weigh lights by `intensity` alone). Default white.
    pub color: [f32; 3],
}

impl Default for LightInfo {
    fn default() -> Self {
        LightInfo {
            light_type: LightType::Directional,
            position: glam::Vec3::ZERO,
            direction: glam::Vec3::NEG_Y,
            angular_extent: 0.0,
            radius: 0.0,
            inner_cone: 0.5,
            outer_cone: 0.6,
            range: 0.0,
            intensity: 1.0,
            color: [1.0; 3],
        }
    }
}

/// Ray-traced shadows from one light. Output (the integration guide's format): R = distance
/// to the closest occluder, negative where the light is visible; G, when the output has a
/// second channel, = the fraction of rays that reached the light (soft visibility).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceShadowTask {
    /// The G-buffer the rays start from, the viewport and camera.
    pub common: TraceCommon,
    /// The light.
    pub light: LightInfo,
    /// GENERAL layout, STORAGE usage: R16_SFLOAT, R32_SFLOAT, R16G16_SFLOAT, R32G32_SFLOAT,
    /// R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT.
    pub output: ImageInput,
    /// Rays per pixel, 1..=64. Default 1 (the guide's one ray per light; denoise it).
    pub rays_per_pixel: u32,
    /// Stop each ray at the first occluder traversal finds instead of the closest (Kickstart
    /// RT's `enableFirstHitAndEndSearch`). Visibility is the same; R then holds *an*
    /// occluder's distance (>= the closest), so `DenoiseShadowTask` may blur penumbrae a little
    /// wider. Default false (exact distances); the bench measures the difference.
    pub first_hit: bool,
    /// Shadow rays stop after this many world units (Kickstart RT's `maxRayLength`): an occluder
    /// farther from the surface does not shadow it — a cheap cap where far geometry should not
    /// shadow (a distant mountain in a valley's sun). At most the distance to a point or spot
    /// light. > 0; default unlimited (`f32::INFINITY`).
    pub max_ray_length: f32,
}

impl Default for TraceShadowTask {
    fn default() -> Self {
        TraceShadowTask {
            common: TraceCommon::default(),
            light: LightInfo::default(),
            output: ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() },
            rays_per_pixel: 1,
            first_hit: false,
            max_ray_length: f32::INFINITY,
        }
    }
}

/// Shadows from several lights in one pass (1..=32, Kickstart RT's limit; each light that
/// reaches a surface gets `rays_per_pixel` rays there, sampled as in `TraceShadowTask`).
/// - `visibility` (R32_UINT for up to 4 lights, R32G32B32A32_UINT for more): per light, the
///   visible fraction x 255 in 8 bits; light i is in channel i / 4 at bits 8 * (i % 4). Lights
///   16..32 go to `visibility_high` the same way (light 16 + i at channel i / 4).
/// - `packed` (RGBA16F/32F), the input of `DenoiseMultiShadowTask`: the lights' visibility
///   weighted by their unshadowed irradiance (see `LightInfo`; 1 where no light reaches), mean
///   penumbra width over the occluded rays (world units: occluder distance x the light's
///   angular size; -1 where no ray was occluded), min occluder distance (0 if none), and the
///   surface's distance to the camera.
/// - `light_outputs` (optional, up to 4): chosen lights' shadows in `TraceShadowTask`'s
///   format, for a `DenoiseShadowTask` each — a per-light denoised result for the lights the
///   engine shades separately (its hero lights), from the same rays.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceMultiShadowTask {
    /// The G-buffer the rays start from, the viewport and camera.
    pub common: TraceCommon,
    /// 1..=32 lights.
    pub lights: Vec<LightInfo>,
    /// Per-light visibility of lights 0..16 (see above): R32_UINT or R32G32B32A32_UINT, GENERAL,
    /// STORAGE usage.
    pub visibility: ImageInput,
    /// Lights 16..32 (required with more than 16 lights, else leave it null): R32_UINT (up to
    /// 20 lights) or R32G32B32A32_UINT.
    pub visibility_high: ImageInput,
    /// The denoiser's input (see above): RGBA16F or RGBA32F, GENERAL, STORAGE usage.
    pub packed: ImageInput,
    /// Up to `MAX_LIGHT_OUTPUTS` lights written on their own (see above). Default none.
    pub light_outputs: Vec<LightShadowOutput>,
    /// Rays per pixel and light, 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// First-hit traversal, as `TraceShadowTask::first_hit` (the packed penumbra width and min
    /// distance then come from the first occluders found). Default false.
    pub first_hit: bool,
    /// Shadow rays stop after this many world units (Kickstart RT's `maxRayLength`): an occluder
    /// farther from the surface does not shadow it — a cheap cap where far geometry should not
    /// shadow (a distant mountain in a valley's sun). At most the distance to a point or spot
    /// light. > 0; default unlimited (`f32::INFINITY`).
    pub max_ray_length: f32,
}

/// One light of a `TraceMultiShadowTask` written on its own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightShadowOutput {
    /// Index into `TraceMultiShadowTask::lights`.
    pub light: u32,
    /// `TraceShadowTask::output`'s formats and layout: R = closest occluder distance (negative
    /// where visible, 0 where the light does not reach), G = visible fraction.
    pub output: ImageInput,
}

impl Default for TraceMultiShadowTask {
    fn default() -> Self {
        let general = ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() };
        TraceMultiShadowTask {
            common: TraceCommon::default(),
            lights: Vec::new(),
            visibility: general,
            visibility_high: general,
            packed: general,
            light_outputs: Vec::new(),
            rays_per_pixel: 1,
            first_hit: false,
            max_ray_length: f32::INFINITY,
        }
    }
}

// ---------------------------------------------------------------- diffuse GI

/// The diffuse BRDF that weighs each GI ray (both are normalized to Lambert's albedo).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum DiffuseBrdfType {
    /// Lambertian: every direction weighs the same. Default.
    #[default]
    Lambertian = 0,
    /// Burley's Disney diffuse with Frostbite's energy normalisation: rough surfaces
    /// retro-reflect, smooth ones darken at grazing angles. Reads `common.roughness`.
    NormalizedDisney = 1,
}

/// One bounce of diffuse GI shaded from the direct-lighting cache. Output (RGBA float):
/// RGB = the mean incoming radiance over the cosine-weighted hemisphere (E/pi: multiply by
/// your albedo for Lambertian outgoing light), A = the mean hit distance (misses count as
/// `ray_length`), which the denoiser uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceDiffuseTask {
    /// The G-buffer the rays start from (plus roughness and the optional lit frame), viewport and camera.
    pub common: TraceCommon,
    /// GENERAL layout, STORAGE usage: R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT.
    pub output: ImageInput,
    /// Rays per pixel, 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// Longest ray in world units (> 0). Default 1000.
    pub ray_length: f32,
    /// Radiance of rays that hit nothing (a constant sky). Default black.
    pub miss_radiance: [f32; 3],
    /// Default Lambertian.
    pub brdf: DiffuseBrdfType,
    /// Optional: what rays that hit nothing see, instead of `miss_radiance`.
    pub environment: EnvironmentInput,
}

/// An environment map for rays that hit nothing (the sky, a captured probe), replacing the
/// task's constant `miss_radiance` when `image` is given.
///
/// Lat-long (equirectangular) layout, the usual one for HDR skies: a direction `d` in the
/// map's frame is at `u = 0.5 + atan2(d.x, -d.z) / 2pi` (u = 0.5 looks down -Z, u grows
/// towards +X), `v = acos(d.y) / pi` (v = 0 straight up). Looked up bilinearly at mip 0 of the
/// view, wrapping in u and clamped in v; done with texel fetches, so any sampled format works
/// (RGBA32F has no linear filtering on some devices).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvironmentInput {
    /// The map (SAMPLED usage, a read-only layout); any size. Null: no map (default).
    pub image: ImageInput,
    /// The map's frame in world space: a world direction `d` is looked up at
    /// `rotation.transpose() * d`. Must be a rotation. Default identity (+Y up).
    pub rotation: glam::Mat3,
    /// Radiance multiplier (>= 0). Default 1.
    pub intensity: f32,
}

impl Default for EnvironmentInput {
    fn default() -> Self {
        EnvironmentInput { image: ImageInput::default(), rotation: glam::Mat3::IDENTITY, intensity: 1.0 }
    }
}

impl EnvironmentInput {
    /// Whether a map is given.
    pub fn has_image(&self) -> bool {
        self.image.image != vk::Image::null()
    }
}

impl Default for TraceDiffuseTask {
    fn default() -> Self {
        TraceDiffuseTask {
            common: TraceCommon::default(),
            output: ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() },
            rays_per_pixel: 1,
            ray_length: 1000.0,
            miss_radiance: [0.0; 3],
            brdf: DiffuseBrdfType::Lambertian,
            environment: EnvironmentInput::default(),
        }
    }
}

// ---------------------------------------------------------------- specular

/// Specular reflections shaded from the direct-lighting cache. Roughness (from
/// `common.roughness`) 0 traces the exact mirror direction; otherwise GGX visible normals are
/// sampled. Output (RGBA float): RGB = reflected radiance weighted by the Smith-GGX lobe (no
/// Fresnel) times the specular colour of `common.specular`; A = hit distance of the first ray
/// (misses: `ray_length`), for the denoiser. `demodulated_output`, if set, receives the same
/// without the specular colour (denoise that, then multiply back).
/// Reflections off clear glass: a second task with the glass's own depth, normals and
/// roughness as its G-buffer.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceSpecularTask {
    /// The G-buffer the rays start from (plus roughness, specular colour and the optional lit frame), viewport and camera.
    pub common: TraceCommon,
    /// GENERAL layout, STORAGE usage: R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT.
    pub output: ImageInput,
    /// Rays per pixel for rough surfaces, 1..=64 (mirrors always trace one). Default 1.
    pub rays_per_pixel: u32,
    /// Longest ray (> 0). Default 1000.
    pub ray_length: f32,
    /// Radiance of rays that hit nothing. Default black.
    pub miss_radiance: [f32; 3],
    /// Largest luminance one sample may carry (fireflies); 0 = no clamp. Default 0.
    pub firefly_clamp: f32,
    /// Optional (image null = none): same format rules as `output`.
    pub demodulated_output: ImageInput,
    /// Optional: what rays that hit nothing see, instead of `miss_radiance` (glass reflections
    /// too: they are a specular task).
    pub environment: EnvironmentInput,
    /// Optional: shade the hits of smooth pixels from the engine's lights instead of the
    /// cache (see `HitLighting`). Default off (no lights).
    pub hit_lighting: HitLighting,
}

/// Hit lighting for mirrors (`TraceSpecularTask::hit_lighting`; Lumen's name for it). The
/// cache is a tile wide: a shadow edge or a small light's falloff seen in a mirror is as
/// blurred as the tiles. On pixels whose roughness is at most `max_roughness`, each specular
/// hit is shaded instead with the engine's lights — the hit's `InstanceInput::albedo` x the
/// lights' irradiance with one shadow ray per light, plus its `InstanceInput::emission` —
/// and the indirect part comes from the caches (see `HitIndirect`). Rougher pixels keep
/// reading the cache, where its blur is below the lobe's. Only the listed lights light the
/// hits directly, so list every light that matters.
///
/// Cost per hit-lit ray: one shadow ray per light that reaches the hit, plus the indirect
/// part's rays (`HitIndirect`); hard lights give a noise-free result, sized lights soft
/// shadows over frames.
#[derive(Debug, Clone, PartialEq)]
pub struct HitLighting {
    /// 0..=32 lights (`MAX_SHADOW_LIGHTS`), `intensity` and `color` absolute as for
    /// `RelightCacheTask`. Empty: hit lighting off. Default empty.
    pub lights: Vec<LightInfo>,
    /// Pixels with roughness up to this (0..=1) are hit-lit. Default 0.1.
    pub max_roughness: f32,
    /// Where the indirect part comes from. Default `HitIndirect::CacheResidual`.
    pub indirect: HitIndirect,
    /// `HitIndirect::Gather`'s rays per hit, 1..=8 (`MAX_HIT_GATHER_RAYS`). Default 1.
    pub gather_rays: u32,
}

impl Default for HitLighting {
    fn default() -> Self {
        HitLighting { lights: Vec::new(), max_roughness: 0.1, indirect: HitIndirect::CacheResidual, gather_rays: 1 }
    }
}

/// The indirect part of hit lighting (`HitLighting::indirect`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[repr(u32)]
pub enum HitIndirect {
    /// The cache sample the hit lands on, less the direct light and emission the listed
    /// lights give at that sample (one more shadow ray per light): what the cache holds beyond
    /// them — a relit sample's bounce exactly, an injected sample's other light (your ambient,
    /// light maps, unlisted lights) up to the tile's variation of direct light. No noise;
    /// clamped at 0. Default.
    #[default]
    CacheResidual = 0,
    /// `gather_rays` cosine rays at the hit, each reading the cache sample it lands on (misses
    /// see the task's miss radiance or environment), times the albedo: unbiased but noisy
    /// (denoise the output).
    Gather = 1,
    /// Direct light and emission only.
    None = 2,
}

/// The most gather rays per hit-lit ray (`HitLighting::gather_rays`).
pub const MAX_HIT_GATHER_RAYS: u32 = 8;

impl Default for TraceSpecularTask {
    fn default() -> Self {
        TraceSpecularTask {
            common: TraceCommon::default(),
            output: ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() },
            rays_per_pixel: 1,
            ray_length: 1000.0,
            miss_radiance: [0.0; 3],
            firefly_clamp: 0.0,
            demodulated_output: ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() },
            environment: EnvironmentInput::default(),
            hit_lighting: HitLighting::default(),
        }
    }
}
