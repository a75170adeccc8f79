//! Scene tasks: geometries (a mesh → one BLAS), instances (a geometry + a transform → a TLAS
//! entry and a direct-lighting cache) and the throttled BVH build.
use super::handles::{GeometryHandle, InstanceHandle};
use super::inputs::ImageInput;
use ash::vk;
use glam::Affine3A;

/// Register creates the BLAS input; Update replaces it (refit for `allow_update` geometry,
/// otherwise a throttled rebuild).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum TaskOperation {
    /// Registers the geometry (its first task). Default.
    #[default]
    Register = 0,
    /// Replaces its data: a refit for `allow_update` geometry, a queued rebuild otherwise.
    Update = 1,
}

/// A vertex buffer of the engine's, as the engine lays it out: the position may sit anywhere in
/// a larger interleaved vertex (`offset` + `stride`). The SDK copies the vertices out of it
/// while the ticket that registers (or updates) the geometry runs — into a transient staging
/// buffer, from which it keeps only the 12 position bytes of each vertex — so the buffer needs
/// TRANSFER_SRC usage and must stay alive until that ticket comes back; then the engine may
/// free or reuse it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct VertexBufferInput {
    /// The engine's buffer (`TRANSFER_SRC` usage).
    pub buffer: vk::Buffer,
    /// Byte offset of the first vertex's position (any: a sub-range of a shared buffer, or the
    /// position's offset inside an interleaved vertex).
    pub offset: u64,
    /// Bytes between vertices (>= the position's 12 or 16 bytes, a multiple of 4). Default 12.
    pub stride: u64,
    /// Number of vertices (>= 1; a multiple of 3 for non-indexed triangles).
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
    /// Byte offset of the first index (any).
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
    /// Tiles or mesh colors. Default `MeshColors`.
    pub surfel_type: SurfelType,
    /// World units per cache sample along a triangle edge. Default 1.0.
    pub tile_unit_length: f32,
    /// Most samples along one edge. Default 64.
    pub tile_resolution_limit: u32,
    /// Tiles only: one sample per triangle, whatever the triangles' size (Kickstart RT's
    /// direct tile mapping) — for dense meshes, whose triangles are near a tile's size anyway.
    /// Default false.
    pub force_direct_tile_mapping: bool,
    /// Tiles only: a layout whose triangles outnumber `threshold` x its samples (they are
    /// nearly one sample each) is mapped directly instead, one sample per triangle. A layout
    /// never has fewer samples than triangles, so 1.0 or more turns this off, 0 maps every
    /// tiles geometry directly. Default 0.7 (Kickstart RT's).
    pub direct_tile_mapping_threshold: f32,
}

impl Default for SurfelSettings {
    fn default() -> Self {
        SurfelSettings {
            surfel_type: SurfelType::MeshColors,
            tile_unit_length: 1.0,
            tile_resolution_limit: 64,
            force_direct_tile_mapping: false,
            direct_tile_mapping_threshold: 0.7,
        }
    }
}

impl SurfelSettings {
    /// Whether a tiles layout of `triangles` triangles and `samples` samples is (to be) mapped
    /// directly: one sample per triangle.
    pub(crate) fn maps_directly(&self, triangles: u64, samples: u64) -> bool {
        self.maps_directly_from_start()
            || (self.surfel_type == SurfelType::Tiles
                && triangles as f64 > self.direct_tile_mapping_threshold as f64 * samples as f64)
    }

    /// Whether a tiles layout is mapped directly whatever its size: forced, or a threshold of
    /// 0 (every layout has more triangles than 0 x its samples).
    pub(crate) fn maps_directly_from_start(&self) -> bool {
        self.surfel_type == SurfelType::Tiles && (self.force_direct_tile_mapping || self.direct_tile_mapping_threshold == 0.0)
    }
}

