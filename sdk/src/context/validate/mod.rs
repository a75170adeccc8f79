//! Input checks run when a task is scheduled, so a mistake is reported at the call that made
//! it, with the field's name. Handle *states* (registered or not) are checked again when the
//! container is built, since handles can be destroyed in between.
use crate::context::Shared;
use crate::error::{Error, Result};
use crate::gpu::device::Limits;
use crate::gpu::formats::{FormatSet, OUTPUT_FORMATS};
use crate::types::*;
use ash::vk;
use glam::{Affine3A, Mat4};

mod geometry;
mod lights;
mod many_lights;
pub(crate) use geometry::geometry_input;
use lights::{light, SHADOW_OUTPUT_FORMATS};

/// The checks of a render task's payload when it is scheduled (the task table's
/// `TaskContainer::schedule_*` functions run them before queueing it).
pub(crate) trait Check {
    fn check(&self, shared: &Shared) -> Result<()>;
}

/// A public task as the payload its task-table row queues: a copy of it, or (denoise tasks)
/// the normalised job.
pub(crate) trait ToPayload<P> {
    fn to_payload(&self) -> P;
}

impl<T: Clone> ToPayload<T> for T {
    fn to_payload(&self) -> T {
        self.clone()
    }
}

impl<T> ToPayload<Box<DenoiseJob>> for T
where
    for<'a> &'a T: Into<DenoiseJob>,
{
    fn to_payload(&self) -> Box<DenoiseJob> {
        Box::new(self.into())
    }
}

impl Check for DirectLightTransferTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        shared.check_instance_alive(self.source, "DirectLightTransferTask.source")?;
        shared.check_instance_alive(self.target, "DirectLightTransferTask.target")?;
        if self.source == self.target {
            return Err(Error::invalid("DirectLightTransferTask.target", "is the source instance"));
        }
        if !(self.max_distance.is_finite() && self.max_distance > 0.0) {
            return Err(Error::invalid("DirectLightTransferTask.max_distance", "must be finite and > 0"));
        }
        Ok(())
    }
}

pub(crate) fn transform(what: &'static str, t: &Affine3A) -> Result<()> {
    if !t.is_finite() || t.matrix3.determinant() == 0.0 {
        return Err(Error::InvalidTransform { what });
    }
    Ok(())
}

fn matrix(what: &'static str, m: &Mat4) -> Result<()> {
    let det = m.determinant();
    if !m.is_finite() || !det.is_finite() || det == 0.0 || !m.inverse().is_finite() {
        return Err(Error::InvalidTransform { what });
    }
    Ok(())
}

const INPUT_LAYOUTS: &[vk::ImageLayout] = &[
    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    vk::ImageLayout::GENERAL,
    vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
    vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
    vk::ImageLayout::READ_ONLY_OPTIMAL,
];

/// How a task uses an image: read through a sampler, or written as a storage image.
#[derive(Clone, Copy)]
enum Use {
    Sampled,
    /// Written: in one of the formats the device writes without a format qualifier.
    Storage(FormatSet),
}

