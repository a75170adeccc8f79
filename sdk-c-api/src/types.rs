//! C mirrors of the SDK's task structs, field for field, with the same defaults (each has an
//! `hrt_*_default()` in lib.rs). Vulkan handles and enums are the <vulkan/vulkan.h> types.
//! Matrices are column-major float[16] (as GLSL and glam); transforms are row-major 3x4
//! float[12] (as VkTransformMatrixKHR).
use ash::vk;
use ash::vk::Handle;
use hybrid_rt as rt;
use std::ffi::c_void;

// Vulkan types as the header names them (declared by <vulkan/vulkan.h>, not by cbindgen).
// Non-dispatchable handles are 64-bit on every platform the SDK supports.
pub type VkInstance = *mut c_void;
pub type VkPhysicalDevice = *mut c_void;
pub type VkDevice = *mut c_void;
pub type VkCommandBuffer = *mut c_void;
pub type VkBuffer = u64;
pub type VkImage = u64;
pub type VkImageView = u64;
pub type VkFormat = i32;
pub type VkImageLayout = i32;
pub type PFN_vkGetInstanceProcAddr = *const c_void;

pub type HrtGeometryHandle = u64;
pub type HrtInstanceHandle = u64;
pub type HrtTicket = u64;

pub(crate) fn buffer(b: VkBuffer) -> vk::Buffer {
    vk::Buffer::from_raw(b)
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtInitSettings {
    /// Tickets in flight at once. Default 2.
    pub supported_working_sets: u32,
    /// Initial upload ring bytes per working set. Default 1 MiB.
    pub upload_ring_bytes: u64,
    /// Timed tasks per ticket. Default 64.
    pub max_timed_tasks: u32,
    /// An engine-owned VkPipelineCache the SDK creates its pipelines through (0: none).
    /// Save it with vkGetPipelineCacheData and reload it next run to skip shader compilation.
    pub pipeline_cache: u64,
    /// Queue families recording SDK work (first `queue_family_count`; 2+: SDK memory is
    /// VK_SHARING_MODE_CONCURRENT over them, for BVH work on an async-compute queue).
    pub queue_family_indices: [u32; 4],
    pub queue_family_count: u32,
    /// Most bytes the direct-lighting caches may hold; the least recently used instances'
    /// caches are evicted past it (0: no limit, the default). See hrt_cache_report.
    pub cache_budget_bytes: u64,
}

impl From<rt::InitSettings> for HrtInitSettings {
    fn from(s: rt::InitSettings) -> Self {
        HrtInitSettings {
            supported_working_sets: s.supported_working_sets,
            upload_ring_bytes: s.upload_ring_bytes,
            max_timed_tasks: s.max_timed_tasks,
            pipeline_cache: s.pipeline_cache.as_raw(),
            queue_family_indices: s.queue_family_indices,
            queue_family_count: s.queue_family_count,
            cache_budget_bytes: s.cache_budget_bytes,
        }
    }
}
impl From<&HrtInitSettings> for rt::InitSettings {
    fn from(s: &HrtInitSettings) -> Self {
        rt::InitSettings {
            supported_working_sets: s.supported_working_sets,
            upload_ring_bytes: s.upload_ring_bytes,
            max_timed_tasks: s.max_timed_tasks,
            pipeline_cache: vk::PipelineCache::from_raw(s.pipeline_cache),
            queue_family_indices: s.queue_family_indices,
            queue_family_count: s.queue_family_count,
            cache_budget_bytes: s.cache_budget_bytes,
        }
    }
}

/// The engine's Vulkan objects. The SDK keeps function tables, not ownership.
#[repr(C)]
pub struct HrtContextDesc {
    /// Must be HRT_API_VERSION (checked: a header/library mismatch is an error).
    pub api_version: u32,
    /// The loader's vkGetInstanceProcAddr; NULL loads libvulkan.so.1 itself.
    pub get_instance_proc_addr: PFN_vkGetInstanceProcAddr,
    pub instance: VkInstance,
    pub physical_device: VkPhysicalDevice,
    pub device: VkDevice,
    /// The device extensions the engine enabled (see hrt_required_device_extensions).
    pub enabled_extensions: *const *const std::ffi::c_char,
    pub enabled_extension_count: u32,
    /// VkApplicationInfo::apiVersion of the instance: VK_API_VERSION_1_3 or later.
    pub instance_api_version: u32,
    /// The pNext chain given to vkCreateDevice (a VkDevice cannot be asked which features it
    /// has): your VkPhysicalDeviceFeatures2 after hrt_device_features_merge, or
    /// hrt_device_features_chain. Read during hrt_context_create only.
    pub enabled_features: *const c_void,
    /// VK_EXT_debug_utils is enabled on the instance: the SDK names its objects and labels its
    /// tasks ("hybrid-rt ..."), for RenderDoc, Nsight and validation messages.
    pub debug_utils: bool,
    pub settings: HrtInitSettings,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtTaskOperation {
    HRT_OPERATION_REGISTER = 0,
    HRT_OPERATION_UPDATE = 1,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtInstanceOperation {
    HRT_INSTANCE_REGISTER = 0,
    HRT_INSTANCE_UPDATE = 1,
    HRT_INSTANCE_REMOVE = 2,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtSurfelType {
    HRT_SURFEL_MESH_COLORS = 0,
    HRT_SURFEL_TILES = 1,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtVertexBufferInput {
    /// Needs TRANSFER_SRC usage; read while the registering ticket runs.
    pub buffer: VkBuffer,
    pub offset: u64,
    /// Default 12.
    pub stride: u64,
    pub count: u32,
    /// Default VK_FORMAT_R32G32B32_SFLOAT.
    pub format: VkFormat,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtIndexBufferInput {
    /// VK_NULL_HANDLE for non-indexed triangles.
    pub buffer: VkBuffer,
    pub offset: u64,
    pub count: u32,
    /// Default VK_FORMAT_R32_UINT (or VK_FORMAT_R16_UINT).
    pub format: VkFormat,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtSurfelSettings {
    /// An HrtSurfelType. Default HRT_SURFEL_MESH_COLORS.
    pub surfel_type: u32,
    /// Default 1.0.
    pub tile_unit_length: f32,
    /// Default 64.
    pub tile_resolution_limit: u32,
}

/// One part of a geometry (GeometryComponent): a vertex/index buffer pair, an optional
/// part-to-geometry transform and an optional vertex range.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtGeometryComponent {
    pub vertices: HrtVertexBufferInput,
    pub indices: HrtIndexBufferInput,
    /// Apply `transform` (row-major 3x4, like VkTransformMatrixKHR). Default false: identity.
    pub has_transform: bool,
    pub transform: [f32; 12],
    /// Copy only vertices vertex_range_first..=vertex_range_last (indexed parts). Default false.
    pub has_vertex_range: bool,
    pub vertex_range_first: u32,
    pub vertex_range_last: u32,
    /// Texture coordinates (R32G32_SFLOAT, R16G16_SFLOAT or R16G16_UNORM) when has_uvs: needed
    /// on every part of an alpha-tested or albedo-textured geometry. Default false.
    pub has_uvs: bool,
    pub uvs: HrtVertexBufferInput,
    /// Per-vertex diffuse colours (R8G8B8A8_UNORM, R16G16B16A16_SFLOAT, R32G32B32_SFLOAT or
    /// R32G32B32A32_SFLOAT; linear) when has_colors: on every part when the first has them.
    /// Default false.
    pub has_colors: bool,
    pub colors: HrtVertexBufferInput,
}

/// Alpha testing of a geometry (see the Rust docs of AlphaTestInput): rays pass where the
/// texture's `channel` at the hit's texture coordinates is below `cutoff`.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtAlphaTestInput {
    /// SAMPLED usage, read-only layout while the registering ticket runs.
    pub texture: HrtImageInput,
    /// 0..=3. Default 3 (A).
    pub channel: u32,
    /// Default 0.5.
    pub cutoff: f32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtGeometryInput {
    /// The first part's positions.
    pub vertices: HrtVertexBufferInput,
    /// The first part's indices (VK_NULL_HANDLE buffer: non-indexed).
    pub indices: HrtIndexBufferInput,
    /// The first part's transform (row-major 3x4) when has_transform. Default identity.
    pub has_transform: bool,
    pub transform: [f32; 12],
    /// The first part's vertex range when has_vertex_range. Default all vertices.
    pub has_vertex_range: bool,
    pub vertex_range_first: u32,
    pub vertex_range_last: u32,
    /// The first part's texture coordinates when has_uvs (alpha testing, albedo texture).
    /// Default false.
    pub has_uvs: bool,
    pub uvs: HrtVertexBufferInput,
    /// The first part's per-vertex diffuse colours when has_colors (relighting, hit
    /// lighting). Default false.
    pub has_colors: bool,
    pub colors: HrtVertexBufferInput,
    /// A diffuse-colour texture when has_albedo_texture (see the Rust docs of
    /// AlbedoTextureInput): SAMPLED usage, read-only layout while the registering ticket runs;
    /// every part needs uvs. Default false.
    pub has_albedo_texture: bool,
    pub albedo_texture: HrtImageInput,
    /// Alpha-test the geometry when has_alpha_test. Default false (opaque).
    pub has_alpha_test: bool,
    pub alpha_test: HrtAlphaTestInput,
    /// Further parts: `extra_component_count` structs at `extra_components` (read during
    /// hrt_schedule_geometry only). Default none.
    pub extra_components: *const HrtGeometryComponent,
    pub extra_component_count: u32,
    /// Deformable: updates refit the BLAS. Default false.
    pub allow_update: bool,
    /// An HrtBuildHint. Default HRT_BUILD_HINT_AUTO.
    pub build_hint: u32,
    pub surfels: HrtSurfelSettings,
}

/// How a geometry's BLAS is built (BuildHint).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtBuildHint {
    HRT_BUILD_HINT_AUTO = 0,
    HRT_BUILD_HINT_PREFER_FAST_TRACE = 1,
    HRT_BUILD_HINT_PREFER_FAST_BUILD = 2,
    HRT_BUILD_HINT_LOW_MEMORY = 3,
    /// Fast build when registered, rebuilt for fast trace (and compacted) at a later BVH build.
    HRT_BUILD_HINT_FAST_THEN_TRACE = 4,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtGeometryTask {
    pub handle: HrtGeometryHandle,
    /// An HrtTaskOperation.
    pub operation: u32,
    pub input: HrtGeometryInput,
}

/// Bits of HrtInstanceInput::mask.
pub const HRT_MASK_REFLECTIONS: u32 = 1;
pub const HRT_MASK_DIFFUSE_GI: u32 = 2;
pub const HRT_MASK_AMBIENT_OCCLUSION: u32 = 4;
pub const HRT_MASK_SHADOWS: u32 = 8;
pub const HRT_MASK_LIGHT_INJECTION: u32 = 16;
pub const HRT_MASK_ALL: u32 = 31;

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtInstanceInput {
    pub geometry: HrtGeometryHandle,
    /// Object to world, row-major 3x4. Default identity.
    pub transform: [f32; 12],
    /// HRT_MASK_* bits. Default HRT_MASK_ALL.
    pub mask: u32,
    /// Default black.
    pub initial_tile_color: [f32; 3],
    /// Diffuse albedo for HrtRelightCacheTask and hit lighting (each 0..=1). Default 0.5 grey.
    pub albedo: [f32; 3],
    /// Emitted radiance relighting and hit lighting add (each finite, >= 0). Default black.
    pub emission: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtInstanceTask {
    pub handle: HrtInstanceHandle,
    /// An HrtInstanceOperation.
    pub operation: u32,
    pub input: HrtInstanceInput,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtBvhBuildTask {
    /// Default 4.
    pub max_blas_build_count: u32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtImageInput {
    pub image: VkImage,
    pub view: VkImageView,
    pub format: VkFormat,
    pub width: u32,
    pub height: u32,
    /// Inputs: VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL (default) or another read-only layout;
    /// outputs: VK_IMAGE_LAYOUT_GENERAL.
    pub layout: VkImageLayout,
    /// The VkImageUsageFlags the image was created with (required: inputs need
    /// VK_IMAGE_USAGE_SAMPLED_BIT, outputs VK_IMAGE_USAGE_STORAGE_BIT; 0 is refused).
    pub usage: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDepthType {
    HRT_DEPTH_CLIP_SPACE = 0,
    HRT_DEPTH_WORLD_POSITION = 1,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtNormalType {
    HRT_NORMAL_RGB_VECTOR = 0,
    HRT_NORMAL_RGB_NORMALIZED_VECTOR = 1,
    HRT_NORMAL_RG_OCTAHEDRON = 2,
    HRT_NORMAL_BA_OCTAHEDRON = 3,
    HRT_NORMAL_RG_NORMALIZED_OCTAHEDRON = 4,
    HRT_NORMAL_BA_NORMALIZED_OCTAHEDRON = 5,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtNormalSpace {
    HRT_NORMAL_SPACE_WORLD = 0,
    HRT_NORMAL_SPACE_VIEW = 1,
    /// HrtNormalInput.normal_to_world takes decoded normals to world space.
    HRT_NORMAL_SPACE_CUSTOM = 2,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtRayOffsetType {
    HRT_RAY_OFFSET_DISABLED = 0,
    HRT_RAY_OFFSET_WORLD_POSITION = 1,
    HRT_RAY_OFFSET_CAMERA_DISTANCE = 2,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDepthInput {
    pub image: HrtImageInput,
    /// An HrtDepthType. Default HRT_DEPTH_CLIP_SPACE.
    pub depth_type: u32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtNormalInput {
    pub image: HrtImageInput,
    /// An HrtNormalType. Default HRT_NORMAL_RGB_NORMALIZED_VECTOR.
    pub normal_type: u32,
    /// An HrtNormalSpace. Default HRT_NORMAL_SPACE_WORLD.
    pub space: u32,
    /// HRT_NORMAL_SPACE_CUSTOM: column-major 3x3 to world space. Default identity.
    pub normal_to_world: [f32; 9],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtViewport {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    /// 0 and 0 mean 0..1.
    pub min_depth: f32,
    pub max_depth: f32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtCamera {
    /// Column-major.
    pub world_to_view: [f32; 16],
    /// Column-major, Vulkan clip space (y down, depth 0..1, standard or reversed).
    pub view_to_clip: [f32; 16],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtRayOffset {
    /// An HrtRayOffsetType. Default HRT_RAY_OFFSET_CAMERA_DISTANCE.
    pub offset_type: u32,
    pub world_threshold: f32,
    pub world_float_scale: f32,
    pub world_int_scale: f32,
    pub cam_constant: f32,
    pub cam_linear: f32,
    pub cam_quadratic: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDebugOutput {
    HRT_DEBUG_DEFAULT = 0,
    HRT_DEBUG_DIRECT_LIGHTING_CACHE = 1,
    HRT_DEBUG_RANDOM_TILE_COLOR = 2,
    HRT_DEBUG_RANDOM_MESH_COLOR = 3,
    HRT_DEBUG_HIT_T = 4,
    HRT_DEBUG_BARYCENTRICS = 5,
}

/// Roughness: clamp(global_roughness * dot(texel, channel_mask), min_roughness, max_roughness)
/// with an image (image != 0), clamp(global_roughness, min, max) without.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtRoughnessInput {
    /// Optional (image = VK_NULL_HANDLE for none).
    pub image: HrtImageInput,
    /// Default {1, 0, 0, 0}.
    pub channel_mask: [f32; 4],
    /// The multiplier. Default 1.0.
    pub global_roughness: f32,
    /// Default 0.
    pub min_roughness: f32,
    /// Default 1.
    pub max_roughness: f32,
}

/// Specular colour: global_metalness * image.rgb (image != 0), global_metalness without.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtSpecularInput {
    pub image: HrtImageInput,
    /// Default 1.0.
    pub global_metalness: f32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceCommon {
    pub depth: HrtDepthInput,
    pub normals: HrtNormalInput,
    pub viewport: HrtViewport,
    pub camera: HrtCamera,
    pub ray_offset: HrtRayOffset,
    pub roughness: HrtRoughnessInput,
    pub specular: HrtSpecularInput,
    /// Optional (image = VK_NULL_HANDLE for none): pixels with R >= 0.5 are excluded from the
    /// trace (written as background).
    pub input_mask: HrtImageInput,
    /// Optional lit frame (image = VK_NULL_HANDLE for none): secondary hits on screen take
    /// its radiance, others the cache's.
    pub direct_lighting: HrtImageInput,
    /// Default false.
    pub use_inline_rt: bool,
    /// Interpolate mesh-colors caches. Default true.
    pub enable_bilinear_sampling: bool,
    /// An HrtDebugOutput. Default HRT_DEBUG_DEFAULT.
    pub debug_output: u32,
    /// Checkerboard: half the pixels per ticket, alternating. Default false.
    pub half_resolution_mode: bool,
}

/// Bakes a lit view into the direct-lighting caches (see the Rust docs of
/// DirectLightingInjectionTask).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDirectLightingInjectionTask {
    pub depth: HrtDepthInput,
    /// The lit frame (RGB radiance), read-only layout, SAMPLED usage.
    pub lit: HrtImageInput,
    pub viewport: HrtViewport,
    pub camera: HrtCamera,
    /// Frames of the running average, >= 1. Default 200.
    pub average_window: f32,
    /// Default false (injection always uses the ray-tracing pipeline).
    pub use_inline_rt: bool,
}

/// Copies one instance's cached lighting onto another covering the same surface (LODs).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtDirectLightTransferTask {
    pub source: HrtInstanceHandle,
    pub target: HrtInstanceHandle,
    /// World-space distance the two surfaces may be apart (> 0). Default 0.1.
    pub max_distance: f32,
    /// Default true.
    pub enable_bilinear_sampling: bool,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtLightType {
    HRT_LIGHT_DIRECTIONAL = 0,
    HRT_LIGHT_POINT = 1,
    HRT_LIGHT_SPOT = 2,
}

/// A light (see the Rust docs of LightInfo).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtLightInfo {
    /// An HrtLightType. Default HRT_LIGHT_DIRECTIONAL.
    pub light_type: u32,
    pub position: [f32; 3],
    /// The direction the light travels. Default (0, -1, 0).
    pub direction: [f32; 3],
    /// Directional: apparent diameter in radians. Default 0 (hard).
    pub angular_extent: f32,
    /// Point/spot: emitter radius. Default 0 (hard).
    pub radius: f32,
    /// Spot: full strength inside this half-angle (radians). Default 0.5.
    pub inner_cone: f32,
    /// Spot: unlit outside this half-angle (< pi/2). Default 0.6.
    pub outer_cone: f32,
    /// Point/spot: influence ends at this distance; 0 = unlimited (default).
    pub range: f32,
    /// Weight in the multi-light mean (>= 0); HrtRelightCacheTask's brightness. Default 1.
    pub intensity: f32,
    /// Linear RGB (each >= 0), used by HrtRelightCacheTask. Default white.
    pub color: [f32; 3],
}

/// One light of an HrtTraceMultiShadowTask written on its own, in HrtTraceShadowTask's output
/// format (for a DenoiseShadow task).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtLightShadowOutput {
    /// Index into the task's lights.
    pub light: u32,
    pub output: HrtImageInput,
}

/// Shadows from one light: R = closest occluder distance, negative where visible; G (if
/// present) = fraction of rays that reached the light.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceShadowTask {
    pub common: HrtTraceCommon,
    pub light: HrtLightInfo,
    /// GENERAL layout, STORAGE usage, a float format.
    pub output: HrtImageInput,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// Stop at the first occluder found (R is then an occluder's distance, >= the closest).
    /// Default false.
    pub first_hit: bool,
}

/// Diffuse GI shaded from the cache: RGB = mean incoming radiance (E/pi, multiply by albedo),
/// A = mean hit distance.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceDiffuseTask {
    pub common: HrtTraceCommon,
    /// GENERAL layout, STORAGE usage, RGBA16F or RGBA32F.
    pub output: HrtImageInput,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// Default 1000.
    pub ray_length: f32,
    /// Radiance of rays that hit nothing. Default black.
    pub miss_radiance: [f32; 3],
    /// An HrtDiffuseBrdfType. Default HRT_DIFFUSE_LAMBERTIAN.
    pub brdf: u32,
    /// Optional (environment.image = VK_NULL_HANDLE: none): what misses see.
    pub environment: HrtEnvironmentInput,
}

/// A lat-long environment map for rays that miss (see the Rust docs of EnvironmentInput):
/// u = 0.5 + atan2(d.x, -d.z) / 2pi, v = acos(d.y) / pi, bilinear, u wraps.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtEnvironmentInput {
    /// Any size, SAMPLED usage, a read-only layout.
    pub image: HrtImageInput,
    /// Column-major rotation: the map's frame in world space. Default identity.
    pub rotation: [f32; 9],
    /// Default 1.
    pub intensity: f32,
}

pub(crate) fn environment(e: &HrtEnvironmentInput) -> rt::EnvironmentInput {
    rt::EnvironmentInput { image: image(&e.image), rotation: glam::Mat3::from_cols_array(&e.rotation), intensity: e.intensity }
}

pub(crate) fn environment_default() -> HrtEnvironmentInput {
    let d = rt::EnvironmentInput::default();
    HrtEnvironmentInput { image: image_c(&d.image), rotation: d.rotation.to_cols_array(), intensity: d.intensity }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtDiffuseBrdfType {
    HRT_DIFFUSE_LAMBERTIAN = 0,
    HRT_DIFFUSE_NORMALIZED_DISNEY = 1,
}

/// Specular reflections shaded from the cache (see the Rust docs of TraceSpecularTask).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceSpecularTask {
    pub common: HrtTraceCommon,
    /// GENERAL layout, STORAGE usage, RGBA16F or RGBA32F.
    pub output: HrtImageInput,
    /// 1..=64 (mirrors trace one). Default 1.
    pub rays_per_pixel: u32,
    /// Default 1000.
    pub ray_length: f32,
    /// Default black.
    pub miss_radiance: [f32; 3],
    /// Largest luminance of one sample; 0 = off (default).
    pub firefly_clamp: f32,
    /// Optional (image = VK_NULL_HANDLE for none): the output without the specular colour.
    pub demodulated_output: HrtImageInput,
    /// Optional (environment.image = VK_NULL_HANDLE: none): what misses see.
    pub environment: HrtEnvironmentInput,
    /// Optional hit lighting for smooth pixels (hit_lighting.light_count = 0: off, default).
    pub hit_lighting: HrtHitLighting,
}

/// Hit lighting (see the Rust docs of HitLighting): hits of pixels with roughness up to
/// max_roughness are shaded from these lights with shadow rays (HrtInstanceInput.albedo x
/// irradiance + emission) plus an indirect part from the caches (an HrtHitIndirect). The
/// lights are copied when the task is scheduled.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtHitLighting {
    pub lights: *const HrtLightInfo,
    /// 0..=HRT_MAX_SHADOW_LIGHTS (0: off). Default 0.
    pub light_count: u32,
    /// 0..=1. Default 0.1.
    pub max_roughness: f32,
    /// An HrtHitIndirect. Default HRT_HIT_INDIRECT_CACHE_RESIDUAL.
    pub indirect: u32,
    /// Gather rays per hit with HRT_HIT_INDIRECT_GATHER, 1..=HRT_MAX_HIT_GATHER_RAYS. Default 1.
    pub gather_rays: u32,
}

/// HrtHitLighting.indirect (see the Rust docs of HitIndirect).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtHitIndirect {
    /// The cache sample less the listed lights' direct light there (no noise). Default.
    HRT_HIT_INDIRECT_CACHE_RESIDUAL = 0,
    /// gather_rays cosine rays reading the caches (noisy).
    HRT_HIT_INDIRECT_GATHER = 1,
    /// Direct light and emission only.
    HRT_HIT_INDIRECT_NONE = 2,
}

/// Shadows from 1..=16 lights in one pass (see the Rust docs of TraceMultiShadowTask): the
/// lights are copied when the task is scheduled.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceMultiShadowTask {
    pub common: HrtTraceCommon,
    pub lights: *const HrtLightInfo,
    pub light_count: u32,
    /// R32_UINT (<= 4 lights) or R32G32B32A32_UINT: 8 bits of visible fraction per light, lights 0..16.
    pub visibility: HrtImageInput,
    /// Lights 16..32, the same way (image = VK_NULL_HANDLE with 16 lights or fewer).
    pub visibility_high: HrtImageInput,
    /// RGBA16F/32F for the multi-shadow denoiser: irradiance-weighted visibility, ...
    pub packed: HrtImageInput,
    /// The first light_output_count entries: lights written on their own.
    pub light_outputs: [HrtLightShadowOutput; 4],
    /// 0..=HRT_MAX_LIGHT_OUTPUTS. Default 0.
    pub light_output_count: u32,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// First-hit traversal (see HrtTraceShadowTask). Default false.
    pub first_hit: bool,
}

/// Resets an instance's cache to its initial colour.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtClearCacheTask {
    pub instance: HrtInstanceHandle,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTraceAmbientOcclusionTask {
    pub common: HrtTraceCommon,
    /// GENERAL layout, STORAGE usage.
    pub output: HrtImageInput,
    /// Default 1.0.
    pub ray_length: f32,
    /// 1..=64. Default 1.
    pub rays_per_pixel: u32,
    /// > 0. Default 1.0.
    pub falloff_power: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtTaskKind {
    /// All BVH work of the ticket.
    HRT_TASK_BVH = 0,
    HRT_TASK_AMBIENT_OCCLUSION = 1,
    /// Inside HRT_TASK_BVH: batched BLAS builds, refits and compactions.
    HRT_TASK_BLAS_BUILD = 2,
    /// Inside HRT_TASK_BVH: the TLAS build.
    HRT_TASK_TLAS_BUILD = 3,
    HRT_TASK_DIRECT_LIGHTING_INJECTION = 4,
    HRT_TASK_CACHE_UPDATE = 5,
    HRT_TASK_CACHE_TRANSFER = 6,
    HRT_TASK_SHADOW = 7,
    HRT_TASK_DIFFUSE = 8,
    HRT_TASK_SPECULAR = 9,
    HRT_TASK_MULTI_SHADOW = 10,
    HRT_TASK_DENOISE_SPECULAR = 11,
    HRT_TASK_DENOISE_DIFFUSE = 12,
    HRT_TASK_DENOISE_SPECULAR_AND_DIFFUSE = 13,
    HRT_TASK_DENOISE_DIFFUSE_OCCLUSION = 14,
    HRT_TASK_DENOISE_SHADOW = 15,
    HRT_TASK_DENOISE_MULTI_SHADOW = 16,
    HRT_TASK_CACHE_RELIGHT = 17,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTaskTiming {
    pub kind: HrtTaskKind,
    pub task_index: u32,
    pub gpu_ms: f64,
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct HrtAllocationCount {
    pub count: u64,
    pub bytes: u64,
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct HrtResourceAllocations {
    pub geometry_copies: HrtAllocationCount,
    pub blas: HrtAllocationCount,
    pub build_scratch: HrtAllocationCount,
    pub tlas: HrtAllocationCount,
    pub upload_rings: HrtAllocationCount,
    pub pipelines: HrtAllocationCount,
    pub cache: HrtAllocationCount,
    pub readback: HrtAllocationCount,
    /// Denoising contexts' history images.
    pub denoiser: HrtAllocationCount,
}

// ---------------------------------------------------------------- conversions
// C enums arrive as integers: an out-of-range value is an HRT_ERROR_INVALID_INPUT, never UB.

use crate::status::Failure;

/// An HrtBuildHint.
pub(crate) fn build_hint(v: u32) -> Result<rt::BuildHint, Failure> {
    pick(
        "HrtBuildHint",
        v,
        &[
            rt::BuildHint::Auto,
            rt::BuildHint::PreferFastTrace,
            rt::BuildHint::PreferFastBuild,
            rt::BuildHint::LowMemory,
            rt::BuildHint::FastThenTrace,
        ],
    )
}

pub(crate) fn pick<T: Copy>(what: &str, v: u32, table: &[T]) -> Result<T, Failure> {
    table.get(v as usize).copied().ok_or_else(|| {
        Failure(crate::status::HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid {what}: {v} is not a valid enum value"))
    })
}

pub(crate) fn image(i: &HrtImageInput) -> rt::ImageInput {
    rt::ImageInput {
        image: vk::Image::from_raw(i.image),
        view: vk::ImageView::from_raw(i.view),
        format: vk::Format::from_raw(i.format),
        width: i.width,
        height: i.height,
        layout: vk::ImageLayout::from_raw(i.layout),
        usage: vk::ImageUsageFlags::from_raw(i.usage),
    }
}
pub(crate) fn image_c(i: &rt::ImageInput) -> HrtImageInput {
    HrtImageInput {
        image: i.image.as_raw(),
        view: i.view.as_raw(),
        format: i.format.as_raw(),
        width: i.width,
        height: i.height,
        layout: i.layout.as_raw(),
        usage: i.usage.as_raw(),
    }
}

/// Row-major 3x4 (VkTransformMatrixKHR) to glam's affine.
pub(crate) fn affine(m: &[f32; 12]) -> glam::Affine3A {
    glam::Affine3A::from_cols_array(&[m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10], m[3], m[7], m[11]])
}

fn affine_c(t: &glam::Affine3A) -> [f32; 12] {
    let (m, tr) = (t.matrix3, t.translation);
    [m.x_axis.x, m.y_axis.x, m.z_axis.x, tr.x, m.x_axis.y, m.y_axis.y, m.z_axis.y, tr.y, m.x_axis.z, m.y_axis.z, m.z_axis.z, tr.z]
}

fn vertices(v: &HrtVertexBufferInput) -> rt::VertexBufferInput {
    rt::VertexBufferInput {
        buffer: buffer(v.buffer),
        offset: v.offset,
        stride: v.stride,
        count: v.count,
        format: vk::Format::from_raw(v.format),
    }
}

fn indices(i: &HrtIndexBufferInput) -> rt::IndexBufferInput {
    rt::IndexBufferInput { buffer: buffer(i.buffer), offset: i.offset, count: i.count, format: vk::Format::from_raw(i.format) }
}

fn component(c: &HrtGeometryComponent) -> rt::GeometryComponent {
    rt::GeometryComponent {
        vertices: vertices(&c.vertices),
        indices: indices(&c.indices),
        transform: c.has_transform.then(|| affine(&c.transform)),
        vertex_range: c.has_vertex_range.then_some(rt::VertexRange { first: c.vertex_range_first, last: c.vertex_range_last }),
        uvs: c.has_uvs.then(|| vertices(&c.uvs)),
        colors: c.has_colors.then(|| vertices(&c.colors)),
    }
}

/// # Safety
/// `t.input.extra_components` points to `extra_component_count` structs (or the count is 0).
pub(crate) unsafe fn geometry_task(t: &HrtGeometryTask) -> Result<rt::GeometryTask, Failure> {
    let i = &t.input;
    let extra = if i.extra_component_count == 0 {
        Vec::new()
    } else if i.extra_components.is_null() {
        return Err(crate::status::null("HrtGeometryInput.extra_components"));
    } else {
        std::slice::from_raw_parts(i.extra_components, i.extra_component_count as usize).iter().map(component).collect()
    };
    let first = component(&HrtGeometryComponent {
        vertices: i.vertices,
        indices: i.indices,
        has_transform: i.has_transform,
        transform: i.transform,
        has_vertex_range: i.has_vertex_range,
        vertex_range_first: i.vertex_range_first,
        vertex_range_last: i.vertex_range_last,
        has_uvs: i.has_uvs,
        uvs: i.uvs,
        has_colors: i.has_colors,
        colors: i.colors,
    });
    Ok(rt::GeometryTask {
        handle: rt::GeometryHandle(t.handle),
        operation: pick("HrtGeometryTask.operation", t.operation, &[rt::TaskOperation::Register, rt::TaskOperation::Update])?,
        input: rt::GeometryInput {
            vertices: first.vertices,
            indices: first.indices,
            transform: first.transform,
            vertex_range: first.vertex_range,
            uvs: first.uvs,
            colors: first.colors,
            albedo_texture: i.has_albedo_texture.then(|| rt::AlbedoTextureInput { texture: image(&i.albedo_texture) }),
            alpha_test: i.has_alpha_test.then(|| rt::AlphaTestInput {
                texture: image(&i.alpha_test.texture),
                channel: i.alpha_test.channel,
                cutoff: i.alpha_test.cutoff,
            }),
            extra_components: extra,
            allow_update: i.allow_update,
            build_hint: build_hint(i.build_hint)?,
            surfels: rt::SurfelSettings {
                surfel_type: pick(
                    "HrtSurfelSettings.surfel_type",
                    i.surfels.surfel_type,
                    &[rt::SurfelType::MeshColors, rt::SurfelType::Tiles],
                )?,
                tile_unit_length: i.surfels.tile_unit_length,
                tile_resolution_limit: i.surfels.tile_resolution_limit,
            },
        },
    })
}

fn vertices_c(v: &rt::VertexBufferInput) -> HrtVertexBufferInput {
    HrtVertexBufferInput { buffer: 0, offset: v.offset, stride: v.stride, count: v.count, format: v.format.as_raw() }
}

fn indices_c(i: &rt::IndexBufferInput) -> HrtIndexBufferInput {
    HrtIndexBufferInput { buffer: 0, offset: i.offset, count: i.count, format: i.format.as_raw() }
}

pub(crate) fn geometry_component_default() -> HrtGeometryComponent {
    let d = rt::GeometryComponent::default();
    HrtGeometryComponent {
        vertices: vertices_c(&d.vertices),
        indices: indices_c(&d.indices),
        has_transform: d.transform.is_some(),
        transform: affine_c(&d.transform.unwrap_or(glam::Affine3A::IDENTITY)),
        has_vertex_range: d.vertex_range.is_some(),
        vertex_range_first: 0,
        vertex_range_last: 0,
        has_uvs: false,
        uvs: vertices_c(&rt::VertexBufferInput { stride: 8, format: ash::vk::Format::R32G32_SFLOAT, ..Default::default() }),
        has_colors: false,
        colors: vertices_c(&rt::VertexBufferInput { stride: 4, format: ash::vk::Format::R8G8B8A8_UNORM, ..Default::default() }),
    }
}

pub(crate) fn geometry_task_default() -> HrtGeometryTask {
    let d = rt::GeometryTask::default();
    let i = &d.input;
    let c = geometry_component_default();
    HrtGeometryTask {
        handle: 0,
        operation: d.operation as u32,
        input: HrtGeometryInput {
            vertices: c.vertices,
            indices: c.indices,
            has_transform: c.has_transform,
            transform: c.transform,
            has_vertex_range: c.has_vertex_range,
            vertex_range_first: 0,
            vertex_range_last: 0,
            has_uvs: false,
            uvs: c.uvs,
            has_colors: false,
            colors: c.colors,
            has_albedo_texture: false,
            albedo_texture: image_c(&rt::ImageInput::default()),
            has_alpha_test: false,
            alpha_test: {
                let a = rt::AlphaTestInput::default();
                HrtAlphaTestInput { texture: image_c(&a.texture), channel: a.channel, cutoff: a.cutoff }
            },
            extra_components: std::ptr::null(),
            extra_component_count: 0,
            allow_update: i.allow_update,
            build_hint: i.build_hint as u32,
            surfels: HrtSurfelSettings {
                surfel_type: i.surfels.surfel_type as u32,
                tile_unit_length: i.surfels.tile_unit_length,
                tile_resolution_limit: i.surfels.tile_resolution_limit,
            },
        },
    }
}

pub(crate) fn instance_task(t: &HrtInstanceTask) -> Result<rt::InstanceTask, Failure> {
    if t.input.mask > HRT_MASK_ALL {
        return Err(Failure(
            crate::status::HrtStatus::HRT_ERROR_INVALID_INPUT,
            format!("invalid HrtInstanceInput.mask: {:#x} has bits outside HRT_MASK_ALL", t.input.mask),
        ));
    }
    let transform = affine(&t.input.transform);
    Ok(rt::InstanceTask {
        handle: rt::InstanceHandle(t.handle),
        operation: pick(
            "HrtInstanceTask.operation",
            t.operation,
            &[rt::InstanceOperation::Register, rt::InstanceOperation::Update, rt::InstanceOperation::Remove],
        )?,
        input: rt::InstanceInput {
            geometry: rt::GeometryHandle(t.input.geometry),
            transform,
            mask: rt::InstanceInclusionMask::from_bits_truncate(t.input.mask as u8),
            initial_tile_color: t.input.initial_tile_color,
            albedo: t.input.albedo,
            emission: t.input.emission,
        },
    })
}

pub(crate) fn instance_task_default() -> HrtInstanceTask {
    let d = rt::InstanceInput::default();
    HrtInstanceTask {
        handle: 0,
        operation: rt::InstanceOperation::Register as u32,
        input: HrtInstanceInput {
            geometry: 0,
            transform: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            mask: d.mask.bits() as u32,
            initial_tile_color: d.initial_tile_color,
            albedo: d.albedo,
            emission: d.emission,
        },
    }
}

pub(crate) fn trace_common(c: &HrtTraceCommon) -> Result<rt::TraceCommon, Failure> {
    use rt::NormalType as N;
    let o = &c.ray_offset;
    Ok(rt::TraceCommon {
        depth: rt::DepthInput {
            image: image(&c.depth.image),
            depth_type: pick(
                "HrtDepthInput.depth_type",
                c.depth.depth_type,
                &[rt::DepthType::ClipSpace, rt::DepthType::WorldPosition],
            )?,
        },
        normals: rt::NormalInput {
            image: image(&c.normals.image),
            normal_type: pick(
                "HrtNormalInput.normal_type",
                c.normals.normal_type,
                &[
                    N::RgbVector,
                    N::RgbNormalizedVector,
                    N::RgOctahedron,
                    N::BaOctahedron,
                    N::RgNormalizedOctahedron,
                    N::BaNormalizedOctahedron,
                ],
            )?,
            space: pick(
                "HrtNormalInput.space",
                c.normals.space,
                &[rt::NormalSpace::World, rt::NormalSpace::View, rt::NormalSpace::Custom],
            )?,
            normal_to_world: glam::Mat3::from_cols_array(&c.normals.normal_to_world),
        },
        viewport: rt::Viewport {
            x: c.viewport.x,
            y: c.viewport.y,
            width: c.viewport.width,
            height: c.viewport.height,
            min_depth: c.viewport.min_depth,
            max_depth: c.viewport.max_depth,
        },
        camera: rt::Camera {
            world_to_view: glam::Mat4::from_cols_array(&c.camera.world_to_view),
            view_to_clip: glam::Mat4::from_cols_array(&c.camera.view_to_clip),
        },
        ray_offset: rt::RayOffset {
            offset_type: pick(
                "HrtRayOffset.offset_type",
                o.offset_type,
                &[rt::RayOffsetType::Disabled, rt::RayOffsetType::WorldPosition, rt::RayOffsetType::CameraDistance],
            )?,
            world_threshold: o.world_threshold,
            world_float_scale: o.world_float_scale,
            world_int_scale: o.world_int_scale,
            cam_constant: o.cam_constant,
            cam_linear: o.cam_linear,
            cam_quadratic: o.cam_quadratic,
        },
        roughness: rt::RoughnessInput {
            image: image(&c.roughness.image),
            channel_mask: c.roughness.channel_mask,
            global_roughness: c.roughness.global_roughness,
            min_roughness: c.roughness.min_roughness,
            max_roughness: c.roughness.max_roughness,
        },
        specular: rt::SpecularInput { image: image(&c.specular.image), global_metalness: c.specular.global_metalness },
        input_mask: image(&c.input_mask),
        direct_lighting: image(&c.direct_lighting),
        use_inline_rt: c.use_inline_rt,
        enable_bilinear_sampling: c.enable_bilinear_sampling,
        debug_output: pick(
            "HrtTraceCommon.debug_output",
            c.debug_output,
            &[
                rt::DebugOutput::Default,
                rt::DebugOutput::DirectLightingCache,
                rt::DebugOutput::RandomTileColor,
                rt::DebugOutput::RandomMeshColor,
                rt::DebugOutput::HitT,
                rt::DebugOutput::Barycentrics,
            ],
        )?,
        half_resolution_mode: c.half_resolution_mode,
    })
}

pub(crate) fn trace_common_default() -> HrtTraceCommon {
    let d = rt::TraceCommon::default();
    let o = &d.ray_offset;
    HrtTraceCommon {
        depth: HrtDepthInput { image: image_c(&d.depth.image), depth_type: d.depth.depth_type as u32 },
        normals: HrtNormalInput {
            image: image_c(&d.normals.image),
            normal_type: d.normals.normal_type as u32,
            space: d.normals.space as u32,
            normal_to_world: d.normals.normal_to_world.to_cols_array(),
        },
        viewport: HrtViewport { x: 0, y: 0, width: 0, height: 0, min_depth: 0.0, max_depth: 0.0 },
        camera: HrtCamera {
            world_to_view: d.camera.world_to_view.to_cols_array(),
            view_to_clip: d.camera.view_to_clip.to_cols_array(),
        },
        ray_offset: HrtRayOffset {
            offset_type: o.offset_type as u32,
            world_threshold: o.world_threshold,
            world_float_scale: o.world_float_scale,
            world_int_scale: o.world_int_scale,
            cam_constant: o.cam_constant,
            cam_linear: o.cam_linear,
            cam_quadratic: o.cam_quadratic,
        },
        roughness: HrtRoughnessInput {
            image: image_c(&d.roughness.image),
            channel_mask: d.roughness.channel_mask,
            global_roughness: d.roughness.global_roughness,
            min_roughness: d.roughness.min_roughness,
            max_roughness: d.roughness.max_roughness,
        },
        specular: HrtSpecularInput { image: image_c(&d.specular.image), global_metalness: d.specular.global_metalness },
        input_mask: image_c(&d.input_mask),
        direct_lighting: image_c(&d.direct_lighting),
        use_inline_rt: d.use_inline_rt,
        enable_bilinear_sampling: d.enable_bilinear_sampling,
        debug_output: d.debug_output as u32,
        half_resolution_mode: d.half_resolution_mode,
    }
}

pub(crate) fn injection_task(t: &HrtDirectLightingInjectionTask) -> Result<rt::DirectLightingInjectionTask, Failure> {
    // Reuse the trace-common conversion for the shared inputs.
    let common = trace_common(&HrtTraceCommon {
        depth: t.depth,
        normals: trace_common_default().normals,
        viewport: t.viewport,
        camera: t.camera,
        ..trace_common_default()
    })?;
    Ok(rt::DirectLightingInjectionTask {
        depth: common.depth,
        lit: image(&t.lit),
        viewport: common.viewport,
        camera: common.camera,
        average_window: t.average_window,
        use_inline_rt: t.use_inline_rt,
    })
}

pub(crate) fn injection_task_default() -> HrtDirectLightingInjectionTask {
    let d = rt::DirectLightingInjectionTask::default();
    let c = trace_common_default();
    HrtDirectLightingInjectionTask {
        depth: c.depth,
        lit: image_c(&d.lit),
        viewport: c.viewport,
        camera: c.camera,
        average_window: d.average_window,
        use_inline_rt: d.use_inline_rt,
    }
}

pub(crate) fn ao_task(t: &HrtTraceAmbientOcclusionTask) -> Result<rt::TraceAmbientOcclusionTask, Failure> {
    Ok(rt::TraceAmbientOcclusionTask {
        common: trace_common(&t.common)?,
        output: image(&t.output),
        ray_length: t.ray_length,
        rays_per_pixel: t.rays_per_pixel,
        falloff_power: t.falloff_power,
    })
}

pub(crate) fn ao_task_default() -> HrtTraceAmbientOcclusionTask {
    let d = rt::TraceAmbientOcclusionTask::default();
    HrtTraceAmbientOcclusionTask {
        common: trace_common_default(),
        output: image_c(&d.output),
        ray_length: d.ray_length,
        rays_per_pixel: d.rays_per_pixel,
        falloff_power: d.falloff_power,
    }
}

impl From<rt::ResourceAllocations> for HrtResourceAllocations {
    fn from(a: rt::ResourceAllocations) -> Self {
        let c = |x: rt::AllocationCount| HrtAllocationCount { count: x.count, bytes: x.bytes };
        HrtResourceAllocations {
            geometry_copies: c(a.geometry_copies),
            blas: c(a.blas),
            build_scratch: c(a.build_scratch),
            tlas: c(a.tlas),
            upload_rings: c(a.upload_rings),
            pipelines: c(a.pipelines),
            cache: c(a.cache),
            readback: c(a.readback),
            denoiser: c(a.denoiser),
        }
    }
}

pub(crate) fn light(l: &HrtLightInfo) -> Result<rt::LightInfo, Failure> {
    Ok(rt::LightInfo {
        light_type: pick(
            "HrtLightInfo.light_type",
            l.light_type,
            &[rt::LightType::Directional, rt::LightType::Point, rt::LightType::Spot],
        )?,
        position: glam::Vec3::from_array(l.position),
        direction: glam::Vec3::from_array(l.direction),
        angular_extent: l.angular_extent,
        radius: l.radius,
        inner_cone: l.inner_cone,
        outer_cone: l.outer_cone,
        range: l.range,
        intensity: l.intensity,
        color: l.color,
    })
}

pub(crate) fn shadow_task(t: &HrtTraceShadowTask) -> Result<rt::TraceShadowTask, Failure> {
    Ok(rt::TraceShadowTask {
        common: trace_common(&t.common)?,
        light: light(&t.light)?,
        output: image(&t.output),
        rays_per_pixel: t.rays_per_pixel,
        first_hit: t.first_hit,
    })
}

pub(crate) fn multi_shadow_task(
    t: &HrtTraceMultiShadowTask,
    lights: &[HrtLightInfo],
) -> Result<rt::TraceMultiShadowTask, Failure> {
    Ok(rt::TraceMultiShadowTask {
        common: trace_common(&t.common)?,
        lights: lights.iter().map(light).collect::<Result<_, _>>()?,
        visibility: image(&t.visibility),
        visibility_high: image(&t.visibility_high),
        packed: image(&t.packed),
        light_outputs: {
            let n = t.light_output_count as usize;
            if n > t.light_outputs.len() {
                return Err(Failure(
                    crate::HrtStatus::HRT_ERROR_INVALID_INPUT,
                    format!("light_output_count {n}: at most {}", t.light_outputs.len()),
                ));
            }
            t.light_outputs[..n].iter().map(|o| rt::LightShadowOutput { light: o.light, output: image(&o.output) }).collect()
        },
        rays_per_pixel: t.rays_per_pixel,
        first_hit: t.first_hit,
    })
}

pub(crate) fn shadow_task_default() -> HrtTraceShadowTask {
    let d = rt::TraceShadowTask::default();
    let l = &d.light;
    HrtTraceShadowTask {
        common: trace_common_default(),
        light: HrtLightInfo {
            light_type: l.light_type as u32,
            position: l.position.to_array(),
            direction: l.direction.to_array(),
            angular_extent: l.angular_extent,
            radius: l.radius,
            inner_cone: l.inner_cone,
            outer_cone: l.outer_cone,
            range: l.range,
            intensity: l.intensity,
            color: l.color,
        },
        output: image_c(&d.output),
        rays_per_pixel: d.rays_per_pixel,
        first_hit: d.first_hit,
    }
}