/// The vertices a component's indices use, `first..=last` (indices stay relative to the vertex
/// buffer's start, as the engine wrote them). Only these vertices are copied: a mesh part that
/// uses 200 vertices of a 100,000-vertex shared buffer copies 200. An index outside the range
/// is a bad index (its triangle is made degenerate and counted, see
/// `ExecuteContext::geometry_invalid_triangles`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct VertexRange {
    /// The first vertex used.
    pub first: u32,
    /// The last vertex used (>= `first`, < the vertex count).
    pub last: u32,
}

/// One part of a geometry: a vertex/index buffer pair and its placement in the geometry. All
/// parts of a geometry go into one BLAS (and one direct-lighting cache).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GeometryComponent {
    /// The positions.
    pub vertices: VertexBufferInput,
    /// The triangles' indices (a null buffer: non-indexed, every three vertices make one).
    pub indices: IndexBufferInput,
    /// Part space to geometry space (applied once, when the part is copied). Must be finite.
    /// Default `None`: identity.
    pub transform: Option<Affine3A>,
    /// Indexed parts: the vertices the indices use, the only ones copied. Default `None`: all
    /// `vertices.count`.
    pub vertex_range: Option<VertexRange>,
    /// Alpha-tested geometry (`GeometryInput::alpha_test`): the texture coordinates, one per
    /// vertex of `vertices` (same indexing, its own stride and offset; `count` >= the
    /// vertices'): R32G32_SFLOAT, R16G16_SFLOAT or R16G16_UNORM. Copied like the positions.
    /// Default `None`; required on every part of an alpha-tested geometry, and of one with
    /// an `albedo_texture`.
    pub uvs: Option<VertexBufferInput>,
    /// Per-vertex diffuse colours for relighting and hit lighting (`GeometryInput::colors`),
    /// one per vertex of `vertices` like `uvs`: R8G8B8A8_UNORM, R16G16B16A16_SFLOAT,
    /// R32G32B32_SFLOAT or R32G32B32A32_SFLOAT (linear; alpha ignored). Default `None`;
    /// required on every part when the first part has them.
    pub colors: Option<VertexBufferInput>,
}

/// An alpha-tested geometry (foliage, fences, grates): rays pass through it where the alpha
/// texture, looked up at the interpolated texture coordinates, is below `cutoff` — in every
/// trace (AO, shadows, GI, reflections, debug views), through an any-hit shader (ray-tracing
/// pipeline) or a candidate test (inline ray queries). Geometries without it stay opaque and
/// never run the test.
///
/// The SDK copies the texture's alpha (one byte per texel, the view's mip level) at
/// registration, with the texture coordinates, into the geometry's compact copy: the engine may
/// free the texture once the registering ticket is back, and the trace binds no texture per
/// geometry. Lookups are nearest-texel and wrap (REPEAT), as a cut-out's sampler usually does.
/// One texture per geometry: split meshes whose parts use different alpha textures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlphaTestInput {
    /// The alpha texture (SAMPLED usage, a read-only layout while the registering ticket
    /// runs): any unorm, sRGB or float colour format; `channel` holds alpha.
    pub texture: ImageInput,
    /// The texture channel holding alpha: 0 (R) ..= 3 (A). Default 3.
    pub channel: u32,
    /// Texels with alpha < cutoff are holes, in [0, 1]. Default 0.5.
    pub cutoff: f32,
}

impl Default for AlphaTestInput {
    fn default() -> Self {
        AlphaTestInput { texture: ImageInput::default(), channel: 3, cutoff: 0.5 }
    }
}

/// A geometry's diffuse-colour texture, for `RelightCacheTask` and hit lighting: the albedo
/// of a point is `InstanceInput::albedo` (a tint: 1 for the texture as it is) x the
/// geometry's per-vertex colour, if any, x this texture at the point's texture coordinates
/// (nearest texel, wrapping) — glTF's base colour x vertex colour x factor.
///
/// The SDK copies the texture at registration into the geometry's copy, box-filtered down to
/// at most `MAX_ALBEDO_TEXTURE_SIZE` texels a side (the cache is far coarser than that), 4
/// bytes a texel, sRGB-encoded: the engine may free the texture once the registering ticket is
/// back, and traces bind no texture per geometry.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AlbedoTextureInput {
    /// SAMPLED usage, a read-only layout while the registering ticket runs; an unorm, sRGB or
    /// float colour format (sRGB views decode to linear, as the SDK reads them). RGB is read.
    pub texture: ImageInput,
}

