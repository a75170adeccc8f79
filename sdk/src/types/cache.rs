//! Direct-lighting cache tasks: injection of a lit view, relighting from the engine's lights,
//! clears, and transfers between instances (LOD switches).
use super::handles::InstanceHandle;
use super::inputs::{Camera, DepthInput, ImageInput, Viewport};
use super::trace::LightInfo;

/// Bakes a lit image into the direct-lighting caches of the surfaces it shows. Each pixel
/// finds the surface under it (a ray from the camera to the depth buffer's point; the hit must
/// match the depth within 0.5%) and adds its radiance to that surface's nearest cache sample;
/// after the pass every touched sample moves to the mean of its pixels by the running average
/// `value += (mean - value) / min(history + 1, average_window)`. Any number per container,
/// from any view and resolution (a low-resolution "lidar" camera sweeping the scene warms
/// surfaces the main camera has not seen).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectLightingInjectionTask {
    /// The depth of the lit view (the surface under each pixel is found from it).
    pub depth: DepthInput,
    /// The rasterized, lit frame (RGB radiance): RGBA16F/32F, RGBA8, B10G11R11 …, in a
    /// read-only layout with SAMPLED usage.
    pub lit: ImageInput,
    /// The pixels injected.
    pub viewport: Viewport,
    /// The camera the lit view was rendered with.
    pub camera: Camera,
    /// Frames of the running average (>= 1). Default 200, as in the guide: stable, slow to
    /// react; lower it for fast-changing lights.
    pub average_window: f32,
    /// Inject one pixel of every `stride x stride` block (1..=16). Default 1: every pixel.
    /// The pixel taken within the block moves every frame (frame index of the container) and
    /// visits every position of the block in `stride²` frames, so a view at 2 costs a quarter
    /// and still feeds every surface it shows; samples that receive no pixel in a frame keep
    /// their value. Kickstart RT's `injectionResolutionStride`.
    pub injection_resolution_stride: u32,
    /// Kickstart RT's `useInlineRT`. Injection always traces with the ray-tracing pipeline, so
    /// `true` is refused (`Error::InvalidInput`) rather than silently ignored. Default false.
    pub use_inline_rt: bool,
}

impl Default for DirectLightingInjectionTask {
    fn default() -> Self {
        DirectLightingInjectionTask {
            depth: DepthInput::default(),
            lit: ImageInput::default(),
            viewport: Viewport::default(),
            camera: Camera::default(),
            average_window: 200.0,
            injection_resolution_stride: 1,
            use_inline_rt: false,
        }
    }
}

/// Resets an instance's cache to its `initial_tile_color` (no history), without
/// re-registering it. A no-op for an instance whose cache does not exist yet.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ClearCacheTask {
    /// The instance whose cache is reset.
    pub instance: InstanceHandle,
}

/// Copies the lighting of `source`'s cache onto `target`'s, for two instances that cover the
/// same surface with different triangles (switching LODs: the new LOD starts lit instead of
/// cold). For every target sample a ray crosses the surface along the sample's normal from
/// `max_distance` above to `max_distance` below and reads the source's cache where it meets
/// the source; samples whose ray misses the source keep their values. Both instances need
/// their caches (one recording after registration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectLightTransferTask {
    /// The instance whose cache is read.
    pub source: InstanceHandle,
    /// The instance whose cache is written (another instance).
    pub target: InstanceHandle,
    /// How far apart the two surfaces may be, in world units (> 0). Default 0.1.
    pub max_distance: f32,
    /// Interpolate the source's mesh-colors cache. Default true.
    pub enable_bilinear_sampling: bool,
}

impl Default for DirectLightTransferTask {
    fn default() -> Self {
        DirectLightTransferTask {
            source: InstanceHandle::NULL,
            target: InstanceHandle::NULL,
            max_distance: 0.1,
            enable_bilinear_sampling: true,
        }
    }
}

