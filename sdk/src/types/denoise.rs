//! Denoising: contexts that own a denoiser's history, and the tasks that filter trace outputs.
//!
//! Kickstart RT hands its noisy images to NVIDIA's NRD (REBLUR/RELAX for radiance, SIGMA for
//! shadows) behind a reduced API. Ours are built in, in the same command buffer and with the
//! same hazard tracking as the trace tasks, so a trace task's output image can be a denoise
//! task's input in the same container with no barrier of the engine's. What the filters do:
//!
//! - **Radiance** (specular, diffuse, both in one pass, and diffuse occlusion), a
//!   ReLAX-like chain of compute passes: temporal accumulation along reprojected history with
//!   disocclusion tests on plane distance and normals and a per-pixel history length; a fast
//!   (few-frame) history beside the slow one, whose local mean ± σ box clamps the slow one so a
//!   moving light or object does not ghost; specular history that follows the *reflected*
//!   point (the virtual position at the hit distance) and accumulates fewer frames the
//!   smoother the surface (a mirror is passed through, sharp); luminance variance from the
//!   history's moving variance, or from the neighbourhood while history is short; then edge-aware
//!   blurs of 8 taps on a rotated disk, as NRD's blur and post-blur (plane, normal,
//!   luminance-variance and roughness stops), whose radius shrinks as a pixel's history grows;
//!   glossy history capped by how far the view turned against the lobe's width (parallax),
//!   and the diffuse history of a surface that moves in the world by how far it turned and
//!   travelled against the distance to what lights it (an orbiting object's GI follows it);
//!   and, for diffuse GI, an anti-firefly cut of each new sample against its pixel's history.
//! - **Shadows** (one light or many), SIGMA-like: the penumbra's width is derived per pixel
//!   from the occluder distance and the light's size (hit distance × angular size), spread to
//!   the lit side of the edge by a neighbourhood search (skipped for the 8x8 tiles with no
//!   occluded sample within its reach: in a sunlit view, most of them), and the visibility is
//!   blurred over a disk of that width with plane and normal stops — contact shadows (small occluder
//!   distance) and hard lights keep hard edges — then stabilised temporally with a
//!   neighbourhood clamp.
//!
//! The passes, by the names their timings carry (`CompletedTask::pass_timings`, with
//! `InitSettings::time_passes`): radiance `temporal` (accumulation and the history clamp),
//! then `blur_1` … `blur_N` for `DenoiserSettings::spatial_passes` = N (`keep` for N = 0: it
//! only keeps the histories and writes the output); shadows `shadow_prep` (penumbra width and
//! its spread), `shadow_blur`, `shadow_temporal`.
//!
//! `half_resolution_mode` resolves a checkerboard trace to full resolution; with no motion
//! vectors the camera matrices reproject (static geometry only: the guide's debugging mode);
//! `DenoisingMethod::SpatialOnly` filters each frame alone (no history), to tell a temporal
//! problem from a spatial one.
use super::handles::DenoisingContextHandle;
use super::inputs::{Camera, DepthInput, HalfResolutionMode, ImageInput, NormalInput, RoughnessInput, TraceCommon, Viewport};
use super::trace::LightInfo;
use ash::vk;

/// Which filter chain a denoising context runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
#[non_exhaustive]
pub enum DenoisingMethod {
    /// Temporal accumulation with reprojection, then spatial filtering (see the
    /// [module documentation](crate::types::denoise)). Default.
    #[default]
    Temporal = 0,
    /// This frame only: the spatial filters with no history (debugging, or content whose
    /// motion cannot be reprojected).
    SpatialOnly = 1,
}

