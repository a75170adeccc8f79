//! The lighting traced per camera after Bevy's opaque pass, in one ticket: the lit frame
//! injected into the SDK's direct-lighting cache, diffuse GI and reflections traced from it,
//! denoised into the application's images and, for a deferred camera, added to the lit image.
use super::deferred::{composited, DeferredPasses, DECODED_FORMAT};
use super::effects::ExtractedLights;
use super::effects::{app_image, effect_targets, record_view, schedule_denoiser, Effect, EffectTargets, PrepassInputs};
use super::HybridRt;
use crate::{RayTracedGi, RayTracedReflections};
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::texture::GpuImage;
use bevy::render::view::{ExtractedView, RetainedViewEntity, ViewTarget};
use hybrid_rt::{
    DenoiseDiffuseTask, DenoiseSpecularTask, DirectLightingInjectionTask, HitLighting, LightInfo, RoughnessInput, TaskContainer,
    TraceDiffuseTask, TraceSpecularTask, MAX_SHADOW_LIGHTS,
};
use hybrid_rt_wgpu::wgpu;

/// A camera's image of the SDK's own (the decoded G-buffer), kept across frames at the view's
/// size and dropped as the denoisers are.
pub(super) struct ViewImage {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    size: (u32, u32),
    /// The last frame that used it.
    pub(super) last_used: u64,
}

/// The camera's decoded G-buffer at `size` (made, or remade at a new size), marked used this
/// frame.
fn decoded_gbuffer<'a>(
    images: &'a mut HashMap<RetainedViewEntity, ViewImage>,
    device: &wgpu::Device,
    key: RetainedViewEntity,
    size: (u32, u32),
    frame: u64,
) -> &'a ViewImage {
    let image = images.entry(key).or_insert_with(|| ViewImage::new(device, size));
    if image.size != size {
        *image = ViewImage::new(device, size);
    }
    image.last_used = frame;
    image
}

