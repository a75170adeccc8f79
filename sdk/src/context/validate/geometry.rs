//! Geometry inputs: each part's fields, then the parts' totals against the device's limits,
//! then every engine region against its buffer's size.
use crate::error::{Error, Result};
use crate::gpu::device::Device;
use crate::scene::geometry::{check_region, CopyPlan};
use crate::types::*;
use ash::vk;

/// A geometry's parts, then its totals against the device's limits, then every engine region
/// against its buffer's size. Errors name the field; for a part of `extra_components` the
/// message starts with its index.
pub(crate) fn geometry_input(device: &Device, input: &GeometryInput) -> Result<()> {
    for (k, c) in input.components().enumerate() {
        let (vertices, indices) = if k == 0 {
            ("GeometryInput.vertices", "GeometryInput.indices")
        } else {
            ("GeometryInput.extra_components.vertices", "GeometryInput.extra_components.indices")
        };
        let part = if k == 0 { String::new() } else { format!("part {}: ", k - 1) };
        geometry_component(&c, vertices, indices, &part)?;
        texture_coordinates(&c, input.alpha_test.is_some() || input.albedo_texture.is_some(), &part)?;
        vertex_colors(&c, input.colors.is_some(), &part)?;
    }
    if let Some(a) = &input.alpha_test {
        alpha_test(device, a)?;
    }
    if let Some(a) = &input.albedo_texture {
        albedo_texture(device, a)?;
    }
    let t = &input.surfels;
    if !(t.tile_unit_length.is_finite() && t.tile_unit_length > 0.0) {
        return Err(Error::invalid("SurfelSettings.tile_unit_length", "must be finite and > 0"));
    }
    if !(t.direct_tile_mapping_threshold.is_finite() && t.direct_tile_mapping_threshold >= 0.0) {
        return Err(Error::invalid("SurfelSettings.direct_tile_mapping_threshold", "must be finite and >= 0"));
    }
    if t.tile_resolution_limit == 0 || t.tile_resolution_limit > crate::cache::layout::MAX_RESOLUTION {
        return Err(Error::invalid(
            "SurfelSettings.tile_resolution_limit",
            format!("{} is not in 1..={}", t.tile_resolution_limit, crate::cache::layout::MAX_RESOLUTION),
        ));
    }
    let plan = CopyPlan::of(input)?;
    let layout = plan.layout;
    if layout.primitive_count as u64 > device.limits.max_primitive_count {
        return Err(Error::invalid(
            "GeometryInput.vertices.count / indices.count (every part's triangles)",
            format!(
                "{} triangles exceed the device's maxPrimitiveCount {}",
                layout.primitive_count, device.limits.max_primitive_count
            ),
        ));
    }
    for (what, bytes) in [("copy", layout.total_bytes()), ("staging copy", plan.staging_bytes)] {
        if bytes > device.limits.max_buffer_size {
            return Err(Error::invalid(
                "GeometryInput.vertices.count / stride (every part's vertices)",
                format!("its {bytes}-byte {what} exceeds the device's maxBufferSize {}", device.limits.max_buffer_size),
            ));
        }
    }
    for (k, p) in plan.parts.iter().enumerate() {
        let (vertices, indices) = if k == 0 {
            ("GeometryInput.vertices", "GeometryInput.indices")
        } else {
            ("GeometryInput.extra_components.vertices", "GeometryInput.extra_components.indices")
        };
        check_region(&device.raw, vertices, p.vertex_buffer, p.vertex_src_offset, p.vertex_bytes)?;
        if p.index_size > 0 {
            check_region(&device.raw, indices, p.index_buffer, p.index_src_offset, p.index_bytes)?;
        }
        if p.uv_buffer != vk::Buffer::null() {
            check_region(&device.raw, "GeometryComponent.uvs", p.uv_buffer, p.uv_src_offset, p.uv_bytes)?;
        }
        if p.color_buffer != vk::Buffer::null() {
            check_region(&device.raw, "GeometryComponent.colors", p.color_buffer, p.color_src_offset, p.color_bytes)?;
        }
    }
    Ok(())
}

