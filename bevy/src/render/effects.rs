//! The effects traced per camera from Bevy's prepass — AO (into Bevy's AO texture or the
//! application's image) and a light's shadow (into the application's image) — with what every
//! effect shares: the denoiser each keeps per camera, the prepass as the SDK reads it, and the
//! recording of a camera's tasks among Bevy's commands; and the lights the shadows are traced
//! from.
use super::deferred::{composited, LightShadow};
use super::{Held, HybridRt, Warnings};
use crate::scene::ExtractedInstances;
use crate::{AoOutput, RayTracedAo, RayTracedShadow};
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::pbr::{ScreenSpaceAmbientOcclusionResources, SsaoBindGroups};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::texture::GpuImage;
use bevy::render::view::{ExtractedView, RetainedViewEntity};
use bevy::render::Extract;
use hybrid_rt::glam::Mat4;
use hybrid_rt::{
    DenoiseDiffuseOcclusionTask, DenoiseShadowTask, DenoisingCommon, DenoisingContextHandle, DenoisingContextInput, DepthInput,
    GpuTicket, ImageInput, LightInfo, LightType, MotionInput, MotionType, NormalInput, NormalType, SignalType, TaskContainer,
    TraceAmbientOcclusionTask, TraceCommon, TraceShadowTask, Viewport,
};
use hybrid_rt_wgpu::{prepare, wgpu, RtDevice};
use std::f32::consts::PI;

/// The effects a camera may trace, each with a denoiser of its own.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(super) enum Effect {
    Ao,
    Shadow,
    Gi,
    Reflections,
}

impl Effect {
    fn signal(self) -> SignalType {
        match self {
            Effect::Ao => SignalType::DiffuseOcclusion,
            Effect::Shadow => SignalType::Shadow,
            Effect::Gi => SignalType::Diffuse,
            Effect::Reflections => SignalType::Specular,
        }
    }

    /// The format of the noisy trace the denoiser reads (the shadow trace writes the occluder
    /// distance and the visible fraction).
    fn noisy_format(self) -> wgpu::TextureFormat {
        match self {
            Effect::Ao => wgpu::TextureFormat::R32Float,
            Effect::Shadow | Effect::Gi | Effect::Reflections => wgpu::TextureFormat::Rgba16Float,
        }
    }
}

/// A camera's denoised effect: the SDK's denoising context (its history) and the texture the
/// trace writes for the denoiser to read, both of the view's size.
pub(super) struct ViewDenoiser {
    pub(super) context: DenoisingContextHandle,
    noisy: wgpu::Texture,
    noisy_view: wgpu::TextureView,
    size: (u32, u32),
    /// The last frame that traced this camera's effect.
    pub(super) last_used: u64,
}