/// The most texels a side of a geometry's copy of its albedo texture (`AlbedoTextureInput`).
pub const MAX_ALBEDO_TEXTURE_SIZE: u32 = 256;

/// How a geometry's BLAS is built (Vulkan's build-preference flags).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[repr(u32)]
#[non_exhaustive]
pub enum BuildHint {
    /// Static geometry: prefer fast trace, then compact. `allow_update` geometry: prefer fast
    /// build (it is refitted often). Default.
    #[default]
    Auto = 0,
    /// Prefer fast trace (and compact), whatever `allow_update` says.
    PreferFastTrace = 1,
    /// Prefer fast build; no compaction (for geometry rebuilt often, or streamed in a hurry).
    PreferFastBuild = 2,
    /// Prefer low memory: the low-memory flag, then compaction.
    LowMemory = 3,
    /// Build fast in the frame that registers it (twice as fast as fast-trace: a 1M-triangle
    /// mesh 1.06 ms instead of 2.12 on a busy H200), then rebuild it for fast trace
    /// and compact it at a later BVH build, after that build's new registrations (the rebuild
    /// counts against `max_blas_build_count` and in `pending_blas_builds`). For big meshes
    /// streamed in while the camera moves. Static geometry only (`allow_update` geometry is
    /// built fast anyway).
    FastThenTrace = 4,
    /// No preference: neither the fast-trace nor the fast-build flag, the driver's own
    /// trade-off (Kickstart RT's `PreferNone`); compacted when static.
    PreferNone = 5,
}

impl BuildHint {
    /// The Vulkan flags a BLAS of this hint is built with: the hint's preference,
    /// ALLOW_UPDATE for `allow_update` geometry (then always a fast-build preference, except
    /// `PreferFastTrace` and `LowMemory`), ALLOW_COMPACTION where `compacts` says. `first_build`:
    /// `FastThenTrace`'s fast build in the registration frame (its later rebuild: false).
    pub fn build_flags(self, allow_update: bool, first_build: bool) -> vk::BuildAccelerationStructureFlagsKHR {
        use vk::BuildAccelerationStructureFlagsKHR as F;
        let preference = match (self, allow_update) {
            (BuildHint::FastThenTrace, false) if first_build => F::PREFER_FAST_BUILD,
            (BuildHint::Auto, true) | (BuildHint::PreferFastBuild, _) | (BuildHint::FastThenTrace, true) => F::PREFER_FAST_BUILD,
            (BuildHint::Auto, false) | (BuildHint::PreferFastTrace, _) | (BuildHint::FastThenTrace, false) => {
                F::PREFER_FAST_TRACE
            }
            (BuildHint::LowMemory, _) => F::LOW_MEMORY,
            (BuildHint::PreferNone, _) => F::empty(),
        };
        let mut f = preference;
        if allow_update {
            f |= F::ALLOW_UPDATE;
        }
        if self.compacts(allow_update) {
            f |= F::ALLOW_COMPACTION;
        }
        f
    }

    /// Whether a BLAS of this hint is compacted once its compacted size is back: static
    /// geometry, unless it asked for fast builds (compaction is one more copy per build).
    pub fn compacts(self, allow_update: bool) -> bool {
        !allow_update && self != BuildHint::PreferFastBuild
    }
}