fn image(what: &'static str, img: &ImageInput, vp: &Viewport, role: Use) -> Result<()> {
    if img.image == vk::Image::null() || img.view == vk::ImageView::null() {
        return Err(Error::invalid(what, "image or view is null"));
    }
    let (layouts, usage, usage_name): (&[vk::ImageLayout], _, _) = match role {
        Use::Sampled => (INPUT_LAYOUTS, vk::ImageUsageFlags::SAMPLED, "SAMPLED"),
        Use::Storage(_) => (&[vk::ImageLayout::GENERAL], vk::ImageUsageFlags::STORAGE, "STORAGE"),
    };
    // Vulkan cannot tell an image's usage, and binding one without it is undefined behaviour
    // (a crash at descriptor write on some drivers): the engine declares it.
    if img.usage.is_empty() {
        return Err(Error::invalid(what, "usage is empty: declare the flags the image was created with"));
    }
    if !img.usage.contains(usage) {
        return Err(Error::invalid(what, format!("usage {:?} lacks {usage_name}, which this task needs", img.usage)));
    }
    if !layouts.contains(&img.layout) {
        return Err(Error::invalid(what, format!("layout {:?} is not one of {layouts:?}", img.layout)));
    }
    // The shaders declare engine outputs without a format qualifier; Vulkan 1.3 allows that per
    // format (a format outside the output list is refused below, by the task's own list).
    if let Use::Storage(writes) = role {
        if OUTPUT_FORMATS.contains(&img.format) && !writes.contains(img.format) {
            return Err(Error::UnsupportedFormat {
                what,
                format: img.format,
                expected: "a format this device writes without a format qualifier (VK_FORMAT_FEATURE_2_STORAGE_WRITE_WITHOUT_FORMAT_BIT)",
            });
        }
    }
    if vp.x as u64 + vp.width as u64 > img.width as u64 || vp.y as u64 + vp.height as u64 > img.height as u64 {
        return Err(Error::invalid(
            what,
            format!("{}x{} image does not cover the viewport {:?}", img.width, img.height, (vp.x, vp.y, vp.width, vp.height)),
        ));
    }
    Ok(())
}

fn format_in(what: &'static str, f: vk::Format, allowed: &[vk::Format], expected: &'static str) -> Result<()> {
    if allowed.contains(&f) {
        Ok(())
    } else {
        Err(Error::UnsupportedFormat { what, format: f, expected })
    }
}

const CLIP_DEPTH_FORMATS: &[vk::Format] = &[
    vk::Format::D32_SFLOAT,
    vk::Format::D32_SFLOAT_S8_UINT,
    vk::Format::D24_UNORM_S8_UINT,
    vk::Format::X8_D24_UNORM_PACK32,
    vk::Format::D16_UNORM,
    vk::Format::R32_SFLOAT,
    vk::Format::R16_SFLOAT,
    vk::Format::R16_UNORM,
];
const POSITION_FORMATS: &[vk::Format] = &[vk::Format::R32G32B32A32_SFLOAT, vk::Format::R16G16B16A16_SFLOAT];
const NORMAL_FORMATS_2: &[vk::Format] = &[
    vk::Format::R8G8_UNORM,
    vk::Format::R8G8_SNORM,
    vk::Format::R16G16_UNORM,
    vk::Format::R16G16_SNORM,
    vk::Format::R16G16_SFLOAT,
    vk::Format::R32G32_SFLOAT,
];
const NORMAL_FORMATS_3: &[vk::Format] = &[vk::Format::B10G11R11_UFLOAT_PACK32];
const NORMAL_FORMATS_4: &[vk::Format] = &[
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::R8G8B8A8_SNORM,
    vk::Format::B8G8R8A8_UNORM,
    vk::Format::A2B10G10R10_UNORM_PACK32,
    vk::Format::A2R10G10B10_UNORM_PACK32,
    vk::Format::R16G16B16A16_UNORM,
    vk::Format::R16G16B16A16_SNORM,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
];
/// Formats a scalar (AO, shadow) output may have.
pub(crate) const SCALAR_OUTPUT_FORMATS: &[vk::Format] = &[
    vk::Format::R8_UNORM,
    vk::Format::R16_UNORM,
    vk::Format::R16_SFLOAT,
    vk::Format::R32_SFLOAT,
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
];

fn normal_format_ok(f: vk::Format, needed: u32) -> bool {
    NORMAL_FORMATS_4.contains(&f)
        || (needed <= 3 && NORMAL_FORMATS_3.contains(&f))
        || (needed <= 2 && NORMAL_FORMATS_2.contains(&f))
}