impl ViewDenoiser {
    fn new(rt: &RtDevice, size: (u32, u32), effect: Effect, warned: &mut Warnings) -> Option<ViewDenoiser> {
        let input = DenoisingContextInput {
            max_width: size.0,
            max_height: size.1,
            method: Default::default(),
            signal: effect.signal(),
            view_id: 0,
        };
        let context = match rt.context().create_denoising_context(&input) {
            Ok(c) => c,
            Err(e) => {
                warned.once(e);
                return None;
            }
        };
        let noisy = rt.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("hybrid-rt noisy trace"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: effect.noisy_format(),
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let noisy_view = noisy.create_view(&Default::default());
        Some(ViewDenoiser { context, noisy, noisy_view, size, last_used: 0 })
    }
}

/// Render world, extraction: the main world's visible directional, point and spot lights as
/// the SDK takes them, by main-world entity, directional lights first (in query order). Their
/// `intensity` x `color` is what lights Bevy's frame before the camera's exposure, in the
/// SDK's convention (a lit image is albedo x irradiance; Bevy's diffuse is albedo / pi x
/// irradiance): a directional light's illuminance / pi, a point or spot light's luminous
/// intensity (lumens / 4 pi) / pi. With each light whose shadow maps are off, the colour x
/// brightness Bevy lights with (illuminance, or lumens / 4 pi): what the composite takes a
/// shadow's part of.
#[derive(Resource, Default)]
pub(super) struct ExtractedLights(pub(super) Vec<(Entity, LightInfo, Option<[f32; 3]>)>);

/// The main world's lights of one kind, as `extract_lights` reads them.
type Lights<'w, 's, L> = Query<'w, 's, (Entity, &'static L, &'static GlobalTransform, &'static InheritedVisibility)>;

/// The largest spot cone the SDK takes (its outer half-angle must stay under pi/2; Bevy allows
/// pi/2 itself).
const MAX_SPOT_HALF_ANGLE: f32 = std::f32::consts::FRAC_PI_2 - 1e-3;

pub(super) fn extract_lights(
    mut out: ResMut<ExtractedLights>,
    suns: Extract<Lights<DirectionalLight>>,
    points: Extract<Lights<PointLight>>,
    spots: Extract<Lights<SpotLight>>,
) {
    let v = |v: Vec3| hybrid_rt::glam::Vec3::new(v.x, v.y, v.z);
    let colour = |c: Color| {
        let c = c.to_linear();
        [c.red, c.green, c.blue].map(|x| x.max(0.0))
    };
    let unshadowed =
        |shadow_maps: bool, c: Color, brightness: f32| (!shadow_maps).then(|| colour(c).map(|x| x * brightness.max(0.0)));
    out.0.clear();
    for (entity, sun, transform, visible) in &suns {
        if visible.get() {
            let light = LightInfo {
                light_type: LightType::Directional,
                direction: v(*transform.forward()),
                intensity: sun.illuminance.max(0.0) / PI,
                color: colour(sun.color),
                ..Default::default()
            };
            // A light without shadow maps lights Bevy's frame unshadowed: the composite can
            // take its occluded part out again.
            out.0.push((entity, light, unshadowed(sun.shadow_maps_enabled, sun.color, sun.illuminance)));
        }
    }
    for (entity, point, transform, visible) in &points {
        if visible.get() {
            let light = LightInfo {
                light_type: LightType::Point,
                position: v(transform.translation()),
                radius: point.radius.max(0.0),
                range: point.range.max(0.0),
                intensity: point.intensity.max(0.0) / (4.0 * PI * PI),
                color: colour(point.color),
                ..Default::default()
            };
            out.0.push((entity, light, unshadowed(point.shadow_maps_enabled, point.color, point.intensity / (4.0 * PI))));
        }
    }
    for (entity, spot, transform, visible) in &spots {
        if visible.get() {
            let outer = spot.outer_angle.clamp(0.0, MAX_SPOT_HALF_ANGLE);
            let light = LightInfo {
                light_type: LightType::Spot,
                position: v(transform.translation()),
                direction: v(*transform.forward()),
                radius: spot.radius.max(0.0),
                range: spot.range.max(0.0),
                inner_cone: spot.inner_angle.clamp(0.0, outer),
                outer_cone: outer,
                intensity: spot.intensity.max(0.0) / (4.0 * PI * PI),
                color: colour(spot.color),
                ..Default::default()
            };
            out.0.push((entity, light, unshadowed(spot.shadow_maps_enabled, spot.color, spot.intensity / (4.0 * PI))));
        }
    }
}

/// What a camera's traces read from Bevy's prepass (its depth and world-space normals, as they
/// are), with the wgpu objects to keep until the ticket is back.
pub(super) struct PrepassInputs {
    pub(super) common: TraceCommon,
    pub(super) motion: MotionInput,
    pub(super) textures: Vec<wgpu::Texture>,
    pub(super) views: Vec<wgpu::TextureView>,
}

/// The SDK's inputs from the view's prepass textures for an output of `size` (None: the prepass
/// has not made them this frame). Motion vectors where the camera has them.
fn prepass_inputs(
    rt: &RtDevice,
    view: &ExtractedView,
    prepass: &ViewPrepassTextures,
    size: (u32, u32),
) -> Result<Option<PrepassInputs>, hybrid_rt_wgpu::BridgeError> {
    let (Some(depth), Some(depth_view), Some(normal)) =
        (prepass.depth.as_ref(), prepass.depth_only_view(), prepass.normal.as_ref())
    else {
        return Ok(None);
    };
    let depth_image = rt.image(&depth.texture.texture, depth_view, hybrid_rt_wgpu::SDK_READ)?;
    let normal_image = rt.image(&normal.texture.texture, &normal.texture.default_view, hybrid_rt_wgpu::SDK_READ)?;
    let mut textures = vec![(*depth.texture.texture).clone(), (*normal.texture.texture).clone()];
    let mut views = vec![(**depth_view).clone(), (*normal.texture.default_view).clone()];
    // Bevy's motion vectors: current minus previous position in UV (y down); the SDK takes
    // previous minus current in normalized device coordinates (twice UV, y down too).
    let motion = match (prepass.motion_vectors.as_ref(), prepass.motion_vectors_view()) {
        (Some(mv), Some(mv_view)) => {
            let image = rt.image(&mv.texture.texture, mv_view, hybrid_rt_wgpu::SDK_READ)?;
            textures.push((*mv.texture.texture).clone());
            views.push((**mv_view).clone());
            MotionInput { image, motion_type: MotionType::RgClipSpace, scale: [-2.0, -2.0, 1.0] }
        }
        _ => MotionInput::default(),
    };
    let common = TraceCommon {
        depth: DepthInput { image: depth_image, ..Default::default() },
        normals: NormalInput { image: normal_image, normal_type: NormalType::RgbNormalizedVector, ..Default::default() },
        viewport: Viewport::full(size.0.min(depth_image.width), size.1.min(depth_image.height)),
        camera: sdk_camera(view),
        use_inline_rt: rt.context().supports_inline_rt(),
        ..Default::default()
    };
    Ok(Some(PrepassInputs { common, motion, textures, views }))
}

impl PrepassInputs {
    /// The denoisers' view of the same inputs.
    fn denoising(&self) -> DenoisingCommon {
        let c = &self.common;
        DenoisingCommon {
            depth: c.depth,
            normals: c.normals,
            roughness: c.roughness,
            input_mask: c.input_mask,
            motion: self.motion,
            viewport: c.viewport,
            camera: c.camera,
            ..Default::default()
        }
    }
}

/// The camera's denoiser for `effect` at `size` (made, or remade at a new size), marked used
/// this frame; None where the SDK refused it (logged once).
fn view_denoiser<'a>(
    views: &'a mut HashMap<(RetainedViewEntity, Effect), ViewDenoiser>,
    rt: &RtDevice,
    key: (RetainedViewEntity, Effect),
    size: (u32, u32),
    frame: u64,
    warned: &mut Warnings,
) -> Option<&'a ViewDenoiser> {
    if views.get(&key).is_none_or(|v| v.size != size) {
        if let Some(old) = views.remove(&key) {
            let _ = rt.context().destroy_denoising_context(old.context);
        }
        if let Some(v) = ViewDenoiser::new(rt, size, key.1, warned) {
            views.insert(key, v);
        }
    }
    views.get_mut(&key).map(|v| {
        v.last_used = frame;
        &*v
    })
}