/// A mesh: where its positions and indices are, and how it is built and cached.
///
/// The first part is given inline (`vertices`, `indices`, `transform`, `vertex_range`), as most
/// meshes have one; further parts go in `extra_components`. The SDK keeps one compact copy of
/// all parts — 12-byte positions, transformed into geometry space, and 32-bit indices — so
/// tracing costs the same whatever layout the engine's buffers have.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GeometryInput {
    /// The first part's positions.
    pub vertices: VertexBufferInput,
    /// The first part's indices (a null buffer: non-indexed).
    pub indices: IndexBufferInput,
    /// The first part's transform into geometry space. Default `None`: identity.
    pub transform: Option<Affine3A>,
    /// The vertices the first part's indices use. Default `None`: all.
    pub vertex_range: Option<VertexRange>,
    /// The first part's texture coordinates, for `alpha_test` and `albedo_texture`. Default
    /// `None`.
    pub uvs: Option<VertexBufferInput>,
    /// The first part's per-vertex diffuse colours (see `GeometryComponent::colors`). Default
    /// `None`.
    pub colors: Option<VertexBufferInput>,
    /// A diffuse-colour texture for relighting and hit lighting (see `AlbedoTextureInput`):
    /// every part needs `uvs`. Default `None`.
    pub albedo_texture: Option<AlbedoTextureInput>,
    /// Alpha testing (see `AlphaTestInput`): every part needs `uvs`. Default `None`: opaque.
    pub alpha_test: Option<AlphaTestInput>,
    /// Further parts of the same geometry (one BLAS for all). Default empty.
    pub extra_components: Vec<GeometryComponent>,
    /// Deforming/skinned meshes: later updates refit the BLAS in place (same parts, vertex and
    /// triangle counts) instead of queueing a rebuild. Default false.
    pub allow_update: bool,
    /// The BLAS build preference. Default `Auto`.
    pub build_hint: BuildHint,
    /// The direct-lighting cache's resolution on it.
    pub surfels: SurfelSettings,
}

impl GeometryInput {
    /// The first part, as a component.
    pub fn first_component(&self) -> GeometryComponent {
        GeometryComponent {
            vertices: self.vertices,
            indices: self.indices,
            transform: self.transform,
            vertex_range: self.vertex_range,
            uvs: self.uvs,
            colors: self.colors,
        }
    }

    /// Every part, the first one first.
    pub fn components(&self) -> impl Iterator<Item = GeometryComponent> + '_ {
        std::iter::once(self.first_component()).chain(self.extra_components.iter().copied())
    }
}

/// Registers or updates a geometry (`TaskContainer::schedule_geometry`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GeometryTask {
    /// The geometry (from `create_geometry_handles`).
    pub handle: GeometryHandle,
    /// Register or update.
    pub operation: TaskOperation,
    /// Its data.
    pub input: GeometryInput,
}

bitflags::bitflags! {
    /// Which rays see an instance: the bits of its TLAS instance mask, matched against each
    /// task's rays. Combine with `|`; `InstanceInclusionMask::empty()` hides it from all.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    #[repr(transparent)]
    pub struct InstanceInclusionMask: u8 {
        /// Specular reflection rays.
        const REFLECTIONS = 1 << 0;
        /// Diffuse GI rays.
        const DIFFUSE_GI = 1 << 1;
        /// Ambient-occlusion rays.
        const AMBIENT_OCCLUSION = 1 << 2;
        /// Shadow rays (single- and multi-light).
        const SHADOWS = 1 << 3;
        /// The rays that find the surface under each pixel of a lit image to inject.
        const LIGHT_INJECTION = 1 << 4;
        /// Every ray type (the default of an instance).
        const ALL = 0x1f;
    }
}

impl Default for InstanceInclusionMask {
    /// Visible to every ray type.
    fn default() -> Self {
        InstanceInclusionMask::ALL
    }
}

/// What an instance task does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u32)]
pub enum InstanceOperation {
    /// Places a geometry (the instance's first task, or after a `Remove`). Default.
    #[default]
    Register = 0,
    /// Moves it, or gives it another geometry or mask (its cache is kept when the geometry stays).
    Update = 1,
    /// Takes the instance out of the TLAS; the handle stays alive and may be registered again.
    Remove = 2,
}

