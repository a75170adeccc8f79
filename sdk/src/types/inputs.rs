//! The inputs trace tasks share: engine images, the G-buffer's encodings, the camera, the
//! viewport, ray offsets, and debug visualisations.
//!
//! Compared with Kickstart RT: the camera is given once as `world_to_view` + `view_to_clip`
//! (the SDK derives the inverses, so they cannot disagree); normals may be in world or view
//! space; every image input carries its format and extent so a wrong one is an error at
//! schedule time, not a garbage image.
use ash::vk;
use glam::{Mat3, Mat4};

/// An engine image the SDK reads or writes. The SDK binds `view` as given and never changes the
/// image's layout: `layout` is the layout it is in while the ticket runs.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct ImageInput {
    /// The engine's image (null: no image, for optional inputs).
    pub image: vk::Image,
    /// The view the SDK binds, as given (one mip level, one layer).
    pub view: vk::ImageView,
    /// Format of the view.
    pub format: vk::Format,
    /// Width in pixels (of the view's mip level): the viewport must fit inside it.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Inputs: SHADER_READ_ONLY_OPTIMAL (default), GENERAL, DEPTH_READ_ONLY_OPTIMAL,
    /// DEPTH_STENCIL_READ_ONLY_OPTIMAL or READ_ONLY_OPTIMAL; the image needs SAMPLED usage.
    /// Outputs: GENERAL, with STORAGE usage.
    pub layout: vk::ImageLayout,
    /// The usage flags the image was created with (Vulkan cannot report them, and binding an
    /// image without the usage a task needs is undefined behaviour). Required: inputs need
    /// SAMPLED, outputs STORAGE; empty is refused. Default empty.
    pub usage: vk::ImageUsageFlags,
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
            usage: vk::ImageUsageFlags::empty(),
        }
    }
}

/// What the depth input holds.
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

/// The G-buffer's depth: read through `image` (sampled, nearest) at each viewport pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct DepthInput {
    /// The image (read only; `SAMPLED` usage).
    pub image: ImageInput,
    /// How to read it. Default `ClipSpace`.
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

/// The space the normals are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum NormalSpace {
    /// Default.
    #[default]
    World = 0,
    /// View space of `TraceCommon::camera` (the SDK rotates them to world space).
    View = 1,
    /// Any other space: `NormalInput::normal_to_world` takes a decoded normal to world space
    /// (the result is normalised, so a uniform scale does no harm; for a non-uniform one give
    /// the inverse transpose).
    Custom = 2,
}

/// The G-buffer's normals: the surface normal each secondary ray leaves from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct NormalInput {
    /// The image (read only; `SAMPLED` usage).
    pub image: ImageInput,
    /// The encoding. Default `RgbNormalizedVector`.
    pub normal_type: NormalType,
    /// World (default), view space, or custom (`normal_to_world`).
    pub space: NormalSpace,
    /// `NormalSpace::Custom`: the 3x3 that takes a decoded normal to world space (e.g. an
    /// engine whose G-buffer holds normals in a previous frame's view, or in a z-up basis).
    /// Ignored for the other spaces. Default identity.
    pub normal_to_world: Mat3,
}

/// The pixel rectangle of the images that the task reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct Viewport {
    /// Left edge, in pixels of every image of the task.
    pub x: u32,
    /// Top edge, in pixels.
    pub y: u32,
    /// Width in pixels (1.. the images' width - x).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The rasterizer's viewport depth range (default 0..1 when both are 0).
    pub min_depth: f32,
    /// The far end of that range.
    pub max_depth: f32,
}

impl Viewport {
    /// The whole of a `width` x `height` image, depth range 0..1.
    pub fn full(width: u32, height: u32) -> Viewport {
        Viewport { x: 0, y: 0, width, height, min_depth: 0.0, max_depth: 1.0 }
    }
}

/// The camera the G-buffer was rendered with. The SDK derives the inverses itself.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Camera {
    /// World to view (the camera's inverse pose). Right-handed, the camera looks down -z.
    pub world_to_view: Mat4,
    /// Vulkan clip space: y down, depth 0..1 (standard or reversed, finite or infinite far).
    pub view_to_clip: Mat4,
}

impl Default for Camera {
    fn default() -> Self {
        Camera { world_to_view: Mat4::IDENTITY, view_to_clip: Mat4::IDENTITY }
    }
}

/// How a secondary ray's origin is moved off the G-buffer surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum RayOffsetType {
    /// No offset: the origin is the reconstructed surface point (tests, analytic G-buffers).
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
    /// The method. Default `CameraDistance`.
    pub offset_type: RayOffsetType,
    /// WorldPosition: below this magnitude a float offset is used, above it an integer one.
    pub world_threshold: f32,
    /// WorldPosition: the float offset's scale. Default 1/65536.
    pub world_float_scale: f32,
    /// WorldPosition: the integer (ulp) offset's scale. Default 256.
    pub world_int_scale: f32,
    /// CameraDistance: offset = constant + linear * d + quadratic * d².
    pub cam_constant: f32,
    /// CameraDistance: per unit of distance.
    pub cam_linear: f32,
    /// CameraDistance: per squared unit of distance.
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