impl ViewImage {
    fn new(device: &wgpu::Device, size: (u32, u32)) -> ViewImage {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("hybrid-rt decoded g-buffer"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DECODED_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        ViewImage { texture, view, size, last_used: 0 }
    }
}

/// What [`trace_lighting`] reads of a camera.
type LightingView = (
    &'static ExtractedView,
    &'static ExtractedCamera,
    &'static ViewPrepassTextures,
    &'static ViewTarget,
    Option<&'static RayTracedGi>,
    Option<&'static RayTracedReflections>,
);

/// Per camera with [`RayTracedGi`] and/or [`RayTracedReflections`], in one ticket: the
/// camera's lit frame (Bevy's view target after the opaque pass) injected into the
/// direct-lighting cache; diffuse GI traced from Bevy's prepass; reflections traced from the
/// prepass and the deferred G-buffer's roughness (decoded first); their hits shaded from the
/// lit frame where the camera sees them and from the cache elsewhere; each denoised into the
/// application's image and, for a deferred camera, added to the lit image.
pub(super) fn trace_lighting(
    view: ViewQuery<LightingView>,
    images: Res<RenderAssets<GpuImage>>,
    lights: Res<ExtractedLights>,
    mut state: ResMut<HybridRt>,
    mut ctx: RenderContext,
) {
    let (view, camera, prepass, target, gi, reflections) = view.into_inner();
    let state = &mut *state;
    let Some(rt) = state.rt.as_ref() else { return };
    let (gi, reflections) = (gi.filter(|g| g.enabled), reflections.filter(|r| r.enabled));
    if (gi.is_none() && reflections.is_none()) || !state.has_instances {
        return;
    }
    let (lit_tex, lit_view) = (target.main_texture(), target.main_texture_view());
    if lit_tex.sample_count() > 1 {
        return state.warned.once("a camera with RayTracedGi or RayTracedReflections renders with MSAA: give it Msaa::Off");
    }
    let gbuffer = prepass.deferred.as_ref().map(|g| &g.texture);
    if reflections.is_some() && gbuffer.is_none() {
        state.warned.once("RayTracedReflections needs a deferred camera (DeferredPrepass, deferred materials)");
    }
    let gi = gi.and_then(|g| Some((g, app_image(&images, &g.output, "RayTracedGi", &mut state.warned)?)));
    let reflections = reflections
        .filter(|_| gbuffer.is_some())
        .and_then(|r| Some((r, app_image(&images, &r.output, "RayTracedReflections", &mut state.warned)?)));
    let lit = match rt.image(lit_tex, lit_view, hybrid_rt_wgpu::SDK_READ) {
        Ok(lit) => lit,
        Err(e) => return state.warned.once(&e),
    };
    let mut tasks = rt.context().create_task_container();
    // What the ticket reads (the effects' inputs, gathered) and writes.
    let mut recording: Option<PrepassInputs> = None;
    let mut writes = Vec::new();
    let mut injected = false;
    // The cache takes the lit frame once, before the first trace that reads it.
    let mut inject = |tasks: &mut TaskContainer, inputs: &PrepassInputs, average_window: f32| -> hybrid_rt::Result<()> {
        if std::mem::replace(&mut injected, true) {
            return Ok(());
        }
        tasks.schedule_direct_lighting_injection(&DirectLightingInjectionTask {
            depth: inputs.common.depth,
            lit,
            viewport: inputs.common.viewport,
            camera: inputs.common.camera,
            average_window,
            ..Default::default()
        })
    };
    let mut outputs: Vec<&wgpu::TextureView> = Vec::new();
    // An effect's tasks scheduled: its inputs, writes and output join the ticket's.
    let mut join = |scheduled: hybrid_rt::Result<Vec<wgpu::Texture>>, inputs, output| -> hybrid_rt::Result<()> {
        writes.extend(scheduled?);
        outputs.push(output);
        gather(&mut recording, inputs);
        Ok(())
    };
    if let Some((settings, image)) = gi {
        let sinks = (&mut state.views, &mut state.warned, state.frame);
        let targets = (&*image.texture, &*image.texture_view);
        if let Some(EffectTargets { output, inputs, noisy }) =
            effect_targets(rt, sinks, (view, prepass), targets, Effect::Gi, settings.denoise)
        {
            let trace = TraceDiffuseTask {
                common: inputs.common,
                output: noisy.as_ref().map_or(output, |n| n.image),
                rays_per_pixel: settings.rays_per_pixel,
                ray_length: settings.ray_length,
                miss_radiance: settings.miss_radiance,
                ..Default::default()
            };
            let denoise = |t: &mut TaskContainer, context, common, input, output| {
                t.schedule_denoise_diffuse(&DenoiseDiffuseTask { context, common, input, output })
            };
            let scheduled = inject(&mut tasks, &inputs, settings.cache_average_frames)
                .and_then(|()| tasks.schedule_diffuse(&trace))
                .and_then(|()| schedule_denoiser(&mut tasks, (&noisy, &inputs, output, &image.texture), denoise));
            if let Err(e) = join(scheduled, inputs, &image.texture_view) {
                return state.warned.once(&e);
            }
        }
    }
    if let (Some((settings, image)), Some(gbuffer)) = (reflections, gbuffer) {
        let sinks = (&mut state.views, &mut state.warned, state.frame);
        let targets = (&*image.texture, &*image.texture_view);
        if let Some(EffectTargets { output, mut inputs, noisy }) =
            effect_targets(rt, sinks, (view, prepass), targets, Effect::Reflections, settings.denoise)
        {
            // The G-buffer's roughness, and the pixels left out, as the SDK reads them.
            let size = (output.width, output.height);
            let decoded = decoded_gbuffer(&mut state.decoded, &rt.device, view.retained_view_entity, size, state.frame);
            let passes = state.deferred.get_or_insert_with(|| DeferredPasses::new(&rt.device));
            passes.decode(&rt.device, ctx.command_encoder(), &gbuffer.default_view, settings.max_roughness, &decoded.view);
            let decoded_image = match rt.image(&decoded.texture, &decoded.view, hybrid_rt_wgpu::SDK_READ) {
                Ok(i) => i,
                Err(e) => return state.warned.once(&e),
            };
            inputs.textures.push(decoded.texture.clone());
            inputs.views.push(decoded.view.clone());
            inputs.common.roughness =
                RoughnessInput { image: decoded_image, channel_mask: [0.0, 1.0, 0.0, 0.0], ..Default::default() };
            inputs.common.input_mask = decoded_image;
            inputs.common.direct_lighting = lit;
            let trace = TraceSpecularTask {
                common: inputs.common,
                output: noisy.as_ref().map_or(output, |n| n.image),
                rays_per_pixel: settings.rays_per_pixel,
                ray_length: settings.ray_length,
                miss_radiance: settings.miss_radiance,
                hit_lighting: hit_lighting(&lights, settings.hit_lighting_roughness, camera.exposure),
                ..Default::default()
            };
            let denoise = |t: &mut TaskContainer, context, common, input, output| {
                t.schedule_denoise_specular(&DenoiseSpecularTask { context, common, input, output })
            };
            let scheduled = inject(&mut tasks, &inputs, settings.cache_average_frames)
                .and_then(|()| tasks.schedule_specular(&trace))
                .and_then(|()| schedule_denoiser(&mut tasks, (&noisy, &inputs, output, &image.texture), denoise));
            if let Err(e) = join(scheduled, inputs, &image.texture_view) {
                return state.warned.once(&e);
            }
        }
    }
    let Some(mut inputs) = recording else { return };
    inputs.textures.push((**lit_tex).clone());
    inputs.views.push((**lit_view).clone());
    let sinks = (&mut state.recorded, &mut state.held, &mut state.warned);
    if !record_view(rt, sinks, &mut ctx, &mut tasks, "hybrid-rt lighting", inputs, writes, &outputs) {
        return;
    }
    // A deferred camera: the composite adds the GI times its G-buffer's diffuse colour, the
    // reflections times its environment BRDF, to the lit image.
    if gbuffer.is_none() {
        return;
    }
    let request = state.composites.entry(view.retained_view_entity).or_default();
    request.gi = gi.and_then(|(g, image)| composited(image, g.composite, "RayTracedGi", &mut state.warned));
    request.reflections =
        reflections.and_then(|(r, image)| composited(image, r.composite, "RayTracedReflections", &mut state.warned));
}

/// Bevy's lights as the SDK's hit lighting takes them (their brightness times the camera's
/// exposure, as Bevy's lit frame has them), for pixels up to `max_roughness`; off where that
/// is negative or the scene has no light.
fn hit_lighting(lights: &ExtractedLights, max_roughness: f32, exposure: f32) -> HitLighting {
    if max_roughness.is_nan() || max_roughness < 0.0 {
        return HitLighting::default();
    }
    let lights = lights.0.iter().take(MAX_SHADOW_LIGHTS).map(|(_, l, _)| LightInfo { intensity: l.intensity * exposure, ..*l });
    HitLighting { lights: lights.collect(), max_roughness: max_roughness.min(1.0), ..Default::default() }
}

/// Adds an effect's inputs to the ticket's: the prepass textures are every effect's, so only
/// the ones not yet there (a decoded G-buffer).
fn gather(into: &mut Option<PrepassInputs>, inputs: PrepassInputs) {
    let Some(first) = into else {
        *into = Some(inputs);
        return;
    };
    let textures: Vec<_> = inputs.textures.into_iter().filter(|t| !first.textures.contains(t)).collect();
    first.textures.extend(textures);
    let views: Vec<_> = inputs.views.into_iter().filter(|v| !first.views.contains(v)).collect();
    first.views.extend(views);
}