/// What one camera's effect writes and reads: the SDK's view of the output image, the prepass
/// inputs at its size, and, denoised, the view's denoiser with its noisy image (which the trace
/// writes then, for the denoiser to read).
pub(super) struct EffectTargets {
    pub(super) output: ImageInput,
    pub(super) inputs: PrepassInputs,
    pub(super) noisy: Option<Noisy>,
}

/// A denoised effect's noisy trace: the denoiser's context, and the texture the trace writes
/// and the denoiser reads.
pub(super) struct Noisy {
    pub(super) context: DenoisingContextHandle,
    pub(super) texture: wgpu::Texture,
    pub(super) image: ImageInput,
}

/// The targets of `effect` for a camera writing `out` (None: nothing to trace this frame, or
/// input the SDK refused, logged once).
pub(super) fn effect_targets(
    rt: &RtDevice,
    (views, warned, frame): (&mut HashMap<(RetainedViewEntity, Effect), ViewDenoiser>, &mut Warnings, u64),
    (view, prepass): (&ExtractedView, &ViewPrepassTextures),
    (out_tex, out_view): (&wgpu::Texture, &wgpu::TextureView),
    effect: Effect,
    denoise: bool,
) -> Option<EffectTargets> {
    let attempt = || -> Result<Option<(ImageInput, PrepassInputs)>, hybrid_rt_wgpu::BridgeError> {
        let output = rt.image(out_tex, out_view, hybrid_rt_wgpu::SDK_WRITE)?;
        Ok(prepass_inputs(rt, view, prepass, (output.width, output.height))?.map(|inputs| (output, inputs)))
    };
    let (output, inputs) = match attempt() {
        Ok(Some(t)) => t,
        Ok(None) => return None,
        Err(e) => {
            warned.once(&e);
            return None;
        }
    };
    let noisy = match denoise {
        true => {
            let size = (output.width, output.height);
            let v = view_denoiser(views, rt, (view.retained_view_entity, effect), size, frame, warned)?;
            match rt.image(&v.noisy, &v.noisy_view, hybrid_rt_wgpu::SDK_WRITE) {
                Ok(image) => Some(Noisy { context: v.context, texture: v.noisy.clone(), image }),
                Err(e) => {
                    warned.once(&e);
                    return None;
                }
            }
        }
        false => None,
    };
    Some(EffectTargets { output, inputs, noisy })
}

