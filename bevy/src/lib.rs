//! hybrid-rt inside Bevy: ray-traced ambient occlusion, shadows, reflections and diffuse GI
//! for Bevy's rasterized frame.
//!
//! Bevy keeps its renderer. Each frame the plugin
//! - mirrors the scene into the SDK: every visible entity with a `Mesh3d` becomes an SDK
//!   instance of its mesh's geometry, read straight from the vertex and index slabs of Bevy's
//!   mesh allocator (offsets and strides, no copy on Bevy's side); entities that move, hide or
//!   go away are updated or removed, and the BVH is rebuilt with them;
//! - traces AO from Bevy's prepass (its depth and world-space normals, as they are: the SDK
//!   reads `Depth32Float` reversed-Z and `Rgb10a2Unorm` normals directly) into the texture
//!   Bevy's PBR reads its screen-space AO from, after Bevy's SSAO and before the opaque pass —
//!   so Bevy's lighting takes ray-traced occlusion where it took SSAO's;
//! - traces the shadow of a light (the sun, a point or a spot light) from the same prepass into
//!   an image of the application's, for its own compositing ([`RayTracedShadow`]);
//! - injects the camera's lit frame into the SDK's direct-lighting cache and traces diffuse GI
//!   ([`RayTracedGi`]) and reflections ([`RayTracedReflections`], deferred cameras) from it
//!   into images of the application's, which for a deferred camera it also adds to the lit
//!   image;
//! - records the SDK's work into a command buffer placed among Bevy's own, and hands each
//!   ticket back once the queue has finished the frame, with the SDK's per-task GPU times
//!   published as Bevy diagnostics ([`DIAGNOSTIC_PATHS`]).
//!
//! Bevy's own ray tracer, `bevy_solari`, replaces Bevy's lighting; this plugin adds ray-traced
//! effects to the lighting Bevy already has.
//!
//! # Set-up
//! The SDK needs Vulkan extensions that Bevy's device must be created with:
//! ```ignore
//! App::new()
//!     .add_plugins(HybridRtInitPlugin) // before DefaultPlugins: the device's extensions
//!     .add_plugins(DefaultPlugins.set(hybrid_rt_bevy::render_plugin()))
//!     .add_plugins(HybridRtPlugin)
//! ```
//! and a camera takes [`RayTracedAo`] (which brings Bevy's depth and normal prepasses and its
//! AO texture with it; the camera needs `Msaa::Off`, as Bevy's SSAO does) and/or
//! [`RayTracedShadow`] (which brings the prepasses), [`RayTracedGi`] and
//! [`RayTracedReflections`].
#![deny(missing_docs)]

mod render;
mod scene;

use bevy::camera::Hdr;
use bevy::core_pipeline::prepass::{DeferredPrepass, DepthPrepass, NormalPrepass};
use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::pbr::ScreenSpaceAmbientOcclusion;
use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::renderer::raw_vulkan_init::RawVulkanInitSettings;
use bevy::render::settings::{RenderCreation, WgpuSettings};
use bevy::render::RenderPlugin;
use parking_lot::Mutex;
use std::sync::Arc;

pub use hybrid_rt;
pub use hybrid_rt_wgpu;

/// Ray-traced ambient occlusion for a 3D camera. Toggle `enabled` at run time: off, Bevy's
/// SSAO shows again.
#[derive(Component, Clone, Debug, PartialEq, ExtractComponent)]
#[extract_app(bevy::render::RenderApp)]
#[require(ScreenSpaceAmbientOcclusion)]
pub struct RayTracedAo {
    /// Trace it (true) or leave Bevy's SSAO in place. Default true.
    pub enabled: bool,
    /// How far an occluder counts, in world units. Default 1.0.
    pub ray_length: f32,
    /// Rays per pixel (1..=64). Default 1.
    pub rays_per_pixel: u32,
    /// Denoise (the SDK's AO denoiser: temporal, along Bevy's motion vectors where the camera
    /// has `MotionVectorPrepass`, else reprojected with the cameras; then spatial). Default true.
    pub denoise: bool,
    /// Where the AO goes. Default [`AoOutput::Pbr`].
    pub output: AoOutput,
}