/// A width x height launch fits the device: the ray-tracing pipeline's invocation limit, and
/// 8x8 compute groups (inline traces, denoisers) within the group-count limits.
pub(crate) fn dispatch_size(what: &'static str, vp: &Viewport, limits: &Limits) -> Result<()> {
    let invocations = vp.width as u64 * vp.height as u64;
    if invocations > limits.max_ray_dispatch as u64 {
        return Err(Error::invalid(
            what,
            format!("{}x{} exceeds the device's maxRayDispatchInvocationCount {}", vp.width, vp.height, limits.max_ray_dispatch),
        ));
    }
    let groups = [vp.width.div_ceil(8), vp.height.div_ceil(8)];
    if groups[0] > limits.max_dispatch_groups[0] || groups[1] > limits.max_dispatch_groups[1] {
        return Err(Error::invalid(
            what,
            format!(
                "{}x{} needs {groups:?} compute groups, over the device's maxComputeWorkGroupCount {:?}",
                vp.width, vp.height, limits.max_dispatch_groups
            ),
        ));
    }
    Ok(())
}

/// The struct whose G-buffer fields `trace_common` checks: a trace task's `TraceCommon` or a
/// denoise task's `DenoisingCommon` (checked as the `TraceCommon` it converts to), so that an
/// error names the field the user filled.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Common {
    Trace,
    Denoising,
}

/// `field!(on, "depth.image")`: the field's path in the struct `on` names, as a static string.
macro_rules! field {
    ($on:expr, $path:literal) => {
        match $on {
            Common::Trace => concat!("TraceCommon.", $path),
            Common::Denoising => concat!("DenoisingCommon.", $path),
        }
    };
}

pub(crate) fn trace_common(c: &TraceCommon, limits: &Limits, on: Common) -> Result<()> {
    dispatch_size(field!(on, "viewport"), &c.viewport, limits)?;
    let vp = &c.viewport;
    if vp.width == 0 || vp.height == 0 {
        return Err(Error::invalid(field!(on, "viewport"), "has zero width or height"));
    }
    if !(vp.min_depth.is_finite() && vp.max_depth.is_finite()) {
        return Err(Error::invalid(field!(on, "viewport"), "depth range is not finite"));
    }
    image(field!(on, "depth.image"), &c.depth.image, vp, Use::Sampled)?;
    match c.depth.depth_type {
        DepthType::ClipSpace => format_in(
            field!(on, "depth.image.format"),
            c.depth.image.format,
            CLIP_DEPTH_FORMATS,
            "a depth format or R32/R16 single channel (DepthType::ClipSpace)",
        )?,
        DepthType::WorldPosition => format_in(
            field!(on, "depth.image.format"),
            c.depth.image.format,
            POSITION_FORMATS,
            "R32G32B32A32_SFLOAT or R16G16B16A16_SFLOAT (DepthType::WorldPosition)",
        )?,
    }
    image(field!(on, "normals.image"), &c.normals.image, vp, Use::Sampled)?;
    if !normal_format_ok(c.normals.image.format, c.normals.normal_type.channels_needed()) {
        return Err(Error::UnsupportedFormat {
            what: field!(on, "normals.image.format"),
            format: c.normals.image.format,
            expected: "a colour format with the channels the NormalType reads",
        });
    }
    if c.direct_lighting.image != vk::Image::null() {
        image(field!(on, "direct_lighting"), &c.direct_lighting, vp, Use::Sampled)?;
        format_in(field!(on, "direct_lighting.format"), c.direct_lighting.format, LIT_FORMATS, "an RGB(A) colour format")?;
    }
    let r = &c.roughness;
    if r.has_image() {
        image(field!(on, "roughness.image"), &r.image, vp, Use::Sampled)?;
        if !NORMAL_FORMATS_4.contains(&r.image.format)
            && !NORMAL_FORMATS_2.contains(&r.image.format)
            && !matches!(
                r.image.format,
                vk::Format::R8_UNORM | vk::Format::R16_UNORM | vk::Format::R16_SFLOAT | vk::Format::R32_SFLOAT
            )
        {
            return Err(Error::UnsupportedFormat {
                what: field!(on, "roughness.image.format"),
                format: r.image.format,
                expected: "a 1-, 2- or 4-channel unorm/float format",
            });
        }
    }
    if !(r.global_roughness.is_finite() && r.global_roughness >= 0.0) || r.channel_mask.iter().any(|m| !m.is_finite()) {
        return Err(Error::invalid(field!(on, "roughness"), "global_roughness must be finite and >= 0, the mask finite"));
    }
    if !r.roughness_multiplier.is_finite() {
        return Err(Error::invalid(field!(on, "roughness.roughness_multiplier"), "must be finite"));
    }
    // NaN fails every comparison, so `!(..)` also refuses it.
    if !(0.0 <= r.min_roughness && r.min_roughness <= r.max_roughness && r.max_roughness <= 1.0) {
        return Err(Error::invalid(field!(on, "roughness"), "needs 0 <= min_roughness <= max_roughness <= 1"));
    }
    if c.normals.space == NormalSpace::Custom {
        let m = &c.normals.normal_to_world;
        let det = m.determinant();
        if !m.is_finite() || !det.is_finite() || det.abs() < 1e-12 {
            return Err(Error::InvalidTransform { what: field!(on, "normals.normal_to_world") });
        }
    }
    if c.input_mask.image != vk::Image::null() {
        image(field!(on, "input_mask"), &c.input_mask, vp, Use::Sampled)?;
        if !limits.mask_formats.contains(c.input_mask.format) {
            return Err(Error::UnsupportedFormat {
                what: field!(on, "input_mask.format"),
                format: c.input_mask.format,
                expected: "a unorm, snorm, sRGB or float colour format the device can sample",
            });
        }
    }
    matrix(field!(on, "camera.world_to_view"), &c.camera.world_to_view)?;
    matrix(field!(on, "camera.view_to_clip"), &c.camera.view_to_clip)?;
    matrix(field!(on, "camera (view_to_clip * world_to_view)"), &(c.camera.view_to_clip * c.camera.world_to_view))?;
    let o = &c.ray_offset;
    let params = [o.world_threshold, o.world_float_scale, o.world_int_scale, o.cam_constant, o.cam_linear, o.cam_quadratic];
    if params.iter().any(|p| !p.is_finite()) {
        return Err(Error::invalid(field!(on, "ray_offset"), "has a non-finite parameter"));
    }
    Ok(())
}

