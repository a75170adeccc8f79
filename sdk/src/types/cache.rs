//! Direct-lighting cache tasks: injection of a lit view, clears, and transfers between
//! instances (LOD switches).
use super::handles::InstanceHandle;
use super::inputs::{Camera, DepthInput, ImageInput, Viewport};

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
    /// Accepted for symmetry with trace tasks; injection always uses the ray-tracing pipeline.
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