/// Alpha textures: formats read as colour by texel fetches, with the channel count.
fn alpha_channels(f: vk::Format) -> Option<u32> {
    use vk::Format as F;
    Some(match f {
        F::R8_UNORM | F::R16_UNORM | F::R16_SFLOAT | F::R32_SFLOAT => 1,
        F::R8G8_UNORM | F::R16G16_SFLOAT | F::R32G32_SFLOAT => 2,
        F::R8G8B8A8_UNORM
        | F::R8G8B8A8_SRGB
        | F::B8G8R8A8_UNORM
        | F::B8G8R8A8_SRGB
        | F::A2B10G10R10_UNORM_PACK32
        | F::R16G16B16A16_SFLOAT
        | F::R32G32B32A32_SFLOAT
        | F::BC1_RGBA_UNORM_BLOCK
        | F::BC1_RGBA_SRGB_BLOCK
        | F::BC2_UNORM_BLOCK
        | F::BC2_SRGB_BLOCK
        | F::BC3_UNORM_BLOCK
        | F::BC3_SRGB_BLOCK
        | F::BC7_UNORM_BLOCK
        | F::BC7_SRGB_BLOCK => 4,
        F::BC4_UNORM_BLOCK => 1,
        _ => return None,
    })
}

fn alpha_test(device: &Device, a: &AlphaTestInput) -> Result<()> {
    const WHAT: &str = "GeometryInput.alpha_test.texture";
    let t = &a.texture;
    let limit = device.limits.max_image_dimension_2d;
    if t.width == 0 || t.height == 0 || t.width > limit || t.height > limit {
        return Err(Error::invalid(WHAT, format!("{}x{} is not within 1..={limit} (maxImageDimension2D)", t.width, t.height)));
    }
    super::image(WHAT, t, &Viewport::full(t.width, t.height), super::Use::Sampled)?;
    let Some(channels) = alpha_channels(t.format) else {
        return Err(Error::UnsupportedFormat {
            what: WHAT,
            format: t.format,
            expected: "an unorm, sRGB, float or BC1/2/3/4/7 colour format",
        });
    };
    if a.channel >= channels {
        return Err(Error::invalid(
            "GeometryInput.alpha_test.channel",
            format!("channel {} of a {channels}-channel format", a.channel),
        ));
    }
    if !(0.0..=1.0).contains(&a.cutoff) {
        return Err(Error::invalid("GeometryInput.alpha_test.cutoff", "must be in [0, 1]"));
    }
    Ok(())
}

/// An albedo texture: any colour format texel fetches read (the alpha test's list).
fn albedo_texture(device: &Device, a: &AlbedoTextureInput) -> Result<()> {
    const WHAT: &str = "GeometryInput.albedo_texture.texture";
    let t = &a.texture;
    let limit = device.limits.max_image_dimension_2d;
    if t.width == 0 || t.height == 0 || t.width > limit || t.height > limit {
        return Err(Error::invalid(WHAT, format!("{}x{} is not within 1..={limit} (maxImageDimension2D)", t.width, t.height)));
    }
    super::image(WHAT, t, &Viewport::full(t.width, t.height), super::Use::Sampled)?;
    if alpha_channels(t.format).is_none() {
        return Err(Error::UnsupportedFormat {
            what: WHAT,
            format: t.format,
            expected: "an unorm, sRGB, float or BC1/2/3/4/7 colour format",
        });
    }
    Ok(())
}

/// A part's vertex colours: on every part when the first part has them.
fn vertex_colors(c: &GeometryComponent, coloured: bool, part: &str) -> Result<()> {
    const WHAT: &str = "GeometryComponent.colors";
    let Some(u) = &c.colors else {
        return if coloured {
            Err(Error::invalid(WHAT, format!("{part}a geometry with vertex colours needs them on every part")))
        } else {
            Ok(())
        };
    };
    if !coloured {
        return Err(Error::invalid(WHAT, format!("{part}vertex colours on a part but not on the first (GeometryInput.colors)")));
    }
    let element = match u.format {
        vk::Format::R8G8B8A8_UNORM
        | vk::Format::R16G16B16A16_SFLOAT
        | vk::Format::R32G32B32_SFLOAT
        | vk::Format::R32G32B32A32_SFLOAT => crate::scene::geometry::color_element_bytes(u.format),
        f => {
            return Err(Error::UnsupportedFormat {
                what: WHAT,
                format: f,
                expected: "R8G8B8A8_UNORM, R16G16B16A16_SFLOAT, R32G32B32_SFLOAT or R32G32B32A32_SFLOAT",
            })
        }
    };
    vertex_attribute(WHAT, u, element, c, part, "colours")
}