pub(crate) fn output_image(
    what: &'static str,
    img: &ImageInput,
    vp: &Viewport,
    formats: &[vk::Format],
    limits: &Limits,
) -> Result<()> {
    image(what, img, vp, Use::Storage(limits.write_formats))?;
    format_in(what, img.format, formats, "R8/R16/R32 single channel or an RGBA 8/16/32-bit format")
}

/// Formats a debug visualisation (colour) may be written to.
pub(crate) const COLOR_OUTPUT_FORMATS: &[vk::Format] =
    &[vk::Format::R8G8B8A8_UNORM, vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT];

impl Check for TraceAmbientOcclusionTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        trace_common(&t.common, limits, Common::Trace)?;
        if t.common.debug_output != DebugOutput::Default {
            image("TraceAmbientOcclusionTask.output", &t.output, &t.common.viewport, Use::Storage(limits.write_formats))?;
            format_in(
                "TraceAmbientOcclusionTask.output (debug output)",
                t.output.format,
                COLOR_OUTPUT_FORMATS,
                "R8G8B8A8_UNORM, R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT for a debug visualisation",
            )?;
        } else {
            output_image("TraceAmbientOcclusionTask.output", &t.output, &t.common.viewport, SCALAR_OUTPUT_FORMATS, limits)?;
        }
        if !(t.ray_length.is_finite() && t.ray_length > 0.0) {
            return Err(Error::invalid("TraceAmbientOcclusionTask.ray_length", "must be finite and > 0"));
        }
        if !(1..=64).contains(&t.rays_per_pixel) {
            return Err(Error::invalid(
                "TraceAmbientOcclusionTask.rays_per_pixel",
                format!("{} is not in 1..=64", t.rays_per_pixel),
            ));
        }
        if !(t.falloff_power.is_finite() && t.falloff_power > 0.0) {
            return Err(Error::invalid("TraceAmbientOcclusionTask.falloff_power", "must be finite and > 0"));
        }
        Ok(())
    }
}

