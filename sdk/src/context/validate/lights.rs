//! Light and shadow task inputs: lights (cones, ranges, intensities), single- and
//! multi-light shadow outputs, per-light outputs.
use super::{format_in, image, trace_common, Check, Common, Use, COLOR_OUTPUT_FORMATS};
use crate::context::Shared;
use crate::error::{Error, Result};
use crate::types::*;
use ash::vk;

pub(super) const SHADOW_OUTPUT_FORMATS: &[vk::Format] = &[
    vk::Format::R16_SFLOAT,
    vk::Format::R32_SFLOAT,
    vk::Format::R16G16_SFLOAT,
    vk::Format::R32G32_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R32G32B32A32_SFLOAT,
];

impl Check for TraceShadowTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        trace_common(&t.common, limits, Common::Trace)?;
        if t.common.debug_output != DebugOutput::Default {
            image("TraceShadowTask.output", &t.output, &t.common.viewport, Use::Storage(limits.write_formats))?;
            return format_in(
                "TraceShadowTask.output (debug output)",
                t.output.format,
                COLOR_OUTPUT_FORMATS,
                "an RGBA format for a debug visualisation",
            );
        }
        image("TraceShadowTask.output", &t.output, &t.common.viewport, Use::Storage(limits.write_formats))?;
        format_in(
            "TraceShadowTask.output",
            t.output.format,
            SHADOW_OUTPUT_FORMATS,
            "a signed float format (R16/R32, RG or RGBA)",
        )?;
        light("TraceShadowTask.light", &t.light)?;
        if !(1..=64).contains(&t.rays_per_pixel) {
            return Err(Error::invalid("TraceShadowTask.rays_per_pixel", format!("{} is not in 1..=64", t.rays_per_pixel)));
        }
        // Infinity (no cap) is the default.
        if t.max_ray_length.is_nan() || t.max_ray_length <= 0.0 {
            return Err(Error::invalid("TraceShadowTask.max_ray_length", format!("{} is not > 0", t.max_ray_length)));
        }
        Ok(())
    }
}

pub(super) fn light(what: &'static str, l: &LightInfo) -> Result<()> {
    if !l.position.is_finite() || !l.direction.is_finite() {
        return Err(Error::invalid(what, "position or direction is not finite"));
    }
    if l.light_type != LightType::Point && l.direction.length_squared() < 1e-12 {
        return Err(Error::invalid(what, "direction is zero"));
    }
    if !(l.angular_extent.is_finite() && (0.0..3.0).contains(&l.angular_extent)) {
        return Err(Error::invalid(what, "angular_extent must be in [0, 3) radians"));
    }
    if !(l.radius.is_finite() && l.radius >= 0.0) {
        return Err(Error::invalid(what, "radius must be finite and >= 0"));
    }
    if !(l.inner_cone.is_finite() && l.outer_cone.is_finite()) {
        return Err(Error::invalid(what, "inner_cone and outer_cone must be finite"));
    }
    if l.light_type == LightType::Spot
        && !(0.0 <= l.inner_cone && l.inner_cone <= l.outer_cone && l.outer_cone < std::f32::consts::FRAC_PI_2)
    {
        return Err(Error::invalid(what, "a spot needs 0 <= inner_cone <= outer_cone < pi/2"));
    }
    if !(l.range.is_finite() && l.range >= 0.0) {
        return Err(Error::invalid(what, "range must be finite and >= 0 (0: unlimited)"));
    }
    if !(l.intensity.is_finite() && l.intensity >= 0.0) {
        return Err(Error::invalid(what, "intensity must be finite and >= 0"));
    }
    if !l.color.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(Error::invalid(what, "color must be finite and >= 0"));
    }
    Ok(())
}

impl Check for RelightCacheTask {
    fn check(&self, _: &Shared) -> Result<()> {
        let t = self;
        if t.lights.is_empty() || t.lights.len() > MAX_SHADOW_LIGHTS {
            return Err(Error::invalid(
                "RelightCacheTask.lights",
                format!("{} lights: 1..={MAX_SHADOW_LIGHTS} are supported", t.lights.len()),
            ));
        }
        for l in &t.lights {
            light("RelightCacheTask.lights[]", l)?;
        }
        if !(1..=MAX_RELIGHT_SAMPLES).contains(&t.max_samples) {
            return Err(Error::invalid(
                "RelightCacheTask.max_samples",
                format!("{} is not in 1..={MAX_RELIGHT_SAMPLES}", t.max_samples),
            ));
        }
        if !(1..=1024).contains(&t.history_frames) {
            return Err(Error::invalid("RelightCacheTask.history_frames", format!("{} is not in 1..=1024", t.history_frames)));
        }
        if !t.sky.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(Error::invalid("RelightCacheTask.sky", "must be finite and >= 0"));
        }
        Ok(())
    }
}