/// What a denoising context filters; each denoise task needs a context of its signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
#[non_exhaustive]
pub enum SignalType {
    /// `TraceSpecularTask` output (RGB radiance, A = hit distance).
    Specular = 0,
    /// `TraceDiffuseTask` output (RGB radiance, A = hit distance). Default.
    #[default]
    Diffuse = 1,
    /// Both, denoised in one pass (`DenoiseSpecularAndDiffuseTask`).
    SpecularAndDiffuse = 2,
    /// `TraceAmbientOcclusionTask` output (R = visibility).
    DiffuseOcclusion = 3,
    /// `TraceShadowTask` output (R = occluder distance, G = visible fraction).
    Shadow = 4,
    /// `TraceMultiShadowTask`'s `packed` output.
    MultiShadow = 5,
}

/// Creates a denoising context: it owns the history images (allocated at `max_width` x
/// `max_height`; a larger viewport needs a new context) of one signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(C)]
pub struct DenoisingContextInput {
    /// 1..=16384 each.
    pub max_width: u32,
    /// Largest height, 1..=16384 (and the device's maxImageDimension2D).
    pub max_height: u32,
    /// Temporal (default) or spatial only.
    pub method: DenoisingMethod,
    /// The signal its tasks denoise.
    pub signal: SignalType,
    /// The camera view it denoises, to share the denoiser's guide with the view's other
    /// contexts (default 0: none). Every denoiser keeps a guide — this frame's and the
    /// previous frame's normal and view distance per pixel, 8 bytes a pixel — to find edges
    /// and disocclusions; the contexts created with the same nonzero `view_id` (the AO,
    /// shadow and radiance contexts of one camera, say) keep one between them. They must have
    /// the same `max_width` and `max_height`, and the denoise tasks of one view in one
    /// container must read the same depth, normals, input mask, viewport and camera (a build
    /// that mixes two cameras under one view id fails). With 0 the context keeps a guide of
    /// its own.
    pub view_id: u32,
}

impl Default for DenoisingContextInput {
    fn default() -> Self {
        DenoisingContextInput {
            max_width: 0,
            max_height: 0,
            method: DenoisingMethod::Temporal,
            signal: SignalType::Diffuse,
            view_id: 0,
        }
    }
}

/// How the motion image encodes where each pixel's surface was in the previous frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum MotionType {
    /// RG = screen-space motion in pixels of the viewport (Kickstart RT's RG_ViewSpace).
    /// Default.
    #[default]
    RgViewSpace = 0,
    /// RG = motion in normalized device coordinates (the viewport spans [-1, 1]).
    RgClipSpace = 1,
    /// RGB = world-space motion of the surface.
    RgbWorldSpace = 2,
}

/// Per-pixel motion vectors. After multiplying by `scale` a vector points from the current
/// position to the previous one (previous − current); engines that store current − previous
/// set a scale of -1 (and flip y for a y-up convention).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionInput {
    /// Optional: leave `image` null to reproject with the camera matrices (static scenes
    /// only, the guide's check that the matrices are right). Read-only layout or GENERAL,
    /// SAMPLED usage; a float format with the channels `motion_type` needs.
    pub image: ImageInput,
    /// What the motion image holds. Default `RgViewSpace` (pixels).
    pub motion_type: MotionType,
    /// Per-component factor. Default [1, 1, 1].
    pub scale: [f32; 3],
}

impl Default for MotionInput {
    fn default() -> Self {
        MotionInput { image: ImageInput::default(), motion_type: MotionType::RgViewSpace, scale: [1.0; 3] }
    }
}

impl MotionInput {
    /// Whether a motion image is given (else the cameras reproject).
    pub fn has_image(&self) -> bool {
        self.image.image != vk::Image::null()
    }
}