const LIT_FORMATS: &[vk::Format] = &[
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::R8G8B8A8_SRGB,
    vk::Format::B8G8R8A8_UNORM,
    vk::Format::B8G8R8A8_SRGB,
    vk::Format::A2B10G10R10_UNORM_PACK32,
    vk::Format::B10G11R11_UFLOAT_PACK32,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
];

impl Check for DirectLightingInjectionTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        let common = TraceCommon { depth: t.depth, viewport: t.viewport, camera: t.camera, ..Default::default() };
        let vp = &t.viewport;
        if vp.width == 0 || vp.height == 0 {
            return Err(Error::invalid("DirectLightingInjectionTask.viewport", "has zero width or height"));
        }
        if !(vp.min_depth.is_finite() && vp.max_depth.is_finite()) {
            return Err(Error::invalid("DirectLightingInjectionTask.viewport", "depth range is not finite"));
        }
        dispatch_size("DirectLightingInjectionTask.viewport", vp, limits)?;
        if t.use_inline_rt {
            return Err(Error::invalid(
                "DirectLightingInjectionTask.use_inline_rt",
                "injection traces with the ray-tracing pipeline only; leave it false",
            ));
        }
        image("DirectLightingInjectionTask.depth.image", &t.depth.image, vp, Use::Sampled)?;
        let depth_formats = if t.depth.depth_type == DepthType::ClipSpace { CLIP_DEPTH_FORMATS } else { POSITION_FORMATS };
        format_in(
            "DirectLightingInjectionTask.depth.image.format",
            t.depth.image.format,
            depth_formats,
            "a depth format matching depth_type",
        )?;
        image("DirectLightingInjectionTask.lit", &t.lit, vp, Use::Sampled)?;
        format_in("DirectLightingInjectionTask.lit.format", t.lit.format, LIT_FORMATS, "an RGB(A) colour format")?;
        matrix("DirectLightingInjectionTask.camera.world_to_view", &common.camera.world_to_view)?;
        matrix("DirectLightingInjectionTask.camera.view_to_clip", &common.camera.view_to_clip)?;
        if !(t.average_window.is_finite() && t.average_window >= 1.0) {
            return Err(Error::invalid("DirectLightingInjectionTask.average_window", "must be finite and >= 1"));
        }
        if !(1..=MAX_INJECTION_STRIDE).contains(&t.injection_resolution_stride) {
            return Err(Error::invalid("DirectLightingInjectionTask.injection_resolution_stride", "must be 1..=16"));
        }
        Ok(())
    }
}

/// The largest `DirectLightingInjectionTask::injection_resolution_stride`.
const MAX_INJECTION_STRIDE: u32 = 16;

/// Environment maps: formats the shader reads as colour (any size; RGB used).
const ENVIRONMENT_FORMATS: &[vk::Format] = &[
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::B10G11R11_UFLOAT_PACK32,
    vk::Format::E5B9G9R9_UFLOAT_PACK32,
    vk::Format::R8G8B8A8_UNORM,
    vk::Format::R8G8B8A8_SRGB,
    vk::Format::B8G8R8A8_UNORM,
    vk::Format::B8G8R8A8_SRGB,
    vk::Format::A2B10G10R10_UNORM_PACK32,
];

fn environment(what: &'static str, e: &EnvironmentInput) -> Result<()> {
    if !e.has_image() {
        return Ok(());
    }
    // Any size: the map is looked up by direction, not by pixel.
    let whole = Viewport::full(e.image.width, e.image.height);
    if e.image.width == 0 || e.image.height == 0 {
        return Err(Error::invalid(what, "has zero width or height"));
    }
    image(what, &e.image, &whole, Use::Sampled)?;
    format_in(what, e.image.format, ENVIRONMENT_FORMATS, "an RGBA float/unorm, B10G11R11 or E5B9G9R9 format")?;
    let r = &e.rotation;
    // A rotation: orthonormal columns (to float precision) and no mirroring.
    if !r.is_finite() || !(*r * r.transpose()).abs_diff_eq(glam::Mat3::IDENTITY, 1e-3) || r.determinant() < 0.0 {
        return Err(Error::InvalidTransform { what: "EnvironmentInput.rotation (must be a rotation)" });
    }
    if !(e.intensity.is_finite() && e.intensity >= 0.0) {
        return Err(Error::invalid(what, "intensity must be finite and >= 0"));
    }
    Ok(())
}

