//! Geometry: the vertex and index buffers of a geometry's parts, alpha testing and the albedo
//! texture, the geometry (BLAS) task and the build hints that choose how its BLAS is built.
use super::HrtGeometryHandle;
use crate::args::{get_mut, pick};
use crate::cache::{surfels, surfels_c, HrtSurfelSettings};
use crate::context::{context, schedule, HrtContext, HrtTaskContainer};
use crate::image::{image, image_c, HrtImageInput};
use crate::status::{guard, null, Failure, HrtStatus};
use crate::vulkan::{VkBuffer, VkFormat};
use ash::vk;
use ash::vk::Handle;
use hybrid_rt as rt;

/// The most texels a side of a geometry's copy of its albedo texture (HrtGeometryInput.albedo_texture).
pub const HRT_MAX_ALBEDO_TEXTURE_SIZE: u32 = 256;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrtTaskOperation {
    HRT_OPERATION_REGISTER = 0,
    HRT_OPERATION_UPDATE = 1,
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
    /// No preference flag (the driver's trade-off); compacted when static.
    HRT_BUILD_HINT_PREFER_NONE = 5,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtGeometryTask {
    pub handle: HrtGeometryHandle,
    /// An HrtTaskOperation.
    pub operation: u32,
    pub input: HrtGeometryInput,
}

/// An HrtBuildHint, read from the field or argument `what`.
fn build_hint(what: &str, v: u32) -> Result<rt::BuildHint, Failure> {
    pick(
        what,
        v,
        &[
            rt::BuildHint::Auto,
            rt::BuildHint::PreferFastTrace,
            rt::BuildHint::PreferFastBuild,
            rt::BuildHint::LowMemory,
            rt::BuildHint::FastThenTrace,
            rt::BuildHint::PreferNone,
        ],
    )
}

/// Row-major 3x4 (VkTransformMatrixKHR) to glam's affine.
pub(super) fn affine(m: &[f32; 12]) -> glam::Affine3A {
    glam::Affine3A::from_cols_array(&[m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10], m[3], m[7], m[11]])
}

fn affine_c(t: &glam::Affine3A) -> [f32; 12] {
    let (m, tr) = (t.matrix3, t.translation);
    [m.x_axis.x, m.y_axis.x, m.z_axis.x, tr.x, m.x_axis.y, m.y_axis.y, m.z_axis.y, tr.y, m.x_axis.z, m.y_axis.z, m.z_axis.z, tr.z]
}

fn vertices(v: &HrtVertexBufferInput) -> rt::VertexBufferInput {
    rt::VertexBufferInput {
        buffer: vk::Buffer::from_raw(v.buffer),
        offset: v.offset,
        stride: v.stride,
        count: v.count,
        format: vk::Format::from_raw(v.format),
    }
}

fn indices(i: &HrtIndexBufferInput) -> rt::IndexBufferInput {
    rt::IndexBufferInput {
        buffer: vk::Buffer::from_raw(i.buffer),
        offset: i.offset,
        count: i.count,
        format: vk::Format::from_raw(i.format),
    }
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
unsafe fn geometry_task(t: &HrtGeometryTask) -> Result<rt::GeometryTask, Failure> {
    let i = &t.input;
    let extra = if i.extra_component_count == 0 {
        Vec::new()
    } else if i.extra_components.is_null() {
        return Err(null("HrtGeometryInput.extra_components"));
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
            build_hint: build_hint("HrtGeometryInput.build_hint", i.build_hint)?,
            surfels: surfels(&i.surfels)?,
        },
    })
}

fn vertices_c(v: &rt::VertexBufferInput) -> HrtVertexBufferInput {
    HrtVertexBufferInput { buffer: 0, offset: v.offset, stride: v.stride, count: v.count, format: v.format.as_raw() }
}

fn indices_c(i: &rt::IndexBufferInput) -> HrtIndexBufferInput {
    HrtIndexBufferInput { buffer: 0, offset: i.offset, count: i.count, format: i.format.as_raw() }
}

/// A part for HrtGeometryInput.extra_components with the defaults (identity, all vertices).
#[no_mangle]
pub extern "C" fn hrt_geometry_component_default() -> HrtGeometryComponent {
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
        uvs: vertices_c(&rt::VertexBufferInput { stride: 8, format: vk::Format::R32G32_SFLOAT, ..Default::default() }),
        has_colors: false,
        colors: vertices_c(&rt::VertexBufferInput { stride: 4, format: vk::Format::R8G8B8A8_UNORM, ..Default::default() }),
    }
}

#[no_mangle]
pub extern "C" fn hrt_geometry_task_default() -> HrtGeometryTask {
    let d = rt::GeometryTask::default();
    let i = &d.input;
    let c = hrt_geometry_component_default();
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
            surfels: surfels_c(&i.surfels),
        },
    }
}

#[no_mangle]
pub unsafe extern "C" fn hrt_schedule_geometry(container: *mut HrtTaskContainer, task: *const HrtGeometryTask) -> HrtStatus {
    schedule(
        container,
        task,
        // SAFETY: the header says extra_components points to extra_component_count parts.
        |t| unsafe { geometry_task(t) },
        // SAFETY: the header asks for live buffers and images, alive until the ticket is back.
        |c, t| unsafe { c.schedule_geometry(t) },
    )
}

/// The VkBuildAccelerationStructureFlagsKHR a BLAS of `build_hint` (an HrtBuildHint) is built
/// with (see the Rust docs of BuildHint::build_flags): for static or `allow_update` geometry,
/// and for HRT_BUILD_HINT_FAST_THEN_TRACE's first build.
///
/// # Safety
/// `flags` points to writable memory.
#[no_mangle]
pub unsafe extern "C" fn hrt_build_hint_flags(
    build_hint: u32,
    allow_update: bool,
    first_build: bool,
    flags: *mut u32,
) -> HrtStatus {
    guard(|| {
        let out = get_mut(flags, "flags")?;
        let hint = self::build_hint("hrt_build_hint_flags build_hint", build_hint)?;
        *out = hint.build_flags(allow_update, first_build).as_raw();
        Ok(())
    })
}

/// Triangles of a geometry's last registered or updated data whose indices reach past its
/// vertex count: the SDK made them degenerate (the driver never sees the bad index) and logged
/// a warning. 0 until the ticket that copied the data has come back.
#[no_mangle]
pub unsafe extern "C" fn hrt_geometry_invalid_triangles(
    ctx: *const HrtContext,
    geometry: HrtGeometryHandle,
    triangles: *mut u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        *get_mut(triangles, "triangles")? = c.ctx.geometry_invalid_triangles(rt::GeometryHandle(geometry))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_limit_is_the_sdk_one() {
        assert_eq!(super::HRT_MAX_ALBEDO_TEXTURE_SIZE, hybrid_rt::MAX_ALBEDO_TEXTURE_SIZE);
    }
}
