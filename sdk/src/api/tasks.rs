//! Task structs: plain data with documented defaults. The C ABI mirrors each field for field.
//!
//! Compared with Kickstart RT: the camera is given once as `world_to_view` + `view_to_clip`
//! (the SDK derives the inverses, so they cannot disagree); normals may be in world or view
//! space; every image input carries its format and extent so a wrong one is an error at
//! schedule time, not a garbage image.
use super::handles::{GeometryHandle, InstanceHandle};
use ash::vk;
use glam::{Affine3A, Mat4};

// ---------------------------------------------------------------- BVH tasks

/// Register creates the BLAS input; Update replaces it (refit for `allow_update` geometry,
/// otherwise a throttled rebuild).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum TaskOperation {
    #[default]
    Register = 0,
    Update = 1,
}

/// A vertex buffer of the engine's. The SDK copies `count` vertices out of it while the ticket
/// that registers (or updates) the geometry runs, so it must have TRANSFER_SRC usage and stay
/// alive until that ticket comes back; after that the engine may free it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct VertexBufferInput {
    pub buffer: vk::Buffer,
    /// Byte offset of the first vertex's position.
    pub offset: u64,
    /// Bytes between vertices (>= 12, a multiple of 4). Default 12.
    pub stride: u64,
    pub count: u32,
    /// Position format: R32G32B32_SFLOAT (default) or R32G32B32A32_SFLOAT.
    pub format: vk::Format,
}

impl Default for VertexBufferInput {
    fn default() -> Self {
        VertexBufferInput { buffer: vk::Buffer::null(), offset: 0, stride: 12, count: 0, format: vk::Format::R32G32B32_SFLOAT }
    }
}

/// An index buffer of the engine's (same lifetime and usage rules as the vertex buffer).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct IndexBufferInput {
    /// Null for non-indexed triangles (every three vertices make one).
    pub buffer: vk::Buffer,
    pub offset: u64,
    /// Number of indices (a multiple of 3).
    pub count: u32,
    /// R32_UINT (default) or R16_UINT.
    pub format: vk::Format,
}

impl Default for IndexBufferInput {
    fn default() -> Self {
        IndexBufferInput { buffer: vk::Buffer::null(), offset: 0, count: 0, format: vk::Format::R32_UINT }
    }
}

/// How the direct-lighting cache lays out its samples on this geometry (used by the cache).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum SurfelType {
    /// Vertex, edge and face samples shared between neighbouring triangles: bilinear lookups
    /// are continuous across edges. The default, as in Kickstart RT.
    #[default]
    MeshColors = 0,
    /// One warped-barycentric square tile per triangle.
    Tiles = 1,
}

/// Direct-lighting cache resolution for a geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct SurfelSettings {
    pub surfel_type: SurfelType,
    /// World units per cache sample along a triangle edge. Default 1.0.
    pub tile_unit_length: f32,
    /// Most samples along one edge. Default 64.
    pub tile_resolution_limit: u32,
}