impl Check for TraceDiffuseTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        trace_common(&t.common, limits, Common::Trace)?;
        environment("TraceDiffuseTask.environment", &t.environment)?;
        image("TraceDiffuseTask.output", &t.output, &t.common.viewport, Use::Storage(limits.write_formats))?;
        format_in(
            "TraceDiffuseTask.output",
            t.output.format,
            &[vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT],
            "R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT",
        )?;
        if !(1..=64).contains(&t.rays_per_pixel) {
            return Err(Error::invalid("TraceDiffuseTask.rays_per_pixel", format!("{} is not in 1..=64", t.rays_per_pixel)));
        }
        if !(t.ray_length.is_finite() && t.ray_length > 0.0) {
            return Err(Error::invalid("TraceDiffuseTask.ray_length", "must be finite and > 0"));
        }
        if t.miss_radiance.iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(Error::invalid("TraceDiffuseTask.miss_radiance", "must be finite and >= 0"));
        }
        Ok(())
    }
}

impl Check for TraceSpecularTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        trace_common(&t.common, limits, Common::Trace)?;
        environment("TraceSpecularTask.environment", &t.environment)?;
        image("TraceSpecularTask.output", &t.output, &t.common.viewport, Use::Storage(limits.write_formats))?;
        let formats = [vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT];
        if t.common.debug_output == DebugOutput::Default {
            format_in("TraceSpecularTask.output", t.output.format, &formats, "R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT")?;
        } else {
            format_in("TraceSpecularTask.output (debug output)", t.output.format, COLOR_OUTPUT_FORMATS, "an RGBA format")?;
        }
        if t.demodulated_output.image != vk::Image::null() {
            image(
                "TraceSpecularTask.demodulated_output",
                &t.demodulated_output,
                &t.common.viewport,
                Use::Storage(limits.write_formats),
            )?;
            format_in(
                "TraceSpecularTask.demodulated_output",
                t.demodulated_output.format,
                &formats,
                "R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT",
            )?;
        }
        let s = &t.common.specular;
        if s.image.image != vk::Image::null() {
            image("TraceCommon.specular.image", &s.image, &t.common.viewport, Use::Sampled)?;
            format_in("TraceCommon.specular.image.format", s.image.format, LIT_FORMATS, "an RGB(A) colour format")?;
        }
        if !(s.global_metalness.is_finite() && s.global_metalness >= 0.0) {
            return Err(Error::invalid("TraceCommon.specular.global_metalness", "must be finite and >= 0"));
        }
        if !(1..=64).contains(&t.rays_per_pixel) {
            return Err(Error::invalid("TraceSpecularTask.rays_per_pixel", format!("{} is not in 1..=64", t.rays_per_pixel)));
        }
        if !(t.ray_length.is_finite() && t.ray_length > 0.0) {
            return Err(Error::invalid("TraceSpecularTask.ray_length", "must be finite and > 0"));
        }
        if t.miss_radiance.iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(Error::invalid("TraceSpecularTask.miss_radiance", "must be finite and >= 0"));
        }
        if !(t.firefly_clamp.is_finite() && t.firefly_clamp >= 0.0) {
            return Err(Error::invalid("TraceSpecularTask.firefly_clamp", "must be finite and >= 0"));
        }
        lights::hit_lighting(&t.hit_lighting)
    }
}

const RADIANCE_FORMATS: &[vk::Format] = &[vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT];
const MOTION_FORMATS_2: &[vk::Format] =
    &[vk::Format::R16G16_SFLOAT, vk::Format::R32G32_SFLOAT, vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT];