/// A part's texture coordinates: required (and only read) with alpha testing or an albedo
/// texture.
fn texture_coordinates(c: &GeometryComponent, textured: bool, part: &str) -> Result<()> {
    const WHAT: &str = "GeometryComponent.uvs";
    let Some(u) = &c.uvs else {
        return if textured {
            Err(Error::invalid(
                WHAT,
                format!("{part}an alpha-tested or albedo-textured geometry needs texture coordinates on every part"),
            ))
        } else {
            Ok(())
        };
    };
    if !textured {
        return Err(Error::invalid(
            WHAT,
            format!("{part}texture coordinates are only read for alpha testing or an albedo texture: set alpha_test or albedo_texture"),
        ));
    }
    let element = match u.format {
        vk::Format::R32G32_SFLOAT => 8,
        vk::Format::R16G16_SFLOAT | vk::Format::R16G16_UNORM => 4,
        f => {
            return Err(Error::UnsupportedFormat {
                what: WHAT,
                format: f,
                expected: "R32G32_SFLOAT, R16G16_SFLOAT or R16G16_UNORM",
            })
        }
    };
    vertex_attribute(WHAT, u, element, c, part, "texture coordinates")
}

/// A per-vertex attribute's buffer, stride and count against the part's vertices.
fn vertex_attribute(
    what: &'static str,
    u: &VertexBufferInput,
    element: u64,
    c: &GeometryComponent,
    part: &str,
    noun: &str,
) -> Result<()> {
    if u.buffer == vk::Buffer::null() {
        return Err(Error::invalid(what, format!("{part}buffer is null")));
    }
    if u.stride < element || u.stride % 4 != 0 || u.stride > u32::MAX as u64 {
        return Err(Error::invalid(what, format!("{part}stride {} must be a multiple of 4, at least {element}", u.stride)));
    }
    let needed = c.vertex_range.map_or(c.vertices.count, |r| r.last.saturating_add(1));
    if u.count < needed {
        return Err(Error::invalid(what, format!("{part}{} {noun} for {needed} vertices", u.count)));
    }
    Ok(())
}

/// One part's fields on their own (`part` prefixes messages about `extra_components`).
fn geometry_component(c: &GeometryComponent, vertices: &'static str, indices: &'static str, part: &str) -> Result<()> {
    let v = &c.vertices;
    if v.buffer == vk::Buffer::null() {
        return Err(Error::invalid(vertices, format!("{part}buffer is null")));
    }
    let position_bytes = match v.format {
        vk::Format::R32G32B32_SFLOAT => 12,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        f => {
            return Err(Error::UnsupportedFormat {
                what: vertices,
                format: f,
                expected: "R32G32B32_SFLOAT or R32G32B32A32_SFLOAT",
            })
        }
    };
    if v.count == 0 {
        return Err(Error::invalid(vertices, format!("{part}count is 0")));
    }
    if v.stride < position_bytes || v.stride % 4 != 0 || v.stride > u32::MAX as u64 {
        return Err(Error::invalid(
            vertices,
            format!("{part}stride {} must be a multiple of 4, at least {position_bytes} and below 4 GiB", v.stride),
        ));
    }
    let i = &c.indices;
    let indexed = i.buffer != vk::Buffer::null();
    if indexed {
        if !matches!(i.format, vk::Format::R32_UINT | vk::Format::R16_UINT) {
            return Err(Error::UnsupportedFormat { what: indices, format: i.format, expected: "R32_UINT or R16_UINT" });
        }
        if i.count == 0 || i.count % 3 != 0 {
            return Err(Error::invalid(indices, format!("{part}count {} is not a positive multiple of 3", i.count)));
        }
    } else if v.count < 3 || v.count % 3 != 0 {
        return Err(Error::invalid(
            vertices,
            format!("{part}count {} is not a positive multiple of 3 (non-indexed triangles)", v.count),
        ));
    }
    if let Some(r) = c.vertex_range {
        if !indexed {
            return Err(Error::invalid(
                vertices,
                format!("{part}a vertex range needs indices (a non-indexed part uses all its vertices)"),
            ));
        }
        if r.first > r.last || r.last >= v.count {
            return Err(Error::invalid(
                vertices,
                format!("{part}vertex range {}..={} is not within the {} vertices", r.first, r.last, v.count),
            ));
        }
    }
    if c.transform.is_some_and(|t| !t.is_finite()) {
        return Err(Error::InvalidTransform { what: "GeometryComponent.transform" });
    }
    Ok(())
}