/// Tuning shared by the denoisers. The defaults suit 1 ray per pixel at 30-120 frames per
/// second. Each field says which denoisers read it ("radiance": specular, diffuse, specular +
/// diffuse; "AO"; "shadows": single- and multi-light); the others ignore it, and
/// tests/tests/denoise.rs checks that every field changes the image of every denoiser said to
/// read it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct DenoiserSettings {
    /// Longest history, in frames (1..=255): the slow history's running average window.
    /// Default 32. Specular surfaces use fewer as they get smoother (a mirror: 1). All.
    pub max_history_frames: u32,
    /// Window of the fast history whose neighbourhood clamps the slow one (1..=max). Default 4.
    /// Radiance, AO.
    pub fast_history_frames: u32,
    /// Width of the clamping box in standard deviations of the fast history's 3x3
    /// neighbourhood (> 0). Larger: steadier, more lag. Default 2.5 (2.0 darkened glossy
    /// reflections by ~0.5%: at 1 ray per pixel the fast history is skewed, and a narrow box
    /// clips the slow mean from above). Radiance, AO.
    pub history_clamp_sigma: f32,
    /// Spatial passes after the temporal ones (0..=6): each an edge-aware blur of 8 taps on a
    /// disk turned by each pass, the first reaching 16 pixels at a pixel without history,
    /// each next one half as wide, all narrower as the history grows. Default 2 (NRD's blur
    /// and post-blur). Radiance, AO.
    pub spatial_passes: u32,
    /// Luminance stop in standard deviations of the local variance (> 0). Default 4.0.
    /// Diffuse GI's stop is 4x as wide for a pixel without history, narrowing to this by 4
    /// frames: a young pixel's variance is an estimate from a few samples. Radiance, AO.
    pub luminance_sigma: f32,
    /// Normal stop: weights go as dot(n, n')^power (>= 0). Default 64. All.
    pub normal_power: f32,
    /// Plane-distance stop, relative to the view distance (> 0): also the disocclusion
    /// threshold. Default 0.02. All.
    pub plane_distance_sigma: f32,
    /// Cut fireflies: a new diffuse sample more than 10 deviations (and 11x the mean) above
    /// its pixel's history is brought down to that bound; without 4 frames of history, one
    /// more than 8x its brightest neighbour (none where all neighbours are black). Light that
    /// reaches at least 1% of a pixel's rays — a small window, a lamp, a sun patch seen from
    /// afar — passes uncut, so its mean stays unbiased; rarer paths to bright surfaces are
    /// cut. Default true. Diffuse GI (AO and shadows
    /// are bounded signals; a reflection's glints are its signal, and its history is of
    /// another lobe while the view moves: cutting them darkened reflections in motion).
    pub anti_firefly: bool,
    /// Widest penumbra blur radius in pixels (0..=64). Default 24. Shadows.
    pub max_shadow_blur_radius: f32,
    /// Restart a pixel's history where this frame's 5x5 same-surface samples and its fast
    /// history disagree by more than 2.5 deviations (and keep at most the fast window past 2;
    /// reflections, whose samples are heavier-tailed, half a deviation more): a moved object's
    /// contact AO, a light switched on, an object that left a reflection (the reflection's
    /// history is compared where the reflected point was). Diffuse GI also compares its 8x8
    /// workgroup's mean (a light switched on: a change smaller than 1-ray noise over 25 pixels).
    /// Default true. Every radiance signal: AO, diffuse, specular.
    pub anti_lag: bool,
    /// How far (world units) a moving object's occlusion reaches: half the AO trace's
    /// `ray_length` suits the default falloff (power 1: at half the ray length a 0.4 m object
    /// changes AO by under 0.05); the whole ray length for larger objects or steeper
    /// falloffs. While the scene changes (instances moved, added or removed, geometry refit),
    /// AO pixels within this distance of a moving surface — on screen, at that surface's
    /// depth — restart their history every frame and are blurred narrowly, so the contact
    /// shadow of an object sliding over a static floor follows it, noisy rather than late
    /// (without it, 44% of the change of 4 frames of sliding was still missing: the floor's
    /// pixels reproject onto themselves, and no statistic of 1-ray samples sees the change
    /// within a frame). A moving surface is one whose motion vector is more than a pixel off
    /// the camera's motion; without motion vectors, one the last frame did not show there,
    /// while the camera stands still. Its price, only while the scene changes: a small search
    /// pass and the restart (0.03 ms at 2560x1440 on an H200), and noise where the objects
    /// reach. 0 turns this off. Default 0.5 (half of `TraceAmbientOcclusionTask`'s default
    /// ray length). AO.
    pub moving_object_reach: f32,
    /// Extra taps of the first spatial pass for a diffuse pixel with under 4 frames of history
    /// (revealed by a moving camera or object, or restarted by `anti_lag`), on a disk of its
    /// own beside the 8 it shares (0..=32): at one ray per pixel such pixels are the noisiest of
    /// a moving image, its blotches. 16 leaves 3% less error in the sample's GI in motion and a
    /// fifth less noise in a first frame; it costs two texture fetches a tap at those
    /// pixels only, but a GPU runs a pixel's neighbours in lockstep, so a few fresh pixels slow
    /// the pass where they are. Default 0 (off). Diffuse GI.
    pub fresh_history_taps: u32,
}