/// Surface roughness (perceptual, 0 = mirror .. 1), read by specular traces, the normalized
/// Disney diffuse BRDF and the specular denoiser — one rule for all three, Kickstart RT's:
/// `r = global_roughness * dot(texel, channel_mask)` (`global_roughness` alone without an
/// image), then `clamp(r * roughness_multiplier + min_roughness, min_roughness,
/// max_roughness)`. An engine moving from Kickstart RT keeps its numbers.
///
/// `min_roughness` both lifts and floors: it keeps near-mirrors from aliasing (a 0.05 floor is
/// common in engines whose normal maps have detail below a pixel); `max_roughness` caps how wide
/// a lobe the reflection trace spends rays on (above ~0.6 a reflection is barely
/// distinguishable from the engine's own prefiltered probe). Kickstart RT suggests multiplier
/// 0.5, min 0.1, max 0.4 to limit roughness smoothly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughnessInput {
    /// Optional: leave `image` null to use `global_roughness` everywhere.
    pub image: ImageInput,
    /// Which channels hold roughness. Default R: [1, 0, 0, 0].
    pub channel_mask: [f32; 4],
    /// Multiplier of the image's roughness, or the roughness itself without an image.
    /// Default 1.0 (the guide: set it to 0 to debug mirror reflections first).
    pub global_roughness: f32,
    /// The remap's multiplier (Kickstart RT's `roughnessMultiplier`). Default 1.0.
    pub roughness_multiplier: f32,
    /// The remap's offset and lower clamp, in [0, `max_roughness`]. Default 0.
    pub min_roughness: f32,
    /// The remap's upper clamp, in [`min_roughness`, 1]. Default 1.
    pub max_roughness: f32,
}

impl Default for RoughnessInput {
    fn default() -> Self {
        RoughnessInput {
            image: ImageInput::default(),
            channel_mask: [1.0, 0.0, 0.0, 0.0],
            global_roughness: 1.0,
            roughness_multiplier: 1.0,
            min_roughness: 0.0,
            max_roughness: 1.0,
        }
    }
}

impl RoughnessInput {
    /// Whether a roughness image is given (else `global_roughness` alone).
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
#[non_exhaustive]
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

/// Checkerboard tracing: half the pixels per ticket, the other half reconstructed by the
/// denoiser. The half alternates with the frame (the container's frame index, else the ticket
/// serial), so two successive tickets cover every pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(u32)]
pub enum HalfResolutionMode {
    /// Every pixel. Default.
    #[default]
    Off = 0,
    /// The pixels where x + y + frame is even.
    Checkerboard = 1,
    /// The other half: where x + y + frame is odd. (Two tasks of one frame, one in each
    /// mode, cover every pixel between them.)
    CheckerboardInverted = 2,
}

impl HalfResolutionMode {
    /// Whether only half the pixels are traced.
    pub fn is_on(self) -> bool {
        self != HalfResolutionMode::Off
    }
}

/// The random numbers a trace draws its rays from. The default is what the denoisers are tuned
/// for; the others are for comparing image quality (Kickstart RT's
/// `DebugParameters::randomNumberGenerator`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
#[repr(u32)]
pub enum RandomNumbers {
    /// Each pixel runs a low-discrepancy sequence (R2) across frames, rotated per pixel (per
    /// 8x8 tile, on a lattice, for diffuse and specular rays): the temporal mean of a static
    /// pixel is a stratified estimate, and the denoisers' statistics assume it. AO takes a new
    /// rotation every frame. Default.
    #[default]
    Default = 0,
    /// Independent numbers for every pixel, frame and ray (a hash; Kickstart RT's `XORShift`):
    /// white noise in space and time, the baseline the others are measured against.
    WhiteNoise = 1,
    /// A 64x64 blue-noise tile (void and cluster), shifted per frame and per dimension by an R2
    /// step (Kickstart RT's `BlueNoiseTexture`, whose texture is 128x128x64): a frame's error is
    /// high in spatial frequency, so a small blur removes more of it; frames are independent.
    BlueNoise = 2,
}

/// Inputs every trace task shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceCommon {
    /// The G-buffer depth of the view the rays start from.
    pub depth: DepthInput,
    /// The G-buffer normals (the surfaces the rays leave).
    pub normals: NormalInput,
    /// The pixels traced and written.
    pub viewport: Viewport,
    /// The camera the G-buffer was rendered with.
    pub camera: Camera,
    /// How rays leave the surface. Default `CameraDistance` with the guide's parameters.
    pub ray_offset: RayOffset,
    /// Roughness, for specular traces.
    pub roughness: RoughnessInput,
    /// Specular colour, for specular traces.
    pub specular: SpecularInput,
    /// Optional (leave `image` null for none): pixels whose R channel is >= 0.5 are excluded —
    /// treated as background (sky) by the trace, which writes its "nothing here" value there
    /// (AO 1, shadows lit, radiance 0), and by the denoisers, which neither filter them nor let
    /// them into a neighbourhood or history. For what the depth buffer shows but rays should not
    /// start from: UI, first-person hands, a portal. Any unorm, snorm, sRGB or float colour
    /// format the device can sample (R8_UNORM, R8_SNORM, R8G8B8A8_SRGB, B8G8R8A8_UNORM,
    /// R16_UNORM, R16G16B16A16_UNORM, R16_SFLOAT, R32_SFLOAT, packed formats such as
    /// A2B10G10R10_UNORM_PACK32, ...); integer and depth/stencil formats are refused
    /// (`Error::UnsupportedFormat`), as is a format the device cannot sample.
    pub input_mask: ImageInput,
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
    /// Checkerboard: trace only half the pixels (half the rays); the others keep their
    /// previous contents, for the denoiser to fill. Successive tickets alternate the halves.
    /// Default `Off`.
    pub half_resolution_mode: HalfResolutionMode,
    /// Where the rays' random numbers come from. Default `RandomNumbers::Default`.
    pub random_numbers: RandomNumbers,
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
            input_mask: ImageInput::default(),
            direct_lighting: ImageInput::default(),
            use_inline_rt: false,
            enable_bilinear_sampling: true,
            debug_output: DebugOutput::Default,
            half_resolution_mode: HalfResolutionMode::Off,
            random_numbers: RandomNumbers::Default,
        }
    }
}