impl Default for SurfelSettings {
    fn default() -> Self {
        SurfelSettings { surfel_type: SurfelType::MeshColors, tile_unit_length: 1.0, tile_resolution_limit: 64 }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct GeometryInput {
    pub vertices: VertexBufferInput,
    pub indices: IndexBufferInput,
    /// Deforming/skinned meshes: later updates refit the BLAS in place (same triangle count)
    /// instead of queueing a rebuild. Such BLASes are not compacted. Default false.
    pub allow_update: bool,
    pub surfels: SurfelSettings,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GeometryTask {
    pub handle: GeometryHandle,
    pub operation: TaskOperation,
    pub input: GeometryInput,
}

/// Which rays see an instance (bits of the TLAS instance mask). Combine with `|`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(transparent)]
pub struct InstanceInclusionMask(pub u8);

impl InstanceInclusionMask {
    pub const NONE: Self = Self(0);
    pub const REFLECTIONS: Self = Self(1 << 0);
    pub const DIFFUSE_GI: Self = Self(1 << 1);
    pub const AMBIENT_OCCLUSION: Self = Self(1 << 2);
    pub const SHADOWS: Self = Self(1 << 3);
    pub const LIGHT_INJECTION: Self = Self(1 << 4);
    pub const ALL: Self = Self(0x1f);

    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
}

impl std::ops::BitOr for InstanceInclusionMask {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum InstanceOperation {
    #[default]
    Register = 0,
    Update = 1,
    /// Takes the instance out of the TLAS; the handle stays alive and may be registered again.
    Remove = 2,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstanceInput {
    pub geometry: GeometryHandle,
    /// Object to world. Must be finite.
    pub transform: Affine3A,
    /// Default: visible to every ray type.
    pub mask: InstanceInclusionMask,
    /// Colour a new direct-lighting cache starts with (used by the cache). Default black.
    pub initial_tile_color: [f32; 3],
}

impl Default for InstanceInput {
    fn default() -> Self {
        InstanceInput {
            geometry: GeometryHandle::NULL,
            transform: Affine3A::IDENTITY,
            mask: InstanceInclusionMask::ALL,
            initial_tile_color: [0.0; 3],
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InstanceTask {
    pub handle: InstanceHandle,
    pub operation: InstanceOperation,
    pub input: InstanceInput,
}

/// Builds pending BLASes (at most `max_blas_build_count`, oldest first, so a level load spreads
/// over frames), refits updated deformable ones, and rebuilds the TLAS from every registered
/// instance whose BLAS is ready. Instances still waiting for their BLAS stay out of the TLAS.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(C)]
pub struct BvhBuildTask {
    /// Default 4 (Kickstart RT's default). 0 builds none this frame.
    pub max_blas_build_count: u32,
}

impl Default for BvhBuildTask {
    fn default() -> Self {
        BvhBuildTask { max_blas_build_count: 4 }
    }
}

// ---------------------------------------------------------------- render task inputs

/// An engine image the SDK reads or writes. The SDK binds `view` as given and never changes the
/// image's layout: `layout` is the layout it is in while the ticket runs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct ImageInput {
    pub image: vk::Image,
    pub view: vk::ImageView,
    /// Format of the view.
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    /// Inputs: SHADER_READ_ONLY_OPTIMAL (default), GENERAL, DEPTH_READ_ONLY_OPTIMAL,
    /// DEPTH_STENCIL_READ_ONLY_OPTIMAL or READ_ONLY_OPTIMAL; the image needs SAMPLED usage.
    /// Outputs: GENERAL, with STORAGE usage.
    pub layout: vk::ImageLayout,
}

impl Default for ImageInput {
    fn default() -> Self {
        ImageInput {
            image: vk::Image::null(),
            view: vk::ImageView::null(),
            format: vk::Format::UNDEFINED,
            width: 0,
            height: 0,
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum DepthType {
    /// R holds the hardware depth (after the viewport transform), as rasterized. Default.
    /// Pixels still at the clear value of the far plane (the viewport's `max_depth`, or
    /// `min_depth` for a reversed-Z projection, detected from `view_to_clip`) are background:
    /// trace tasks write their "nothing here" value there (AO: 1).
    #[default]
    ClipSpace = 0,
    /// RGB holds the world-space position.
    WorldPosition = 1,
}

#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct DepthInput {
    pub image: ImageInput,
    pub depth_type: DepthType,
}

impl Default for DepthInput {
    fn default() -> Self {
        DepthInput { image: ImageInput::default(), depth_type: DepthType::ClipSpace }
    }
}

/// The six normal encodings of the integration guide.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum NormalType {
    /// RGB = xyz.
    RgbVector = 0,
    /// RGB = xyz * 0.5 + 0.5. Default.
    #[default]
    RgbNormalizedVector = 1,
    /// RG = octahedral encoding in [-1, 1].
    RgOctahedron = 2,
    /// BA = octahedral encoding in [-1, 1].
    BaOctahedron = 3,
    /// RG = octahedral encoding * 0.5 + 0.5.
    RgNormalizedOctahedron = 4,
    /// BA = octahedral encoding * 0.5 + 0.5.
    BaNormalizedOctahedron = 5,
}

impl NormalType {
    /// Channels the encoding reads (a format must have at least this many).
    pub fn channels_needed(self) -> u32 {
        match self {
            NormalType::RgbVector | NormalType::RgbNormalizedVector => 3,
            NormalType::RgOctahedron | NormalType::RgNormalizedOctahedron => 2,
            NormalType::BaOctahedron | NormalType::BaNormalizedOctahedron => 4,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum NormalSpace {
    /// Default.
    #[default]
    World = 0,
    View = 1,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct NormalInput {
    pub image: ImageInput,
    pub normal_type: NormalType,
    pub space: NormalSpace,
}

/// The pixel rectangle of the images that the task reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct Viewport {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    /// The rasterizer's viewport depth range (default 0..1 when both are 0).
    pub min_depth: f32,
    pub max_depth: f32,
}

impl Viewport {
    pub fn full(width: u32, height: u32) -> Viewport {
        Viewport { x: 0, y: 0, width, height, min_depth: 0.0, max_depth: 1.0 }
    }
}

/// The camera the G-buffer was rendered with. The SDK derives the inverses itself.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Camera {
    pub world_to_view: Mat4,
    /// Vulkan clip space: y down, depth 0..1 (standard or reversed, finite or infinite far).
    pub view_to_clip: Mat4,
}

impl Default for Camera {
    fn default() -> Self {
        Camera { world_to_view: Mat4::IDENTITY, view_to_clip: Mat4::IDENTITY }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum RayOffsetType {
    Disabled = 0,
    /// Offset in the position's own float precision (Ray Tracing Gems ch. 6).
    WorldPosition = 1,
    /// Offset growing with the distance to the camera. Default: it needs no tuning for the
    /// usual camera ranges; with `Disabled`, rays from a rasterized G-buffer hit their own
    /// surface (the guide's "zero reflections in part of the image").
    #[default]
    CameraDistance = 2,
}

/// How secondary rays leave the G-buffer surface. Parameter defaults are the guide's.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct RayOffset {
    pub offset_type: RayOffsetType,
    /// WorldPosition: below this magnitude a float offset is used, above it an integer one.
    pub world_threshold: f32,
    pub world_float_scale: f32,
    pub world_int_scale: f32,
    /// CameraDistance: offset = constant + linear * d + quadratic * d².
    pub cam_constant: f32,
    pub cam_linear: f32,
    pub cam_quadratic: f32,
}

impl Default for RayOffset {
    fn default() -> Self {
        RayOffset {
            offset_type: RayOffsetType::CameraDistance,
            world_threshold: 1.0 / 32.0,
            world_float_scale: 1.0 / 65536.0,
            world_int_scale: 256.0,
            cam_constant: 0.00174,
            cam_linear: -0.0001547,
            cam_quadratic: 0.0000996,
        }
    }
}

/// Surface roughness (perceptual, 0 = mirror .. 1), read by specular traces:
/// `global_roughness * dot(texel, channel_mask)` with an image, `global_roughness` without.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughnessInput {
    /// Optional: leave `image` null to use `global_roughness` everywhere.
    pub image: ImageInput,
    /// Which channels hold roughness. Default R: [1, 0, 0, 0].
    pub channel_mask: [f32; 4],
    /// Multiplier of the image's roughness, or the roughness itself without an image.
    /// Default 1.0 (the guide: set it to 0 to debug mirror reflections first).
    pub global_roughness: f32,
}

impl Default for RoughnessInput {
    fn default() -> Self {
        RoughnessInput { image: ImageInput::default(), channel_mask: [1.0, 0.0, 0.0, 0.0], global_roughness: 1.0 }
    }
}

impl RoughnessInput {
    pub fn has_image(&self) -> bool {
        self.image.image != vk::Image::null()
    }
}

/// The specular colour the specular output is multiplied by (Kickstart RT's convention):
/// `global_metalness * image.rgb`, or `global_metalness` without an image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecularInput {
    /// Optional RGB specular colour (F0); leave `image` null for white.
    pub image: ImageInput,
    /// A scalar factor; 1.0 (default) in most cases, other values to debug without an image.
    pub global_metalness: f32,
}

impl Default for SpecularInput {
    fn default() -> Self {
        SpecularInput { image: ImageInput::default(), global_metalness: 1.0 }
    }
}

/// Debug visualisations. Any mode but `Default` replaces the task's output with an image made
/// by primary rays from the task's camera through the SDK's TLAS (one per pixel centre of the
/// viewport; the G-buffer is not read), into an output with four channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(u32)]
pub enum DebugOutput {
    /// The task's normal output.
    #[default]
    Default = 0,
    /// The direct-lighting cache's colour at the hit (bilinear for mesh colors when
    /// `enable_bilinear_sampling`): what injection has baked so far.
    DirectLightingCache = 1,
    /// A random colour per cache sample (tile cell or mesh-colors lattice point).
    RandomTileColor = 2,
    /// A random colour per instance.
    RandomMeshColor = 3,
    /// The hit distance in every channel (0 where nothing is hit).
    HitT = 4,
    /// The hit's barycentrics (b0, b1, b2) as RGB.
    Barycentrics = 5,
}

/// Inputs every trace task shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceCommon {
    pub depth: DepthInput,
    pub normals: NormalInput,
    pub viewport: Viewport,
    pub camera: Camera,
    pub ray_offset: RayOffset,
    /// Roughness, for specular traces.
    pub roughness: RoughnessInput,
    /// Specular colour, for specular traces.
    pub specular: SpecularInput,
    /// Optional (leave `image` null for none): the lit frame of this view, as a direct-lighting
    /// source for secondary hits. A diffuse or specular hit that lands in the viewport where the
    /// depth shows that surface takes this image's radiance, any other hit the cache's (the
    /// guide's "Direct Lighting Input"). Same formats and layouts as injection's lit image.
    pub direct_lighting: ImageInput,
    /// Trace with inline ray queries (a compute shader) when the device has them; otherwise
    /// (e.g. NVIDIA's Vulkan driver today) the ray-tracing pipeline is used and a warning is
    /// logged once. Both give the same image. Default false.
    pub use_inline_rt: bool,
    /// Interpolate mesh-colors caches between samples (continuous across triangle edges)
    /// instead of taking the nearest sample. Default true (see `TraceCommon::default`).
    pub enable_bilinear_sampling: bool,
    /// Default `DebugOutput::Default`.
    pub debug_output: DebugOutput,
    /// Checkerboard: trace only the pixels where x + y + ticket serial is even (half the
    /// rays); the others keep their previous contents, for the denoiser to fill. Successive
    /// tickets alternate the pattern. Default false.
    pub half_resolution_mode: bool,
}

impl Default for TraceCommon {
    fn default() -> Self {
        TraceCommon {
            depth: DepthInput::default(),
            normals: NormalInput::default(),
            viewport: Viewport::default(),
            camera: Camera::default(),
            ray_offset: RayOffset::default(),
            roughness: RoughnessInput::default(),
            specular: SpecularInput::default(),
            direct_lighting: ImageInput::default(),
            use_inline_rt: false,
            enable_bilinear_sampling: true,
            debug_output: DebugOutput::Default,
            half_resolution_mode: false,
        }
    }
}

/// Ray-traced ambient occlusion. Output: visibility in [0, 1] (1 = unoccluded) written to
/// every channel of `output` (RGB = AO, A = 1) inside the viewport.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceAmbientOcclusionTask {
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

// ---------------------------------------------------------------- direct-lighting cache

/// Bakes a lit image into the direct-lighting caches of the surfaces it shows. Each pixel
/// finds the surface under it (a ray from the camera to the depth buffer's point; the hit must
/// match the depth within 0.5%) and adds its radiance to that surface's nearest cache sample;
/// after the pass every touched sample moves to the mean of its pixels by the running average
/// `value += (mean - value) / min(history + 1, average_window)`. Any number per container,
/// from any view and resolution (a low-resolution "lidar" camera sweeping the scene warms
/// surfaces the main camera has not seen).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectLightingInjectionTask {
    pub depth: DepthInput,
    /// The rasterized, lit frame (RGB radiance): RGBA16F/32F, RGBA8, B10G11R11 …, in a
    /// read-only layout with SAMPLED usage.
    pub lit: ImageInput,
    pub viewport: Viewport,
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
    pub source: InstanceHandle,
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

// ---------------------------------------------------------------- shadows

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum LightType {
    /// Parallel rays (the sun). Default.
    #[default]
    Directional = 0,
    /// An emitting sphere of `radius` at `position`.
    Point = 1,
    /// A point light with a cone; the cone's falloff is the engine's to apply (it does not
    /// change visibility).
    Spot = 2,
}

/// A light, as the engine converts its own to. Size makes soft shadows: the SDK samples the
/// light's extent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightInfo {
    pub light_type: LightType,
    /// Point and spot: world-space centre.
    pub position: glam::Vec3,
    /// Directional and spot: the direction the light travels (need not be normalized).
    pub direction: glam::Vec3,
    /// Directional: apparent diameter in radians (the sun: about 0.0093). 0 = hard shadows.
    pub angular_extent: f32,
    /// Point and spot: radius of the emitting sphere. 0 = hard shadows.
    pub radius: f32,
    /// Spot: inner and outer cone half-angles in radians (kept for the engine's shading).
    pub inner_cone: f32,
    pub outer_cone: f32,
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
        }
    }
}

/// Ray-traced shadows from one light. Output (the integration guide's format): R = distance
/// to the closest occluder, negative where the light is visible; G, when the output has a
/// second channel, = the fraction of rays that reached the light (soft visibility).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceShadowTask {
    pub common: TraceCommon,
    pub light: LightInfo,
    /// GENERAL layout, STORAGE usage: R16_SFLOAT, R32_SFLOAT, R16G16_SFLOAT, R32G32_SFLOAT,
    /// R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT.
    pub output: ImageInput,
    /// Rays per pixel, 1..=64. Default 1 (the guide's one ray per light; denoise it).
    pub rays_per_pixel: u32,
}

impl Default for TraceShadowTask {
    fn default() -> Self {
        TraceShadowTask {
            common: TraceCommon::default(),
            light: LightInfo::default(),
            output: ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() },
            rays_per_pixel: 1,
        }
    }
}

/// Most lights one `TraceMultiShadowTask` traces.
pub const MAX_SHADOW_LIGHTS: usize = 16;

/// Shadows from several lights in one pass (1..=16; each light gets `rays_per_pixel` rays,
/// sampled as in `TraceShadowTask`).
/// - `visibility` (R32_UINT for up to 4 lights, R32G32B32A32_UINT for up to 16): per light, the
///   visible fraction x 255 in 8 bits; light i is in channel i / 4 at bits 8 * (i % 4).
/// - `packed` (RGBA16F/32F), the input of `DenoiseMultiShadowTask`: mean visibility over the
///   lights, mean penumbra width over the occluded rays (world units: occluder distance x the
///   light's angular size; -1 where no ray was occluded), min occluder distance (0 if none),
///   and the surface's distance to the camera.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceMultiShadowTask {
    pub common: TraceCommon,
    pub lights: Vec<LightInfo>,
    pub visibility: ImageInput,
    pub packed: ImageInput,
    /// Rays per pixel and light, 1..=64. Default 1.
    pub rays_per_pixel: u32,
}

impl Default for TraceMultiShadowTask {
    fn default() -> Self {
        let general = ImageInput { layout: vk::ImageLayout::GENERAL, ..Default::default() };
        TraceMultiShadowTask {
            common: TraceCommon::default(),
            lights: Vec::new(),
            visibility: general,
            packed: general,
            rays_per_pixel: 1,
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
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceSpecularTask {
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
}

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
        }
    }
}