pub(super) fn hit_lighting(h: &HitLighting) -> Result<()> {
    if h.lights.len() > MAX_SHADOW_LIGHTS {
        return Err(Error::invalid(
            "TraceSpecularTask.hit_lighting.lights",
            format!("{} lights: at most {MAX_SHADOW_LIGHTS} are supported", h.lights.len()),
        ));
    }
    for l in &h.lights {
        light("TraceSpecularTask.hit_lighting.lights[]", l)?;
    }
    if !(h.max_roughness.is_finite() && (0.0..=1.0).contains(&h.max_roughness)) {
        return Err(Error::invalid("TraceSpecularTask.hit_lighting.max_roughness", "must be in 0..=1"));
    }
    if !(1..=MAX_HIT_GATHER_RAYS).contains(&h.gather_rays) {
        return Err(Error::invalid(
            "TraceSpecularTask.hit_lighting.gather_rays",
            format!("{} is not in 1..={MAX_HIT_GATHER_RAYS}", h.gather_rays),
        ));
    }
    Ok(())
}

impl Check for TraceMultiShadowTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        trace_common(&t.common, limits, Common::Trace)?;
        if t.common.debug_output != DebugOutput::Default {
            return Err(Error::invalid(
                "TraceMultiShadowTask.common.debug_output",
                "debug visualisations need a colour output: use them on a shadow, AO, diffuse or specular task",
            ));
        }
        if t.lights.is_empty() || t.lights.len() > MAX_SHADOW_LIGHTS {
            return Err(Error::invalid(
                "TraceMultiShadowTask.lights",
                format!("{} lights: 1..={MAX_SHADOW_LIGHTS} are supported", t.lights.len()),
            ));
        }
        for l in &t.lights {
            light("TraceMultiShadowTask.lights[]", l)?;
        }
        let vp = &t.common.viewport;
        image("TraceMultiShadowTask.visibility", &t.visibility, vp, Use::Storage(limits.write_formats))?;
        let vis_formats: &[vk::Format] = if t.lights.len() <= 4 {
            &[vk::Format::R32_UINT, vk::Format::R32G32B32A32_UINT]
        } else {
            &[vk::Format::R32G32B32A32_UINT]
        };
        format_in(
            "TraceMultiShadowTask.visibility",
            t.visibility.format,
            vis_formats,
            "R32_UINT (up to 4 lights) or R32G32B32A32_UINT",
        )?;
        let high = t.lights.len().saturating_sub(LIGHTS_PER_VISIBILITY_IMAGE);
        let has_high = t.visibility_high.image != vk::Image::null();
        if high > 0 && !has_high {
            return Err(Error::invalid(
                "TraceMultiShadowTask.visibility_high",
                format!("{} lights: lights 16.. need visibility_high", t.lights.len()),
            ));
        }
        if has_high {
            if high == 0 {
                return Err(Error::invalid(
                    "TraceMultiShadowTask.visibility_high",
                    "given with 16 lights or fewer: leave it null",
                ));
            }
            image("TraceMultiShadowTask.visibility_high", &t.visibility_high, vp, Use::Storage(limits.write_formats))?;
            let formats: &[vk::Format] =
                if high <= 4 { &[vk::Format::R32_UINT, vk::Format::R32G32B32A32_UINT] } else { &[vk::Format::R32G32B32A32_UINT] };
            format_in(
                "TraceMultiShadowTask.visibility_high",
                t.visibility_high.format,
                formats,
                "R32_UINT (up to 4 lights above 16) or R32G32B32A32_UINT",
            )?;
            if t.visibility_high.image == t.visibility.image {
                return Err(Error::invalid("TraceMultiShadowTask.visibility_high", "is the visibility image"));
            }
        }
        if t.light_outputs.len() > MAX_LIGHT_OUTPUTS {
            return Err(Error::invalid(
                "TraceMultiShadowTask.light_outputs",
                format!("{} outputs: at most {MAX_LIGHT_OUTPUTS}", t.light_outputs.len()),
            ));
        }
        for (k, o) in t.light_outputs.iter().enumerate() {
            if o.light as usize >= t.lights.len() {
                return Err(Error::invalid(
                    "TraceMultiShadowTask.light_outputs[].light",
                    format!("light {} of {} lights", o.light, t.lights.len()),
                ));
            }
            image("TraceMultiShadowTask.light_outputs[].output", &o.output, vp, Use::Storage(limits.write_formats))?;
            format_in(
                "TraceMultiShadowTask.light_outputs[].output",
                o.output.format,
                SHADOW_OUTPUT_FORMATS,
                "a signed float format (R16/R32, RG or RGBA)",
            )?;
            let others = [t.visibility.image, t.visibility_high.image, t.packed.image];
            if others.contains(&o.output.image) || t.light_outputs[..k].iter().any(|p| p.output.image == o.output.image) {
                return Err(Error::invalid(
                    "TraceMultiShadowTask.light_outputs[].output",
                    "each output needs an image of its own (not another output's, the visibility's or packed's)",
                ));
            }
        }
        image("TraceMultiShadowTask.packed", &t.packed, vp, Use::Storage(limits.write_formats))?;
        format_in(
            "TraceMultiShadowTask.packed",
            t.packed.format,
            &[vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT],
            "R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT",
        )?;
        if !(1..=64).contains(&t.rays_per_pixel) {
            return Err(Error::invalid("TraceMultiShadowTask.rays_per_pixel", format!("{} is not in 1..=64", t.rays_per_pixel)));
        }
        // Infinity (no cap) is the default.
        if t.max_ray_length.is_nan() || t.max_ray_length <= 0.0 {
            return Err(Error::invalid("TraceMultiShadowTask.max_ray_length", format!("{} is not > 0", t.max_ray_length)));
        }
        Ok(())
    }
}