impl Default for RayTracedAo {
    fn default() -> Self {
        RayTracedAo { enabled: true, ray_length: 1.0, rays_per_pixel: 1, denoise: true, output: AoOutput::Pbr }
    }
}

/// Where [`RayTracedAo`] writes.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum AoOutput {
    /// Into the texture Bevy's PBR reads its screen-space AO from (after Bevy's SSAO wrote it,
    /// before the opaque pass reads it): Bevy's lighting takes ray-traced occlusion. The
    /// camera needs `Msaa::Off`, as Bevy's SSAO does. Default.
    #[default]
    Pbr,
    /// Into an image of the application's, of the view's size (`R32Float`, `R16Float` or
    /// `Rgba16Float`, with `STORAGE_BINDING` usage, created with contents): for its own
    /// materials or compositing, debug views, tests.
    Image(Handle<Image>),
}

/// A ray-traced shadow for a 3D camera: the fraction of one light — the sun (a
/// `DirectionalLight`), a `PointLight` or a `SpotLight` — that each pixel of Bevy's prepass
/// sees, soft as the light's size makes it, written into an image of the application's. For a
/// deferred camera and a light with `shadow_maps_enabled: false` the plugin also takes the
/// light's occluded part out of the lit image (`composite`): the ray-traced shadow replaces
/// the shadow map in Bevy's frame. Otherwise the image is for the application's own
/// compositing (Bevy's forward PBR has no input for a screen-space shadow). Toggle `enabled`
/// at run time.
///
/// A point or spot light's `radius` is the emitting sphere's (0: hard shadows) and its
/// `range` ends its reach: beyond it, and outside a spot light's outer cone, pixels are unlit
/// (visible fraction 0, no rays traced).
#[derive(Component, Clone, Debug, PartialEq, ExtractComponent)]
#[extract_app(bevy::render::RenderApp)]
#[require(DepthPrepass, NormalPrepass)]
pub struct RayTracedShadow {
    /// Trace it (true) or leave the image as it is. Default true.
    pub enabled: bool,
    /// The light: a `DirectionalLight`, `PointLight` or `SpotLight` entity; None (default):
    /// the scene's first visible `DirectionalLight`.
    pub light: Option<Entity>,
    /// A directional light's apparent diameter in radians: 0 casts hard shadows. Default
    /// 0.0093 (the sun's). Point and spot lights take their own `radius` instead.
    pub angular_diameter: f32,
    /// Rays per pixel (1..=64). Default 1.
    pub rays_per_pixel: u32,
    /// Denoise (the SDK's shadow denoiser: temporal, along Bevy's motion vectors where the
    /// camera has `MotionVectorPrepass`, else reprojected with the cameras; then spatial, its
    /// penumbrae as wide as the light's size and the occluders' distances make them). Default
    /// true.
    pub denoise: bool,
    /// A deferred camera with `Hdr` and a light with `shadow_maps_enabled: false` (which Bevy
    /// then lights unshadowed): take the occluded part of its light — computed from the
    /// deferred G-buffer as Bevy's lighting computes it — out of the lit image, after Bevy's
    /// lighting; `output` then needs `TEXTURE_BINDING` usage too. Other cameras and lights keep
    /// the shadow in `output` only. Default true.
    pub composite: bool,
    /// Where the shadow goes: an image of the view's size with `STORAGE_BINDING` usage,
    /// created with contents. Denoised, the visible fraction is in every channel (`R32Float`,
    /// `R16Float` or `Rgba16Float`); with `denoise: false`, the trace's own texels: R = the
    /// distance to the nearest occluder, G = the visible fraction (`Rgba16Float`).
    pub output: Handle<Image>,
}

impl Default for RayTracedShadow {
    fn default() -> Self {
        RayTracedShadow {
            enabled: true,
            light: None,
            angular_diameter: 0.0093,
            rays_per_pixel: 1,
            denoise: true,
            composite: true,
            output: Handle::default(),
        }
    }
}