/// Where and how an instance places its geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstanceInput {
    /// The geometry placed (registered, in this container or before).
    pub geometry: GeometryHandle,
    /// Object to world. Must be finite.
    pub transform: Affine3A,
    /// Default: visible to every ray type.
    pub mask: InstanceInclusionMask,
    /// Colour a new direct-lighting cache starts with (used by the cache). Default black.
    pub initial_tile_color: [f32; 3],
    /// Diffuse albedo (linear RGB, each in 0..=1) that `RelightCacheTask` lights the
    /// instance's cache with, and hit lighting its specular hits. Default 0.5 grey: an engine
    /// that relights gives the real one.
    pub albedo: [f32; 3],
    /// Emitted radiance (linear RGB, each finite and >= 0) that relighting and hit lighting
    /// add to the lit surface (a camera's injection already holds it). Default black.
    pub emission: [f32; 3],
}

impl Default for InstanceInput {
    fn default() -> Self {
        InstanceInput {
            geometry: GeometryHandle::NULL,
            transform: Affine3A::IDENTITY,
            mask: InstanceInclusionMask::ALL,
            initial_tile_color: [0.0; 3],
            albedo: [0.5; 3],
            emission: [0.0; 3],
        }
    }
}

/// Registers, updates or removes an instance (`TaskContainer::schedule_instance`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InstanceTask {
    /// The instance (from `create_instance_handles`).
    pub handle: InstanceHandle,
    /// Register, update or remove.
    pub operation: InstanceOperation,
    /// Its placement (ignored by `Remove`).
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
    /// How many times in a row a TLAS may be refit instead of rebuilt. Default 0: rebuilt
    /// whenever anything changed, as Kickstart RT does. Above 0, a frame whose instances
    /// differ from the TLAS's last full build only by their transforms (none added, removed,
    /// or pointed at another BLAS) refits it — about a quarter of a build's GPU time for a
    /// few thousand instances (more where ray tracing has no dedicated hardware) — and every
    /// `tlas_max_refits + 1`-th such frame rebuilds it, so a tree that grew loose while
    /// instances moved far is rebuilt within that many frames. Refitting suits slow, local
    /// motion (foliage, doors, vehicles in view); instances that jump across the level
    /// make a refit TLAS slow to trace until its rebuild. A TLAS is kept per ticket in
    /// flight; each counts its own refits. A container without a `BvhBuildTask` (render
    /// tasks only) rebuilds a changed TLAS in full and starts the count again.
    pub tlas_max_refits: u32,
}

impl Default for BvhBuildTask {
    fn default() -> Self {
        BvhBuildTask { max_blas_build_count: 4, tlas_max_refits: 0 }
    }
}

#[cfg(test)]
mod build_flag_tests {
    use super::BuildHint;
    use ash::vk::BuildAccelerationStructureFlagsKHR as F;

    #[test]
    fn every_hint_maps_to_its_documented_flags() {
        let cases = [
            (BuildHint::Auto, false, false, F::PREFER_FAST_TRACE | F::ALLOW_COMPACTION),
            (BuildHint::Auto, true, false, F::PREFER_FAST_BUILD | F::ALLOW_UPDATE),
            (BuildHint::PreferFastTrace, true, false, F::PREFER_FAST_TRACE | F::ALLOW_UPDATE),
            (BuildHint::PreferFastBuild, false, false, F::PREFER_FAST_BUILD),
            (BuildHint::LowMemory, false, false, F::LOW_MEMORY | F::ALLOW_COMPACTION),
            (BuildHint::FastThenTrace, false, true, F::PREFER_FAST_BUILD | F::ALLOW_COMPACTION),
            (BuildHint::FastThenTrace, false, false, F::PREFER_FAST_TRACE | F::ALLOW_COMPACTION),
            (BuildHint::FastThenTrace, true, true, F::PREFER_FAST_BUILD | F::ALLOW_UPDATE),
        ];
        for (hint, update, first, want) in cases {
            assert_eq!(hint.build_flags(update, first), want, "{hint:?}, allow_update {update}, first build {first}");
        }
    }
}