/// The field of the task the engine filled that holds a denoise job's context.
pub(crate) fn denoise_context_field(signal: SignalType) -> &'static str {
    match signal {
        SignalType::Specular => "DenoiseSpecularTask.context",
        SignalType::Diffuse => "DenoiseDiffuseTask.context",
        SignalType::SpecularAndDiffuse => "DenoiseSpecularAndDiffuseTask.context",
        SignalType::DiffuseOcclusion => "DenoiseDiffuseOcclusionTask.context",
        SignalType::Shadow => "DenoiseShadowTask.context",
        SignalType::MultiShadow => "DenoiseMultiShadowTask.context",
    }
}

/// The fields of the task the engine filled that hold a denoise job's input and output `k`.
fn denoise_image_fields(signal: SignalType, k: usize) -> (&'static str, &'static str) {
    match (signal, k) {
        (SignalType::Specular, _) => ("DenoiseSpecularTask.input", "DenoiseSpecularTask.output"),
        (SignalType::Diffuse, _) => ("DenoiseDiffuseTask.input", "DenoiseDiffuseTask.output"),
        (SignalType::SpecularAndDiffuse, 0) => {
            ("DenoiseSpecularAndDiffuseTask.input_specular", "DenoiseSpecularAndDiffuseTask.output_specular")
        }
        (SignalType::SpecularAndDiffuse, _) => {
            ("DenoiseSpecularAndDiffuseTask.input_diffuse", "DenoiseSpecularAndDiffuseTask.output_diffuse")
        }
        (SignalType::DiffuseOcclusion, _) => ("DenoiseDiffuseOcclusionTask.input", "DenoiseDiffuseOcclusionTask.output"),
        (SignalType::Shadow, _) => ("DenoiseShadowTask.input", "DenoiseShadowTask.output"),
        (SignalType::MultiShadow, _) => ("DenoiseMultiShadowTask.input", "DenoiseMultiShadowTask.output"),
    }
}