impl Default for DenoiserSettings {
    fn default() -> Self {
        DenoiserSettings {
            max_history_frames: 32,
            fast_history_frames: 4,
            history_clamp_sigma: 2.5,
            spatial_passes: 2,
            luminance_sigma: 4.0,
            normal_power: 64.0,
            plane_distance_sigma: 0.02,
            anti_firefly: true,
            max_shadow_blur_radius: 24.0,
            anti_lag: true,
            moving_object_reach: 0.5,
            fresh_history_taps: 0,
        }
    }
}

/// Inputs every denoise task shares: the G-buffer the noisy image was traced from, motion,
/// and the cameras.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoisingCommon {
    /// The G-buffer depth the noisy image was traced from.
    pub depth: DepthInput,
    /// The G-buffer normals it was traced from.
    pub normals: NormalInput,
    /// Specular: the roughness the trace used (same rules as `TraceCommon::roughness`).
    pub roughness: RoughnessInput,
    /// Optional: the trace's input mask (`TraceCommon::input_mask`): pixels with R >= 0.5 are
    /// left out of filtering, neighbourhoods and history. Give the traces the same mask.
    pub input_mask: ImageInput,
    /// Motion vectors (optional: leave the image null to reproject with the cameras).
    pub motion: MotionInput,
    /// The pixels denoised (the trace's viewport).
    pub viewport: Viewport,
    /// The camera of this frame, as rendered (jitter included in `view_to_clip`).
    pub camera: Camera,
    /// The camera of the frame the history was made in. None (default): the camera of the
    /// previous task this denoising context recorded.
    pub previous_camera: Option<Camera>,
    /// Sub-pixel offset (pixels) by which this frame's image content is shifted by jitter;
    /// the context remembers the previous one. Only motion vectors need it (engines write
    /// them without jitter). Default [0, 0].
    pub camera_jitter: [f32; 2],
    /// The checkerboard mode the noisy input was traced with in *this* container (the
    /// pattern follows the frame): the other half of the pixels is reconstructed, giving a
    /// full image. Default `Off`.
    pub half_resolution_mode: HalfResolutionMode,
    /// Drop the history (a camera cut, a teleport, a new level). Default false.
    pub reset_history: bool,
    /// Filter settings (documented defaults).
    pub settings: DenoiserSettings,
}

impl DenoisingCommon {
    /// The G-buffer inputs as a trace task has them (the rest default): one conversion for
    /// the validation and the recording of every denoise task, so a G-buffer input added to
    /// both structs is carried in one place.
    pub(crate) fn as_trace_common(&self) -> TraceCommon {
        TraceCommon {
            depth: self.depth,
            normals: self.normals,
            viewport: self.viewport,
            camera: self.camera,
            roughness: self.roughness,
            input_mask: self.input_mask,
            half_resolution_mode: self.half_resolution_mode,
            ..Default::default()
        }
    }
}

