//! `--many-lights`: a thousand-odd small lights scattered through the scene, shaded by the
//! SDK's resampled direct lighting (`TraceManyLightsTask`) on the main view, denoised
//! (`DenoiseSpecularAndDiffuseTask`), and added to the lit image by a small compose pass.
//! A few dozen of them circle every frame: the task uploads only those (`LightListUpdate::Write`).
use super::resources::work_image;
use super::schedule::schedule;
use super::{sdk_err, GENERAL, MAIN_VIEW};
use crate::gpu::{spirv, ComputePass};
use crate::modes::Mode;
use crate::raster::Targets;
use glam::Vec3;
use hybrid_rt::*;
use hybrid_rt_host::scene::Rng;
use hybrid_rt_host::{Host, HostImage, HostResult};

/// Lights that move (the first of the list): they circle their starting point.
const MOVING: usize = 64;

/// The lights, the SDK's contexts, and the images of the main view.
pub(super) struct ManyLights {
    lights: Vec<LightInfo>,
    context: ManyLightsContextHandle,
    denoiser: DenoisingContextHandle,
    noisy_diffuse: HostImage,
    noisy_specular: HostImage,
    diffuse: HostImage,
    specular: HostImage,
    /// The task's debug output: a colour per chosen light, the sample count in A.
    debug: HostImage,
    compose: ComputePass,
    /// Whether the SDK has the list yet.
    uploaded: bool,
}

/// `count` small sphere lights of random colour scattered through the scene's bounds (lower
/// three quarters of its height), each reaching a fifth of the scene's diagonal; together about
/// a hundred times the point light's intensity (each reaches a small part of the scene).
pub fn scatter(bounds: (Vec3, Vec3), point_intensity: f32, count: usize) -> Vec<LightInfo> {
    let (lo, hi) = bounds;
    let size = hi - lo;
    let mut rng = Rng::new(23);
    let intensity = 100.0 * point_intensity.max(1.0) / count as f32;
    (0..count)
        .map(|_| {
            let p = lo + size * Vec3::new(0.05 + 0.9 * rng.next_f32(), 0.1 + 0.65 * rng.next_f32(), 0.05 + 0.9 * rng.next_f32());
            let hue = rng.next_f32() * 6.0;
            let colour = [(hue - 3.0).abs() - 1.0, 2.0 - (hue - 2.0).abs(), 2.0 - (hue - 4.0).abs()]
                .map(|c: f32| 0.3 + 0.7 * c.clamp(0.0, 1.0));
            LightInfo {
                light_type: LightType::Point,
                position: p,
                radius: 0.01 * size.length(),
                range: 0.2 * size.length(),
                intensity: intensity * (0.5 + rng.next_f32()),
                color: colour,
                ..Default::default()
            }
        })
        .collect()
}

impl ManyLights {
    pub fn new(host: &Host, ctx: &ExecuteContext, lights: Vec<LightInfo>, width: u32, height: u32) -> HostResult<ManyLights> {
        let context = ctx
            .create_many_lights_context(&ManyLightsContextInput {
                max_width: width,
                max_height: height,
                max_lights: lights.len() as u32,
            })
            .map_err(sdk_err)?;
        let denoiser = ctx
            .create_denoising_context(&DenoisingContextInput {
                max_width: width,
                max_height: height,
                signal: SignalType::SpecularAndDiffuse,
                view_id: MAIN_VIEW,
                ..Default::default()
            })
            .map_err(sdk_err)?;
        Ok(ManyLights {
            lights,
            context,
            denoiser,
            noisy_diffuse: work_image(host, width, height)?,
            noisy_specular: work_image(host, width, height)?,
            diffuse: work_image(host, width, height)?,
            specular: work_image(host, width, height)?,
            debug: work_image(host, width, height)?,
            compose: ComputePass::new(host, spirv::MANY_LIGHTS_COMP, 3, 1)?,
            uploaded: false,
        })
    }

    /// The moving lights at `time` (seconds): circles of 0.3 m around where they started.
    fn moved(&self, time: f32) -> Vec<LightInfo> {
        self.lights[..MOVING.min(self.lights.len())]
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let a = time * 1.5 + i as f32;
                LightInfo { position: l.position + 0.3 * Vec3::new(a.cos(), 0.0, a.sin()), ..*l }
            })
            .collect()
    }

    /// The trace (the whole list the first time, then the moving lights, and with `debug` the
    /// debug output) and its denoiser.
    pub fn schedule(
        &mut self,
        container: &mut TaskContainer,
        common: TraceCommon,
        denoising: DenoisingCommon,
        time: f32,
        debug: bool,
    ) -> HostResult<()> {
        let lights = if self.uploaded {
            LightListUpdate::Write { first: 0, lights: self.moved(time) }
        } else {
            let mut all = self.lights.clone();
            let moved = self.moved(time);
            all[..moved.len()].copy_from_slice(&moved);
            LightListUpdate::Replace(all)
        };
        let trace = TraceManyLightsTask {
            context: self.context,
            common,
            motion: denoising.motion,
            lights,
            diffuse_output: self.noisy_diffuse.input(GENERAL),
            specular_output: self.noisy_specular.input(GENERAL),
            debug_output: if debug { self.debug.input(GENERAL) } else { ImageInput::default() },
            ..Default::default()
        };
        schedule(container, "many lights", |c| c.schedule_many_lights(&trace))?;
        self.uploaded = true;
        let denoise = DenoiseSpecularAndDiffuseTask {
            context: self.denoiser,
            common: denoising,
            input_specular: self.noisy_specular.input(GENERAL),
            input_diffuse: self.noisy_diffuse.input(GENERAL),
            output_specular: self.specular.input(GENERAL),
            output_diffuse: self.diffuse.input(GENERAL),
        };
        schedule(container, "denoise many lights", |c| c.schedule_denoise_specular_and_diffuse(&denoise))
    }

    /// Adds the denoised lighting to `lit` (the main view's, in GENERAL).
    pub fn compose(
        &mut self,
        host: &Host,
        cmd: ash::vk::CommandBuffer,
        slot: usize,
        targets: &Targets,
        lit: &HostImage,
    ) -> HostResult<()> {
        let size = [targets.width as f32, targets.height as f32, 0.0, 0.0];
        let sampled = [(&targets.albedo_metalness, crate::raster::READ), (&self.diffuse, GENERAL), (&self.specular, GENERAL)];
        self.compose.dispatch(host, cmd, slot, &sampled, &[lit], bytemuck::bytes_of(&size), targets.width, targets.height)
    }

    /// The image a many-lights view mode shows (diffuse raw or denoised, the debug output).
    pub fn image(&self, mode: Mode) -> &HostImage {
        match mode {
            Mode::ManyLightsNoisy => &self.noisy_diffuse,
            Mode::ManyLightsDebug => &self.debug,
            _ => &self.diffuse,
        }
    }

    pub fn destroy(self, host: &Host, ctx: &ExecuteContext) -> HostResult<()> {
        ctx.destroy_many_lights_context(self.context).map_err(sdk_err)?;
        ctx.destroy_denoising_context(self.denoiser).map_err(sdk_err)?;
        for i in [self.noisy_diffuse, self.noisy_specular, self.diffuse, self.specular, self.debug] {
            host.destroy_image(i);
        }
        self.compose.destroy(host);
        Ok(())
    }
}