/// The application's image an effect writes (None: not set, warned once, or not on the GPU yet).
pub(super) fn app_image<'a>(
    images: &'a RenderAssets<GpuImage>,
    handle: &Handle<Image>,
    component: &str,
    warned: &mut Warnings,
) -> Option<&'a GpuImage> {
    if *handle == Handle::default() {
        warned.once(format!("{component}.output is not set: give it an image of the view's size"));
        return None;
    }
    images.get(handle)
}

/// Schedules the effect's denoiser where it has one — `schedule(tasks, context, common, the
/// noisy trace, the output)` — and returns the textures the container writes: the output, and
/// the noisy trace the denoiser reads.
pub(super) fn schedule_denoiser(
    tasks: &mut TaskContainer,
    (noisy, inputs, output, out_tex): (&Option<Noisy>, &PrepassInputs, ImageInput, &wgpu::Texture),
    schedule: impl FnOnce(
        &mut TaskContainer,
        DenoisingContextHandle,
        DenoisingCommon,
        ImageInput,
        ImageInput,
    ) -> hybrid_rt::Result<()>,
) -> hybrid_rt::Result<Vec<wgpu::Texture>> {
    let mut writes = vec![out_tex.clone()];
    if let Some(n) = noisy {
        schedule(tasks, n.context, inputs.denoising(), n.image, output)?;
        writes.push(n.texture.clone());
    }
    Ok(writes)
}

/// Records one camera's tasks into a command buffer placed among Bevy's (after the barriers
/// that hand the textures to the SDK: `inputs`' to read, `writes` to write), and keeps the
/// wgpu objects they use until the ticket is back (`inputs`' and the outputs' `views` too).
#[allow(clippy::too_many_arguments)]
pub(super) fn record_view(
    rt: &RtDevice,
    (recorded, held, warned): (&mut Vec<GpuTicket>, &mut Held, &mut Warnings),
    ctx: &mut RenderContext,
    tasks: &mut TaskContainer,
    label: &str,
    inputs: PrepassInputs,
    writes: Vec<wgpu::Texture>,
    output_views: &[&wgpu::TextureView],
) -> bool {
    let reads: Vec<&wgpu::Texture> = inputs.textures.iter().collect();
    let write_refs: Vec<&wgpu::Texture> = writes.iter().collect();
    prepare(ctx.command_encoder(), &reads, &write_refs, &[]);
    // SAFETY: the textures and views the tasks name are kept (cloned) until the ticket is back.
    match unsafe { rt.record(tasks, Some(label)) } {
        Ok((commands, ticket)) => {
            ctx.add_command_buffer(commands);
            recorded.push(ticket);
            held.textures.extend(inputs.textures);
            held.textures.extend(writes);
            held.views.extend(inputs.views);
            held.views.extend(output_views.iter().map(|v| (*v).clone()));
            true
        }
        Err(e) => {
            warned.once(&e);
            false
        }
    }
}