/// Diffuse global illumination for a 3D camera: one bounce of the light Bevy's frame shows,
/// traced from Bevy's prepass into an image of the application's, for its own compositing
/// (multiplied by the surface's diffuse colour, added to the lit image).
///
/// Each frame the camera's lit frame — Bevy's HDR view target after the opaque pass — is
/// injected into the SDK's direct-lighting cache, which remembers the lit colour of every
/// surface a camera has shown; the GI's rays read that cache where they hit. Surfaces no
/// camera has shown yet stay black until one does. The camera needs `Hdr` (brought along: the
/// cache takes radiance, not tonemapped colour) and `Msaa::Off`. Toggle `enabled` at run time.
#[derive(Component, Clone, Debug, PartialEq, ExtractComponent)]
#[extract_app(bevy::render::RenderApp)]
#[require(DepthPrepass, NormalPrepass, Hdr)]
pub struct RayTracedGi {
    /// Inject and trace (true), or leave the cache and the image as they are. Default true.
    pub enabled: bool,
    /// Rays per pixel (1..=64). Default 1.
    pub rays_per_pixel: u32,
    /// The longest ray in world units (> 0). Default 100.
    pub ray_length: f32,
    /// Radiance (linear RGB) of rays that hit nothing: a constant sky. Default black.
    pub miss_radiance: [f32; 3],
    /// Frames over which the cache averages each surface's lit colour (>= 1): longer is
    /// steadier under a moving camera, shorter follows lights that change sooner. Default 30
    /// (half a second at 60 frames a second).
    pub cache_average_frames: f32,
    /// Denoise (the SDK's diffuse denoiser: temporal, along Bevy's motion vectors where the
    /// camera has `MotionVectorPrepass`, then spatial). Default true.
    pub denoise: bool,
    /// A deferred camera (`DeferredPrepass`): add the GI, times each pixel's diffuse colour
    /// from Bevy's deferred G-buffer (base colour x (1 - metallic)), to the lit image after
    /// Bevy's lighting; `output` then needs `TEXTURE_BINDING` usage too. Lower Bevy's
    /// `GlobalAmbientLight` where the GI takes its place. A forward camera's GI stays in
    /// `output` (its surfaces' colours are not in any texture). Default true.
    pub composite: bool,
    /// Where the GI goes: an `Rgba16Float` or `Rgba32Float` image of the view's size with
    /// `STORAGE_BINDING` usage, created with contents. RGB: the mean radiance arriving over the
    /// cosine-weighted hemisphere (irradiance / pi; times the diffuse albedo, the light the
    /// surface reflects); A: the distance to the hits.
    pub output: Handle<Image>,
}

impl Default for RayTracedGi {
    fn default() -> Self {
        RayTracedGi {
            enabled: true,
            rays_per_pixel: 1,
            ray_length: 100.0,
            miss_radiance: [0.0; 3],
            cache_average_frames: 30.0,
            denoise: true,
            composite: true,
            output: Handle::default(),
        }
    }
}