impl Default for DenoisingCommon {
    fn default() -> Self {
        DenoisingCommon {
            depth: DepthInput::default(),
            normals: NormalInput::default(),
            roughness: RoughnessInput::default(),
            input_mask: ImageInput::default(),
            motion: MotionInput::default(),
            viewport: Viewport::default(),
            camera: Camera::default(),
            previous_camera: None,
            camera_jitter: [0.0; 2],
            half_resolution_mode: HalfResolutionMode::Off,
            reset_history: false,
            settings: DenoiserSettings::default(),
        }
    }
}

/// The noisy input image: the trace task's output as it wrote it (GENERAL layout, or a
/// read-only one), with SAMPLED usage. The output image (GENERAL, STORAGE usage) may be the
/// input image itself; its RGB receives the denoised radiance, A = 1.
fn general() -> ImageInput {
    ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() }
}

/// Denoises `TraceSpecularTask` output (RGBA16F/32F in and out).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseSpecularTask {
    /// The denoising context (of this task's signal, at least as large as the viewport's far corner).
    pub context: DenoisingContextHandle,
    /// The G-buffer, motion and cameras.
    pub common: DenoisingCommon,
    /// The specular trace's output (RGBA16F/32F, sampled).
    pub input: ImageInput,
    /// The denoised specular (RGBA16F/32F, GENERAL, storage; may be the input).
    pub output: ImageInput,
}

/// Denoises `TraceDiffuseTask` output (RGBA16F/32F in and out).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseDiffuseTask {
    /// The denoising context (of this task's signal, at least as large as the viewport's far corner).
    pub context: DenoisingContextHandle,
    /// The G-buffer, motion and cameras.
    pub common: DenoisingCommon,
    /// The diffuse trace's output (RGBA16F/32F, sampled).
    pub input: ImageInput,
    /// The denoised diffuse (RGBA16F/32F, GENERAL, storage; may be the input).
    pub output: ImageInput,
}

/// Denoises specular and diffuse together: one reprojection and one set of passes for both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseSpecularAndDiffuseTask {
    /// The denoising context (of this task's signal, at least as large as the viewport's far corner).
    pub context: DenoisingContextHandle,
    /// The G-buffer, motion and cameras.
    pub common: DenoisingCommon,
    /// The specular trace's output.
    pub input_specular: ImageInput,
    /// The diffuse trace's output.
    pub input_diffuse: ImageInput,
    /// The denoised specular.
    pub output_specular: ImageInput,
    /// The denoised diffuse.
    pub output_diffuse: ImageInput,
}

/// Denoises `TraceAmbientOcclusionTask` output (R of the input; every channel of the output
/// gets the visibility, A = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseDiffuseOcclusionTask {
    /// The denoising context (of this task's signal, at least as large as the viewport's far corner).
    pub context: DenoisingContextHandle,
    /// The G-buffer, motion and cameras.
    pub common: DenoisingCommon,
    /// The AO trace's output (R = visibility, sampled).
    pub input: ImageInput,
    /// The denoised visibility (GENERAL, storage).
    pub output: ImageInput,
}

/// Denoises `TraceShadowTask` output. `light` must be the light that was traced (its size
/// sets the penumbra widths). Output: visibility in every channel (A = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseShadowTask {
    /// The denoising context (of this task's signal, at least as large as the viewport's far corner).
    pub context: DenoisingContextHandle,
    /// The G-buffer, motion and cameras.
    pub common: DenoisingCommon,
    /// The light the shadow was traced from.
    pub light: LightInfo,
    /// The shadow trace's output (R = occluder distance, G = visibility).
    pub input: ImageInput,
    /// The denoised visibility (GENERAL, storage).
    pub output: ImageInput,
}

/// Denoises `TraceMultiShadowTask`'s `packed` output into one visibility per pixel (the mean
/// over the lights) in every channel of `output` (A = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseMultiShadowTask {
    /// The denoising context (of this task's signal, at least as large as the viewport's far corner).
    pub context: DenoisingContextHandle,
    /// The G-buffer, motion and cameras.
    pub common: DenoisingCommon,
    /// The multi-light trace's `packed` output.
    pub input: ImageInput,
    /// The denoised mean visibility (GENERAL, storage).
    pub output: ImageInput,
}