/// Before the cameras render: Bevy's SSAO is not computed for cameras whose AO the SDK will
/// trace into Bevy's AO texture (its bind groups are taken from the view, which makes Bevy's
/// SSAO pass skip it; the texture itself stays for the SDK to write). Cameras the SDK will not
/// trace this frame (the effect off, nothing in the scene yet, no device) keep Bevy's SSAO.
pub(super) fn skip_replaced_ssao(
    mut commands: Commands,
    state: Res<HybridRt>,
    instances: Res<ExtractedInstances>,
    views: Query<(Entity, &RayTracedAo), With<SsaoBindGroups>>,
) {
    if state.rt.is_none() || instances.0.is_empty() {
        return;
    }
    for (entity, ao) in &views {
        if ao.enabled && ao.output == AoOutput::Pbr {
            commands.entity(entity).remove::<SsaoBindGroups>();
        }
    }
}

/// Per camera with [`RayTracedAo`]: AO from Bevy's prepass into the texture Bevy's PBR reads
/// its screen-space AO from (after Bevy's SSAO wrote it, before the opaque pass reads it), or
/// into the application's image.
pub(super) fn trace_ao(
    view: ViewQuery<(&ExtractedView, &ViewPrepassTextures, Option<&ScreenSpaceAmbientOcclusionResources>, &RayTracedAo)>,
    images: Res<RenderAssets<GpuImage>>,
    mut state: ResMut<HybridRt>,
    mut ctx: RenderContext,
) {
    let (view, prepass, ssao, settings) = view.into_inner();
    let state = &mut *state;
    let Some(rt) = state.rt.as_ref() else { return };
    if !settings.enabled || !state.has_instances {
        return;
    }
    let (out_tex, out_view) = match &settings.output {
        AoOutput::Pbr => match ssao {
            Some(s) => {
                (&s.screen_space_ambient_occlusion_texture.texture, &s.screen_space_ambient_occlusion_texture.default_view)
            }
            None => {
                // Bevy makes no AO texture for cameras with MSAA (as for its SSAO).
                state.warned.once("a camera with RayTracedAo has no AO texture: give it Msaa::Off");
                return;
            }
        },
        AoOutput::Image(handle) => match images.get(handle) {
            Some(image) => (&image.texture, &image.texture_view),
            None => return, // not on the GPU yet
        },
    };
    let sinks = (&mut state.views, &mut state.warned, state.frame);
    let Some(EffectTargets { output, inputs, noisy }) =
        effect_targets(rt, sinks, (view, prepass), (out_tex, out_view), Effect::Ao, settings.denoise)
    else {
        return;
    };
    let mut tasks = rt.context().create_task_container();
    let task = TraceAmbientOcclusionTask {
        common: inputs.common,
        output: noisy.as_ref().map_or(output, |n| n.image),
        ray_length: settings.ray_length,
        rays_per_pixel: settings.rays_per_pixel,
        ..Default::default()
    };
    if let Err(e) = tasks.schedule_ambient_occlusion(&task) {
        return state.warned.once(&e);
    }
    let denoise = |t: &mut TaskContainer, context, common, input, output| {
        t.schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask { context, common, input, output })
    };
    let writes = match schedule_denoiser(&mut tasks, (&noisy, &inputs, output, out_tex), denoise) {
        Ok(w) => w,
        Err(e) => return state.warned.once(&e),
    };
    let sinks = (&mut state.recorded, &mut state.held, &mut state.warned);
    record_view(rt, sinks, &mut ctx, &mut tasks, "hybrid-rt ao", inputs, writes, &[out_view]);
}