/// Ray-traced reflections for a deferred 3D camera: the light each pixel's specular lobe
/// reflects — mirrors exactly, rough surfaces by sampling their GGX lobe — traced from Bevy's
/// prepass and deferred G-buffer (roughness per pixel), denoised into an image of the
/// application's, and added to the lit image (times each pixel's environment BRDF, as Bevy
/// weighs its environment map's light) before transparent surfaces are drawn.
///
/// Reflected surfaces are shaded as the GI's rays shade theirs: from Bevy's lit frame where
/// the camera sees them (sharp, this frame's lighting), elsewhere from the SDK's
/// direct-lighting cache, into which the camera's lit frame is injected each frame (once, when
/// the camera has [`RayTracedGi`] too, with the GI's `cache_average_frames`). Surfaces no
/// camera has shown yet reflect black until one does. Like Bevy's screen-space reflections,
/// it needs deferred rendering (the roughness and specular colour of a forward camera's pixels
/// are in no texture) and `Msaa::Off`; it brings `DeferredPrepass` and `Hdr`. Unlit surfaces
/// reflect nothing. Toggle `enabled` at run time.
#[derive(Component, Clone, Debug, PartialEq, ExtractComponent)]
#[extract_app(bevy::render::RenderApp)]
#[require(DepthPrepass, NormalPrepass, DeferredPrepass, Hdr)]
pub struct RayTracedReflections {
    /// Trace (true), or leave the image and the lit image as they are. Default true.
    pub enabled: bool,
    /// Rays per pixel on rough surfaces (1..=64); mirrors trace one. Default 1.
    pub rays_per_pixel: u32,
    /// Surfaces rougher than this (Bevy's perceptual roughness, 0..=1) are not traced: they
    /// keep the specular Bevy's lighting gives them, and cost no rays. Default 1.0 (all).
    pub max_roughness: f32,
    /// The longest ray in world units (> 0). Default 100.
    pub ray_length: f32,
    /// Radiance (linear RGB) of rays that hit nothing: a constant sky. Default black.
    pub miss_radiance: [f32; 3],
    /// Surfaces up to this roughness (near-mirrors, 0..=1) shade their reflections' hits from
    /// Bevy's lights (the first 32 visible directional, point and spot lights, one shadow ray
    /// each; the hit's `StandardMaterial` base colour as its albedo, Lambert) plus what the
    /// cache holds beyond those lights — sharp where the cache is a tile wide, and lit where no
    /// camera has shown the surface. Rougher surfaces read the cache only. Negative: off.
    /// Default 0.1.
    pub hit_lighting_roughness: f32,
    /// Frames over which the cache averages each surface's lit colour (>= 1), when the camera
    /// has no enabled [`RayTracedGi`] (whose setting governs otherwise). Default 30.
    pub cache_average_frames: f32,
    /// Denoise (the SDK's specular denoiser: temporal, along Bevy's motion vectors where the
    /// camera has `MotionVectorPrepass`, then spatial, as wide as each pixel's roughness and
    /// hit distance allow; mirrors stay sharp). Default true.
    pub denoise: bool,
    /// Add the reflections to the lit image, times each pixel's environment BRDF (Bevy's
    /// split-sum terms for its specular colour, roughness and view angle); `output` then needs
    /// `TEXTURE_BINDING` usage too. Lower the specular of Bevy's `GlobalAmbientLight` or
    /// environment map where the reflections take its place. Default true.
    pub composite: bool,
    /// Where the reflections go: an `Rgba16Float` or `Rgba32Float` image of the view's size
    /// with `STORAGE_BINDING` usage, created with contents. RGB: the reflected radiance,
    /// weighted by the lobe's shadowing and masking but not by Fresnel (times the environment
    /// BRDF over the lobe's albedo, the light the surface reflects); A: the distance to the hits.
    pub output: Handle<Image>,
}

impl Default for RayTracedReflections {
    fn default() -> Self {
        RayTracedReflections {
            enabled: true,
            rays_per_pixel: 1,
            max_roughness: 1.0,
            ray_length: 100.0,
            miss_radiance: [0.0; 3],
            hit_lighting_roughness: 0.1,
            cache_average_frames: 30.0,
            denoise: true,
            composite: true,
            output: Handle::default(),
        }
    }
}

/// Adds what the SDK needs to the Vulkan device Bevy is about to create. Add it *before*
/// `DefaultPlugins` (Bevy reads the device callbacks when its render plugin is built), with
/// [`render_plugin`] in place of Bevy's default `RenderPlugin`.
pub struct HybridRtInitPlugin;

impl Plugin for HybridRtInitPlugin {
    fn build(&self, app: &mut App) {
        let mut settings = app.world_mut().get_resource_or_init::<RawVulkanInitSettings>();
        // SAFETY: the callback only adds device extensions and one feature struct to the chain.
        unsafe { settings.add_create_device_callback(|args, _adapter, _features| hybrid_rt_wgpu::add_sdk_requirements(args)) };
    }
}

/// Bevy's render plugin with the wgpu features the SDK needs ([`hybrid_rt_wgpu::SDK_WGPU_FEATURES`]):
/// `DefaultPlugins.set(hybrid_rt_bevy::render_plugin())`.
pub fn render_plugin() -> RenderPlugin {
    let settings = WgpuSettings { features: hybrid_rt_wgpu::SDK_WGPU_FEATURES, ..Default::default() };
    RenderPlugin { render_creation: RenderCreation::Automatic(Box::new(settings)), ..Default::default() }
}

/// The plugin: scene sync, AO and a light's shadow traced per camera, tickets and GPU times. Add it after
/// `DefaultPlugins` (and [`HybridRtInitPlugin`] before them).
pub struct HybridRtPlugin;