/// Lights cache samples that no camera has injected from the engine's lights, so surfaces seen
/// only in reflections, or by GI rays, or not yet seen at all, get their direct light instead
/// of their `initial_tile_color` (Kickstart RT's guide flies a "lidar" camera around for
/// that). For each sample: one shadow ray per light towards a random point of its extent
/// (the shadow tasks' sampling), and the sample's colour becomes its albedo
/// (`InstanceInput::albedo` x the geometry's vertex colours and albedo texture, where it has
/// them) x the lights' irradiance there (Lambert, no 1/pi: the convention of a lit image
/// `albedo x irradiance`) + `InstanceInput::emission`, averaged over the frames that relit it
/// (up to `history_frames`).
///
/// Injected camera light wins: a sample a camera has injected is never relit, and a relit
/// sample's history is dropped the first time a camera sees it. Each build relights up to
/// `max_samples` samples, walking every instance's cache round-robin across builds (oldest
/// first), so its cost is bounded whatever the scene. Light units: a directional light's
/// `intensity x color` is its irradiance at normal incidence, a point or spot light's its
/// intensity (irradiance = that / d²), in the units of the engine's lit image.
/// The sample's surface is the triangle's front face (counter-clockwise winding, as the
/// engine's vertex order gives it): a plane seen from its back is lit as its front is.
///
/// With `bounce`, each relit sample also gathers one diffuse bounce from the caches: a
/// cosine-distributed ray reads the cache sample it hits (`sky` where it leaves the scene;
/// nothing where the hit's sample is still unlit), and the sample becomes albedo x (direct
/// irradiance + the mean gathered radiance) — the convention of `TraceDiffuseTask`'s output
/// and an engine's `albedo x GI`. The gather reads caches that already hold earlier
/// bounces, so light goes one bounce further per build and the caches converge to the
/// multi-bounce solution (Lumen's and Solari's feedback); camera-injected samples keep the
/// engine's direct light and pass it on.
#[derive(Debug, Clone, PartialEq)]
pub struct RelightCacheTask {
    /// 1..=32 lights (`MAX_SHADOW_LIGHTS`), each with `intensity` and `color`.
    pub lights: Vec<LightInfo>,
    /// Samples relit per build, at most: the cost bound (about 1 ray per sample per light).
    /// 1..=16,777,216. Default 65,536.
    pub max_samples: u32,
    /// Frames a relit sample's average runs over (its noise falls as 1/sqrt of it; a light that
    /// moves takes about this many relights to show). 1..=1024. Default 16.
    pub history_frames: u32,
    /// Gather one diffuse bounce from the caches (see above). Default false.
    pub bounce: bool,
    /// Radiance of bounce rays that leave the scene (each >= 0). Default black.
    pub sky: [f32; 3],
}

impl Default for RelightCacheTask {
    fn default() -> Self {
        RelightCacheTask { lights: Vec::new(), max_samples: 65_536, history_frames: 16, bounce: false, sky: [0.0; 3] }
    }
}

/// The direct-lighting caches' memory (`ExecuteContext::cache_report`), under the budget of
/// `InitSettings::cache_budget_bytes`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CacheReport {
    /// Bytes of the caches held now (32 per sample).
    pub resident_bytes: u64,
    /// The budget (0: none).
    pub budget_bytes: u64,
    /// Placed instances whose geometry has a layout but that hold no cache (evicted, or never
    /// given one for lack of room): they read as their initial colour.
    pub waiting_instances: u32,
    /// Caches evicted since the context was made.
    pub evictions: u64,
    /// Their bytes.
    pub evicted_bytes: u64,
    /// Geometry bytes copied to the host since the context was made, to size surfel layouts:
    /// 0 unless a mesh was too big for the GPU layout passes (more than 65,535 x 256 / 3
    /// triangles on most devices), which the CPU builder then lays out from a copy. Layouts
    /// are sized on the GPU and only their 16-byte sample count comes home with the ticket.
    pub geometry_readback_bytes: u64,
}

/// Most samples one relight task may take (`RelightCacheTask::max_samples`).
pub const MAX_RELIGHT_SAMPLES: u32 = 1 << 24;
