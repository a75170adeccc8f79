//! `TraceManyLightsTask`'s checks at scheduling (its context's size and list at build).
use super::Check;
use super::{format_in, image, light, trace_common, Common, Use, MOTION_FORMATS_2, RADIANCE_FORMATS};
use crate::context::Shared;
use crate::error::{Error, Result};
use crate::types::*;
use ash::vk;

const OUTPUT_FORMATS: &[vk::Format] = &[vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT];

impl Check for TraceManyLightsTask {
    fn check(&self, shared: &Shared) -> Result<()> {
        let (t, limits) = (self, &shared.device.limits);
        shared.check_many_lights_context_alive(t.context, "TraceManyLightsTask.context")?;
        trace_common(&t.common, limits, Common::Trace)?;
        if t.common.debug_output != DebugOutput::Default {
            return Err(Error::invalid(
                "TraceManyLightsTask.common.debug_output",
                "the SDK's debug visualisations are not drawn by this task: use its debug_output",
            ));
        }
        if t.common.half_resolution_mode != HalfResolutionMode::Off {
            return Err(Error::invalid("TraceManyLightsTask.common.half_resolution_mode", "checkerboard mode is not supported"));
        }
        let vp = &t.common.viewport;
        for (what, output) in [
            ("TraceManyLightsTask.diffuse_output", &t.diffuse_output),
            ("TraceManyLightsTask.specular_output", &t.specular_output),
        ] {
            image(what, output, vp, Use::Storage(limits.write_formats))?;
            format_in(what, output.format, OUTPUT_FORMATS, "R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT")?;
        }
        if t.debug_output.image != vk::Image::null() {
            image("TraceManyLightsTask.debug_output", &t.debug_output, vp, Use::Storage(limits.write_formats))?;
            format_in(
                "TraceManyLightsTask.debug_output",
                t.debug_output.format,
                OUTPUT_FORMATS,
                "R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT",
            )?;
        }
        let m = &t.motion;
        if m.has_image() {
            image("TraceManyLightsTask.motion.image", &m.image, vp, Use::Sampled)?;
            let formats = if m.motion_type == MotionType::RgbWorldSpace { RADIANCE_FORMATS } else { MOTION_FORMATS_2 };
            format_in(
                "TraceManyLightsTask.motion.image.format",
                m.image.format,
                formats,
                "a float format with the channels the MotionType reads",
            )?;
        }
        if m.scale.iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid("TraceManyLightsTask.motion.scale", "is not finite"));
        }
        let s = &t.settings;
        let checks: [(&'static str, bool); 4] = [
            ("ManyLightsSettings.initial_candidates (1..=32)", (1..=32).contains(&s.initial_candidates)),
            ("ManyLightsSettings.spatial_samples (0..=8)", s.spatial_samples <= 8),
            ("ManyLightsSettings.spatial_radius (1..=128)", (1.0..=128.0).contains(&s.spatial_radius)),
            ("ManyLightsSettings.max_history (1..=64)", (1..=64).contains(&s.max_history)),
        ];
        if let Some((what, _)) = checks.iter().find(|(_, ok)| !ok) {
            return Err(Error::invalid(what, "is out of range"));
        }
        if let LightListUpdate::Replace(l) | LightListUpdate::Write { lights: l, .. } = &t.lights {
            if l.len() > MAX_MANY_LIGHTS as usize {
                return Err(Error::invalid(
                    "TraceManyLightsTask.lights",
                    format!("{} lights: at most {MAX_MANY_LIGHTS}", l.len()),
                ));
            }
            for light_info in l {
                light("TraceManyLightsTask.lights[]", light_info)?;
            }
        }
        if let LightListUpdate::Write { first, lights } = &t.lights {
            if (*first as u64 + lights.len() as u64) > MAX_MANY_LIGHTS as u64 {
                return Err(Error::invalid(
                    "TraceManyLightsTask.lights",
                    format!("first {first} + {} lights: at most {MAX_MANY_LIGHTS}", lights.len()),
                ));
            }
        }
        Ok(())
    }
}