/// A denoise task, normalised (see `DenoiseJob`): G-buffer, cameras, motion, settings, and the
/// formats its signal reads and writes.
impl Check for Box<DenoiseJob> {
    fn check(&self, shared: &Shared) -> Result<()> {
        shared.check_denoising_context_alive(self.context, denoise_context_field(self.signal))?;
        let (j, limits) = (&**self, &shared.device.limits);
        let c = &j.common;
        trace_common(&c.as_trace_common(), limits, Common::Denoising)?;
        if let Some(p) = &c.previous_camera {
            matrix("DenoisingCommon.previous_camera.world_to_view", &p.world_to_view)?;
            matrix("DenoisingCommon.previous_camera (view_to_clip * world_to_view)", &(p.view_to_clip * p.world_to_view))?;
        }
        if c.camera_jitter.iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid("DenoisingCommon.camera_jitter", "is not finite"));
        }
        let vp = &c.viewport;
        let m = &c.motion;
        if m.has_image() {
            image("DenoisingCommon.motion.image", &m.image, vp, Use::Sampled)?;
            let formats = if m.motion_type == MotionType::RgbWorldSpace { RADIANCE_FORMATS } else { MOTION_FORMATS_2 };
            format_in(
                "DenoisingCommon.motion.image.format",
                m.image.format,
                formats,
                "a float format with the channels the MotionType reads",
            )?;
        }
        if m.scale.iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid("DenoisingCommon.motion.scale", "is not finite"));
        }
        let s = &c.settings;
        let checks: [(&'static str, bool); 11] = [
            ("DenoiserSettings.max_history_frames (1..=255)", (1..=255).contains(&s.max_history_frames)),
            (
                "DenoiserSettings.fast_history_frames (1..=max_history_frames)",
                (1..=s.max_history_frames).contains(&s.fast_history_frames),
            ),
            ("DenoiserSettings.history_clamp_sigma (> 0)", s.history_clamp_sigma.is_finite() && s.history_clamp_sigma > 0.0),
            ("DenoiserSettings.spatial_passes (0..=6)", s.spatial_passes <= 6),
            ("DenoiserSettings.luminance_sigma (> 0)", s.luminance_sigma.is_finite() && s.luminance_sigma > 0.0),
            ("DenoiserSettings.normal_power (>= 0)", s.normal_power.is_finite() && s.normal_power >= 0.0),
            ("DenoiserSettings.plane_distance_sigma (> 0)", s.plane_distance_sigma.is_finite() && s.plane_distance_sigma > 0.0),
            ("DenoiserSettings.max_shadow_blur_radius (0..=64)", (0.0..=64.0).contains(&s.max_shadow_blur_radius)),
            ("DenoiserSettings.moving_object_reach (>= 0)", s.moving_object_reach.is_finite() && s.moving_object_reach >= 0.0),
            ("DenoiserSettings.fresh_history_taps (0..=32)", s.fresh_history_taps <= 32),
            ("DenoiserSettings", true),
        ];
        if let Some((what, _)) = checks.iter().find(|(_, ok)| !ok) {
            return Err(Error::invalid(what, "is out of range"));
        }
        let (inputs, outputs): (&[vk::Format], &[vk::Format]) = match j.signal {
            SignalType::Specular | SignalType::Diffuse | SignalType::SpecularAndDiffuse => (RADIANCE_FORMATS, RADIANCE_FORMATS),
            SignalType::DiffuseOcclusion => (SCALAR_OUTPUT_FORMATS, SCALAR_OUTPUT_FORMATS),
            SignalType::Shadow => (SHADOW_OUTPUT_FORMATS, SCALAR_OUTPUT_FORMATS),
            SignalType::MultiShadow => (RADIANCE_FORMATS, SCALAR_OUTPUT_FORMATS),
        };
        for k in 0..j.count {
            let (input, output) = denoise_image_fields(j.signal, k);
            image(input, &j.inputs[k], vp, Use::Sampled)?;
            format_in(input, j.inputs[k].format, inputs, "the format of the trace task's output for this signal")?;
            image(output, &j.outputs[k], vp, Use::Storage(limits.write_formats))?;
            format_in(output, j.outputs[k].format, outputs, "an RGBA16F/32F (radiance) or scalar/RGBA (visibility) format")?;
        }
        if j.signal == SignalType::Shadow {
            light("DenoiseShadowTask.light", &j.light)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ash::vk::Handle;

    /// An output the device cannot write without a format qualifier is refused by name, before
    /// anything reaches the driver; the same image is accepted where the device can.
    #[test]
    fn a_storage_output_needs_formatless_writes_in_its_format() {
        let img = ImageInput {
            image: vk::Image::from_raw(1),
            view: vk::ImageView::from_raw(2),
            format: vk::Format::R16_SFLOAT,
            width: 8,
            height: 8,
            layout: vk::ImageLayout::GENERAL,
            usage: vk::ImageUsageFlags::STORAGE,
        };
        let vp = Viewport::full(8, 8);
        match image("output", &img, &vp, Use::Storage(FormatSet::default())) {
            Err(Error::UnsupportedFormat { what: "output", format: vk::Format::R16_SFLOAT, .. }) => {}
            other => panic!("expected UnsupportedFormat, got {other:?}"),
        }
        assert!(image("output", &img, &vp, Use::Storage(FormatSet::all_outputs())).is_ok());
        // Read through a sampler, the format needs no storage support.
        let sampled =
            ImageInput { usage: vk::ImageUsageFlags::SAMPLED, layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, ..img };
        assert!(image("input", &sampled, &vp, Use::Sampled).is_ok());
    }

    /// Every format a task accepts for an output is one whose formatless writes the context
    /// asks the device about (else the check above would let it through unasked).
    #[test]
    fn every_output_format_is_asked_about() {
        let lists = [SCALAR_OUTPUT_FORMATS, COLOR_OUTPUT_FORMATS, RADIANCE_FORMATS, SHADOW_OUTPUT_FORMATS];
        let visibility = [vk::Format::R32_UINT, vk::Format::R32G32B32A32_UINT];
        for f in lists.iter().flat_map(|l| l.iter()).chain(&visibility) {
            assert!(OUTPUT_FORMATS.contains(f), "{f:?}");
        }
    }
}