/// Per camera with [`RayTracedShadow`]: a light's shadow from Bevy's prepass into the
/// application's image.
pub(super) fn trace_shadow(
    view: ViewQuery<(&ExtractedView, &ExtractedCamera, &ViewPrepassTextures, &RayTracedShadow)>,
    images: Res<RenderAssets<GpuImage>>,
    lights: Res<ExtractedLights>,
    mut state: ResMut<HybridRt>,
    mut ctx: RenderContext,
) {
    let (view, camera, prepass, settings) = view.into_inner();
    let state = &mut *state;
    let Some(rt) = state.rt.as_ref() else { return };
    if !settings.enabled || !state.has_instances {
        return;
    }
    let found = match settings.light {
        Some(entity) => lights.0.iter().find(|(e, _, _)| *e == entity),
        None => lights.0.first().filter(|(_, l, _)| l.light_type == LightType::Directional),
    };
    let Some(&(_, mut light, unshadowed)) = found else {
        return state.warned.once(match settings.light {
            Some(entity) => format!("RayTracedShadow.light {entity} is not a visible DirectionalLight, PointLight or SpotLight"),
            None => "a camera has RayTracedShadow without a light, and the scene has no visible DirectionalLight".to_string(),
        });
    };
    if light.light_type == LightType::Directional {
        light.angular_extent = settings.angular_diameter;
    }
    let Some(image) = app_image(&images, &settings.output, "RayTracedShadow", &mut state.warned) else { return };
    let (out_tex, out_view) = (&image.texture, &image.texture_view);
    let sinks = (&mut state.views, &mut state.warned, state.frame);
    let Some(EffectTargets { output, inputs, noisy }) =
        effect_targets(rt, sinks, (view, prepass), (out_tex, out_view), Effect::Shadow, settings.denoise)
    else {
        return;
    };
    let mut tasks = rt.context().create_task_container();
    let task = TraceShadowTask {
        common: inputs.common,
        light,
        output: noisy.as_ref().map_or(output, |n| n.image),
        rays_per_pixel: settings.rays_per_pixel,
        ..Default::default()
    };
    if let Err(e) = tasks.schedule_shadow(&task) {
        return state.warned.once(&e);
    }
    let denoise = |t: &mut TaskContainer, context, common, input, output| {
        t.schedule_denoise_shadow(&DenoiseShadowTask { context, common, light, input, output })
    };
    let writes = match schedule_denoiser(&mut tasks, (&noisy, &inputs, output, out_tex), denoise) {
        Ok(w) => w,
        Err(e) => return state.warned.once(&e),
    };
    let sinks = (&mut state.recorded, &mut state.held, &mut state.warned);
    if !record_view(rt, sinks, &mut ctx, &mut tasks, "hybrid-rt shadow", inputs, writes, &[out_view]) {
        return;
    }
    // A deferred camera and a light without shadow maps: the composite takes the occluded part
    // of its light out of the lit image.
    if !settings.composite || prepass.deferred.is_none() {
        return;
    }
    let Some(radiance) = unshadowed else {
        return state.warned.once(
            "RayTracedShadow: the light's shadow maps are on, so Bevy's frame keeps them (give it shadow_maps_enabled: false for the ray-traced shadow to replace them)",
        );
    };
    let Some(visible) = composited(image, true, "RayTracedShadow", &mut state.warned) else { return };
    state.composites.entry(view.retained_view_entity).or_default().shadow =
        Some(LightShadow { visible, in_green: !settings.denoise, light, radiance: radiance.map(|c| c * camera.exposure) });
}

/// The view's camera as the SDK takes it: world to view, and Bevy's (unjittered) projection
/// with y turned down (Vulkan's clip space; wgpu's points y up). Reversed-Z with an infinite
/// far plane, as Bevy projects, the SDK detects itself.
fn sdk_camera(view: &ExtractedView) -> hybrid_rt::Camera {
    let world_from_view = Mat4::from_cols_array(&view.world_from_view.to_matrix().to_cols_array());
    let clip_from_view = Mat4::from_cols_array(&view.clip_from_view.to_cols_array());
    let flip_y = Mat4::from_scale(hybrid_rt::glam::Vec3::new(1.0, -1.0, 1.0));
    hybrid_rt::Camera { world_to_view: world_from_view.inverse(), view_to_clip: flip_y * clip_from_view }
}