/// The SDK's per-task GPU times of the last frame whose ticket came back, shared between
/// Bevy's render world (which fills it) and the main world (which publishes it).
#[derive(Resource, Clone, Default)]
pub struct HybridRtTimings(pub Arc<Mutex<Vec<(String, f64)>>>);

/// Diagnostics the plugin publishes, in milliseconds of GPU time (the SDK's timestamp queries):
/// the scene's sync and BVH builds (frames that change the scene), AO traced and denoised (all
/// cameras), the shadow traced and denoised (all cameras), the GI traced and denoised with the
/// lit frame's injection into the cache (all cameras; the reflections read the cache too, and
/// its injection counts here where a camera traces only reflections), the reflections traced
/// and denoised (all cameras), and the SDK's whole frame.
pub const DIAGNOSTIC_PATHS: [&str; 6] =
    ["hybrid_rt/scene", "hybrid_rt/ao", "hybrid_rt/shadow", "hybrid_rt/gi", "hybrid_rt/reflections", "hybrid_rt/frame"];

/// Diagnostics of each of the SDK's tasks, in milliseconds of GPU time per frame (all cameras):
/// this prefix and the task's name (`hybrid_rt::TaskKind::name`), e.g.
/// `hybrid_rt/task/denoise_diffuse` — how [`DIAGNOSTIC_PATHS`]' sums split.
pub const DIAGNOSTIC_TASK_PREFIX: &str = "hybrid_rt/task/";

/// Diagnostic: how many cameras hold an AO denoiser history (about 8 bytes a pixel of the
/// view, besides the view's shared denoising guide). A camera's history is freed a few frames after it stops
/// being traced (despawned, `RayTracedAo` removed or disabled).
pub const DIAGNOSTIC_AO_HISTORIES: &str = "hybrid_rt/ao_histories";

/// Diagnostic: how many cameras hold a shadow denoiser history, freed as the AO's are.
pub const DIAGNOSTIC_SHADOW_HISTORIES: &str = "hybrid_rt/shadow_histories";

/// Diagnostic: how many cameras hold a GI denoiser history, freed as the AO's are.
pub const DIAGNOSTIC_GI_HISTORIES: &str = "hybrid_rt/gi_histories";

/// Diagnostic: how many cameras hold a reflections denoiser history, freed as the AO's are.
pub const DIAGNOSTIC_REFLECTIONS_HISTORIES: &str = "hybrid_rt/reflections_histories";

impl Plugin for HybridRtPlugin {
    fn build(&self, app: &mut App) {
        let timings = HybridRtTimings::default();
        app.add_plugins((
            ExtractComponentPlugin::<RayTracedAo>::default(),
            ExtractComponentPlugin::<RayTracedShadow>::default(),
            ExtractComponentPlugin::<RayTracedGi>::default(),
            ExtractComponentPlugin::<RayTracedReflections>::default(),
        ))
        .insert_resource(timings.clone());
        for path in DIAGNOSTIC_PATHS {
            app.register_diagnostic(Diagnostic::new(DiagnosticPath::new(path)).with_suffix(" ms"));
        }
        for kind in hybrid_rt::TaskKind::ALL {
            let path = format!("{DIAGNOSTIC_TASK_PREFIX}{}", kind.name());
            app.register_diagnostic(Diagnostic::new(DiagnosticPath::new(path)).with_suffix(" ms"));
        }
        for path in
            [DIAGNOSTIC_AO_HISTORIES, DIAGNOSTIC_SHADOW_HISTORIES, DIAGNOSTIC_GI_HISTORIES, DIAGNOSTIC_REFLECTIONS_HISTORIES]
        {
            app.register_diagnostic(Diagnostic::new(DiagnosticPath::new(path)));
        }
        app.add_systems(Update, publish_timings);
        render::build(app, timings);
    }
}

/// Main world: the GPU times the render world collected, as diagnostics.
fn publish_timings(timings: Res<HybridRtTimings>, mut diagnostics: Diagnostics) {
    let mut t = timings.0.lock();
    for (name, ms) in t.drain(..) {
        let path = DiagnosticPath::new(format!("hybrid_rt/{name}"));
        diagnostics.add_measurement(&path, || ms);
    }
}