macro_rules! default_task {
    ($t:ident { $($img:ident),* }) => {
        impl Default for $t {
            fn default() -> Self {
                $t { context: DenoisingContextHandle::NULL, common: DenoisingCommon::default(), $($img: general()),* }
            }
        }
    };
}
default_task!(DenoiseSpecularTask { input, output });
default_task!(DenoiseDiffuseTask { input, output });
default_task!(DenoiseSpecularAndDiffuseTask { input_specular, input_diffuse, output_specular, output_diffuse });
default_task!(DenoiseDiffuseOcclusionTask { input, output });
default_task!(DenoiseMultiShadowTask { input, output });

impl Default for DenoiseShadowTask {
    fn default() -> Self {
        DenoiseShadowTask {
            context: DenoisingContextHandle::NULL,
            common: DenoisingCommon::default(),
            light: LightInfo::default(),
            input: general(),
            output: general(),
        }
    }
}

/// Every denoise task, normalised for recording: one or two (input, output) pairs of one
/// signal type, and the light for single-light shadows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DenoiseJob {
    pub context: DenoisingContextHandle,
    pub signal: SignalType,
    pub common: DenoisingCommon,
    pub inputs: [ImageInput; 2],
    pub outputs: [ImageInput; 2],
    /// 1, or 2 for specular + diffuse (index 0 specular, 1 diffuse).
    pub count: usize,
    pub light: LightInfo,
}

impl DenoiseJob {
    fn one(
        context: DenoisingContextHandle,
        signal: SignalType,
        common: &DenoisingCommon,
        input: &ImageInput,
        output: &ImageInput,
    ) -> DenoiseJob {
        DenoiseJob {
            context,
            signal,
            common: *common,
            inputs: [*input; 2],
            outputs: [*output; 2],
            count: 1,
            light: LightInfo::default(),
        }
    }
}

impl From<&DenoiseSpecularTask> for DenoiseJob {
    fn from(t: &DenoiseSpecularTask) -> Self {
        DenoiseJob::one(t.context, SignalType::Specular, &t.common, &t.input, &t.output)
    }
}
impl From<&DenoiseDiffuseTask> for DenoiseJob {
    fn from(t: &DenoiseDiffuseTask) -> Self {
        DenoiseJob::one(t.context, SignalType::Diffuse, &t.common, &t.input, &t.output)
    }
}
impl From<&DenoiseSpecularAndDiffuseTask> for DenoiseJob {
    fn from(t: &DenoiseSpecularAndDiffuseTask) -> Self {
        DenoiseJob {
            context: t.context,
            signal: SignalType::SpecularAndDiffuse,
            common: t.common,
            inputs: [t.input_specular, t.input_diffuse],
            outputs: [t.output_specular, t.output_diffuse],
            count: 2,
            light: LightInfo::default(),
        }
    }
}
impl From<&DenoiseDiffuseOcclusionTask> for DenoiseJob {
    fn from(t: &DenoiseDiffuseOcclusionTask) -> Self {
        DenoiseJob::one(t.context, SignalType::DiffuseOcclusion, &t.common, &t.input, &t.output)
    }
}
impl From<&DenoiseShadowTask> for DenoiseJob {
    fn from(t: &DenoiseShadowTask) -> Self {
        DenoiseJob { light: t.light, ..DenoiseJob::one(t.context, SignalType::Shadow, &t.common, &t.input, &t.output) }
    }
}
impl From<&DenoiseMultiShadowTask> for DenoiseJob {
    fn from(t: &DenoiseMultiShadowTask) -> Self {
        DenoiseJob::one(t.context, SignalType::MultiShadow, &t.common, &t.input, &t.output)
    }
}
