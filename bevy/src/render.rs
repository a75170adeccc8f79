//! Bevy's render world: the SDK's context on Bevy's device, the scene sync before the cameras
//! render, AO per camera between Bevy's SSAO and its opaque pass, tickets handed back once the
//! queue has done the frame.
use crate::scene::{extract_instances, ExtractedInstances, SceneMirror};
use crate::{AoOutput, HybridRtTimings, RayTracedAo};
use bevy::core_pipeline::core_3d::main_opaque_pass_3d;
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::core_pipeline::schedule::camera_driver;
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::log::{error, warn};
use bevy::pbr::deferred::deferred_lighting;
use bevy::pbr::ScreenSpaceAmbientOcclusionResources;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::mesh::allocator::{MeshAllocator, MeshAllocatorSettings};
use bevy::render::mesh::RenderMesh;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{
    RenderAdapter, RenderContext, RenderDevice, RenderGraph, RenderGraphSystems, RenderQueue, ViewQuery,
};
use bevy::render::texture::GpuImage;
use bevy::render::view::ExtractedView;
use bevy::render::view::RetainedViewEntity;
use bevy::render::{ExtractSchedule, RenderApp};
use hybrid_rt::glam::Mat4;
use hybrid_rt::{
    BvhBuildTask, CompletedTask, DenoiseDiffuseOcclusionTask, DenoisingCommon, DenoisingContextHandle, DenoisingContextInput,
    DepthInput, GpuTicket, InitSettings, MotionInput, MotionType, NormalInput, NormalType, SignalType, TaskKind,
    TraceAmbientOcclusionTask, TraceCommon, Viewport,
};
use hybrid_rt_wgpu::{prepare, wgpu, RtDevice};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// The SDK in Bevy's render world.
/// The SDK's working sets (tickets in flight at once): frames in flight (3) x tickets a frame
/// (the scene's and one camera's).
const WORKING_SETS: u32 = 6;

/// wgpu objects (reference-counted handles) kept until a ticket is back.
#[derive(Default)]
struct Held {
    buffers: Vec<wgpu::Buffer>,
    textures: Vec<wgpu::Texture>,
    views: Vec<bevy::render::render_resource::TextureView>,
}

#[derive(Resource, Default)]
pub(crate) struct HybridRt {
    /// Made on the first frame, on Bevy's device (None until then, or if that failed).
    rt: Option<RtDevice>,
    failed: bool,
    scene: SceneMirror,
    /// Tickets recorded this frame, waiting for Bevy's submission.
    recorded: Vec<GpuTicket>,
    /// Tickets submitted, with the flag the queue sets once their frame is done, and the wgpu
    /// objects their commands use (kept alive until then: wgpu does not see the SDK's use).
    in_flight: Vec<(GpuTicket, Arc<AtomicBool>, Held)>,
    /// The wgpu objects this frame's SDK commands use.
    held: Held,
    /// Nothing traced until the BVH has instances.
    has_instances: bool,
    /// Per camera: the AO denoiser's context and the noisy trace it reads.
    views: HashMap<RetainedViewEntity, ViewAo>,
    /// Frames rendered (for dropping the contexts of cameras gone).
    frame: u64,
    /// Messages already logged: a refused input is reported once, not every frame.
    warned: Warnings,
}

/// A camera's AO state is dropped after this many frames without it (a camera despawned, its
/// `RayTracedAo` removed or disabled), freeing the denoiser's history.
const VIEW_GRACE_FRAMES: u64 = 3;

/// Messages logged once each (bounded, so a message that changes every frame cannot grow it).
#[derive(Default)]
struct Warnings(bevy::platform::collections::HashSet<String>);

impl Warnings {
    fn once(&mut self, message: impl std::fmt::Display) {
        let message = format!("hybrid-rt: {message}");
        if self.0.len() < 256 && self.0.insert(message.clone()) {
            warn!("{message}");
        }
    }
}

/// A camera's denoised AO: the SDK's denoising context (its history) and the texture the
/// 1-ray trace writes for the denoiser to read, both of the view's size.
struct ViewAo {
    context: DenoisingContextHandle,
    noisy: wgpu::Texture,
    noisy_view: wgpu::TextureView,
    size: (u32, u32),
    /// The last frame that traced this camera.
    last_used: u64,
}

impl ViewAo {
    fn new(rt: &RtDevice, size: (u32, u32), warned: &mut Warnings) -> Option<ViewAo> {
        let input = DenoisingContextInput {
            max_width: size.0,
            max_height: size.1,
            method: Default::default(),
            signal: SignalType::DiffuseOcclusion,
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
            label: Some("hybrid-rt noisy ao"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let noisy_view = noisy.create_view(&Default::default());
        Some(ViewAo { context, noisy, noisy_view, size, last_used: 0 })
    }
}

pub(crate) fn build(app: &mut App, timings: HybridRtTimings) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    // The SDK copies positions and indices out of Bevy's mesh slabs.
    render_app.world_mut().get_resource_or_init::<MeshAllocatorSettings>().extra_buffer_usages |= wgpu::BufferUsages::COPY_SRC;
    render_app
        .insert_resource(timings)
        .init_resource::<HybridRt>()
        .init_resource::<ExtractedInstances>()
        .add_systems(ExtractSchedule, extract_instances)
        .add_systems(RenderGraph, sync_scene.in_set(RenderGraphSystems::Render).before(camera_driver))
        .add_systems(RenderGraph, track_submission.after(RenderGraphSystems::Submit))
        // After Bevy's SSAO (before MainPass), before whichever pass reads the AO texture: the
        // forward opaque pass, or the deferred lighting pass of a deferred camera.
        .add_systems(Core3d, trace_ao.in_set(Core3dSystems::MainPass).before(main_opaque_pass_3d).before(deferred_lighting));
}

/// Before the cameras: hand back the tickets whose frames are done, then bring the SDK's scene
/// to this frame's entities and rebuild its BVH where anything changed.
#[allow(clippy::too_many_arguments)]
fn sync_scene(
    mut state: ResMut<HybridRt>,
    adapter: Res<RenderAdapter>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    extracted: Res<ExtractedInstances>,
    allocator: Res<MeshAllocator>,
    meshes: Res<RenderAssets<RenderMesh>>,
    timings: Res<HybridRtTimings>,
    mut ctx: RenderContext,
) {
    let state = &mut *state;
    if state.rt.is_none() && !state.failed {
        // Tickets in flight: the scene's and one per camera each frame, and Bevy's pipelined
        // rendering keeps up to three frames on the GPU.
        let settings = InitSettings { supported_working_sets: WORKING_SETS, ..Default::default() };
        match RtDevice::attach(&adapter, device.wgpu_device(), &queue, &settings) {
            Ok(rt) => state.rt = Some(rt),
            Err(e) => {
                error!("hybrid-rt: cannot attach to Bevy's device: {e} (see hybrid_rt_bevy::HybridRtInitPlugin)");
                state.failed = true;
            }
        }
    }
    let Some(rt) = state.rt.as_ref() else { return };
    // Tickets of frames the queue has finished.
    let (done, waiting): (Vec<_>, Vec<_>) = state.in_flight.drain(..).partition(|(_, flag, _)| flag.load(Ordering::Acquire));
    state.in_flight = waiting;
    // A frame's tickets share its flag: their times add up to the frame's.
    let mut frames: Vec<(*const AtomicBool, FrameTimes)> = Vec::new();
    for (ticket, flag, _) in done {
        match rt.context().mark_gpu_task_completed(ticket) {
            Ok(completed) => {
                let key = Arc::as_ptr(&flag);
                let at = frames.iter().position(|(k, _)| *k == key).unwrap_or_else(|| {
                    frames.push((key, FrameTimes::default()));
                    frames.len() - 1
                });
                frames[at].1.add(&completed);
            }
            Err(e) => state.warned.once(&e),
        }
    }
    for (_, times) in frames {
        times.publish(&timings);
    }
    // Cameras gone or no longer traced: their denoiser history is freed (the SDK keeps it until
    // the tickets that use it are back; the noisy textures are held with those tickets).
    state.frame += 1;
    let frame = state.frame;
    state.views.retain(|_, v| {
        let keep = frame - v.last_used <= VIEW_GRACE_FRAMES;
        if !keep {
            let _ = rt.context().destroy_denoising_context(v.context);
        }
        keep
    });
    timings.0.lock().push(("ao_histories".into(), state.views.len() as f64));
    let mut tasks = rt.context().create_task_container();
    let outcome = match state.scene.sync(rt, &mut tasks, &extracted, &allocator, &meshes) {
        Ok(o) => o,
        Err(e) => {
            state.warned.once(format!("scene sync: {e}"));
            return;
        }
    };
    state.has_instances = !extracted.0.is_empty();
    if !outcome.changed {
        return;
    }
    if let Err(e) = tasks.schedule_bvh_build(&BvhBuildTask::default()) {
        state.warned.once(&e);
        return;
    }
    let copies: Vec<&wgpu::Buffer> = outcome.copies.iter().collect();
    prepare(ctx.command_encoder(), &[], &[], &copies);
    // SAFETY: the slab buffers the tasks name are kept (cloned) with the ticket until it is back.
    match unsafe { rt.record(&mut tasks, Some("hybrid-rt scene")) } {
        Ok((commands, ticket)) => {
            ctx.add_command_buffer(commands);
            state.recorded.push(ticket);
            state.held.buffers.extend(outcome.copies);
            state.scene.release_removed(rt);
        }
        Err(e) => state.warned.once(&e),
    }
}

/// Per camera with [`RayTracedAo`]: AO from Bevy's prepass into the texture Bevy's PBR reads
/// its screen-space AO from (after Bevy's SSAO wrote it, before the opaque pass reads it), or
/// into the application's image.
fn trace_ao(
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
    let (Some(depth), Some(depth_view), Some(normal)) =
        (prepass.depth.as_ref(), prepass.depth_only_view(), prepass.normal.as_ref())
    else {
        return;
    };
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
    let (depth_tex, normal_tex, out_tex): (&wgpu::Texture, &wgpu::Texture, &wgpu::Texture) =
        (&depth.texture.texture, &normal.texture.texture, out_tex);
    let inputs = (|| -> std::result::Result<_, hybrid_rt_wgpu::BridgeError> {
        Ok((
            rt.image(depth_tex, depth_view, hybrid_rt_wgpu::SDK_READ)?,
            rt.image(normal_tex, &normal.texture.default_view, hybrid_rt_wgpu::SDK_READ)?,
            rt.image(out_tex, out_view, hybrid_rt_wgpu::SDK_WRITE)?,
        ))
    })();
    let (depth_image, normal_image, output) = match inputs {
        Ok(i) => i,
        Err(e) => {
            state.warned.once(&e);
            return;
        }
    };
    let common = TraceCommon {
        depth: DepthInput { image: depth_image, ..Default::default() },
        normals: NormalInput { image: normal_image, normal_type: NormalType::RgbNormalizedVector, ..Default::default() },
        viewport: Viewport::full(output.width.min(depth_image.width), output.height.min(depth_image.height)),
        camera: sdk_camera(view),
        use_inline_rt: rt.context().supports_inline_rt(),
        ..Default::default()
    };
    let mut tasks = rt.context().create_task_container();
    let mut reads: Vec<&wgpu::Texture> = vec![depth_tex, normal_tex];
    let mut writes: Vec<&wgpu::Texture> = vec![out_tex];
    let size = (output.width, output.height);
    // Denoised: the trace writes the view's noisy texture, the denoiser the output.
    let denoiser = if settings.denoise {
        if state.views.get(&view.retained_view_entity).is_none_or(|v| v.size != size) {
            if let Some(old) = state.views.remove(&view.retained_view_entity) {
                let _ = rt.context().destroy_denoising_context(old.context);
            }
            if let Some(v) = ViewAo::new(rt, size, &mut state.warned) {
                state.views.insert(view.retained_view_entity, v);
            }
        }
        let frame = state.frame;
        state.views.get_mut(&view.retained_view_entity).map(|v| {
            v.last_used = frame;
            &*v
        })
    } else {
        None
    };
    let noisy = match denoiser {
        Some(v) => match rt.image(&v.noisy, &v.noisy_view, hybrid_rt_wgpu::SDK_WRITE) {
            Ok(i) => Some((v, i)),
            Err(e) => {
                state.warned.once(&e);
                return;
            }
        },
        None => None,
    };
    let task = TraceAmbientOcclusionTask {
        common,
        output: noisy.as_ref().map_or(output, |(_, i)| *i),
        ray_length: settings.ray_length,
        rays_per_pixel: settings.rays_per_pixel,
        ..Default::default()
    };
    if let Err(e) = tasks.schedule_ambient_occlusion(&task) {
        state.warned.once(&e);
        return;
    }
    if let Some((v, noisy_image)) = &noisy {
        // Bevy's motion vectors: current minus previous position in UV (y down); the SDK takes
        // previous minus current in normalized device coordinates (twice UV, y down too).
        let motion = match (prepass.motion_vectors.as_ref(), prepass.motion_vectors_view()) {
            (Some(mv), Some(mv_view)) => match rt.image(&mv.texture.texture, mv_view, hybrid_rt_wgpu::SDK_READ) {
                Ok(image) => {
                    reads.push(&mv.texture.texture);
                    state.held.textures.push((*mv.texture.texture).clone());
                    state.held.views.push(mv_view.clone());
                    MotionInput { image, motion_type: MotionType::RgClipSpace, scale: [-2.0, -2.0, 1.0] }
                }
                Err(e) => {
                    state.warned.once(&e);
                    return;
                }
            },
            _ => MotionInput::default(),
        };
        let denoise = DenoiseDiffuseOcclusionTask {
            context: v.context,
            common: DenoisingCommon {
                depth: common.depth,
                normals: common.normals,
                motion,
                viewport: common.viewport,
                camera: common.camera,
                ..Default::default()
            },
            input: *noisy_image,
            output,
        };
        if let Err(e) = tasks.schedule_denoise_diffuse_occlusion(&denoise) {
            state.warned.once(&e);
            return;
        }
        writes.push(&v.noisy);
        state.held.textures.push(v.noisy.clone());
    }
    prepare(ctx.command_encoder(), &reads, &writes, &[]);
    // SAFETY: the textures and views the task names are kept (cloned) until its ticket is back.
    match unsafe { rt.record(&mut tasks, Some("hybrid-rt ao")) } {
        Ok((commands, ticket)) => {
            ctx.add_command_buffer(commands);
            state.recorded.push(ticket);
            state.held.textures.extend([depth_tex.clone(), normal_tex.clone(), out_tex.clone()]);
            state.held.views.extend([depth_view.clone(), normal.texture.default_view.clone(), out_view.clone()]);
        }
        Err(e) => state.warned.once(&e),
    }
}

/// After Bevy submitted the frame: its tickets are done once the queue has done the frame.
fn track_submission(mut state: ResMut<HybridRt>, queue: Res<RenderQueue>) {
    if state.recorded.is_empty() {
        return;
    }
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    queue.on_submitted_work_done(move || f.store(true, Ordering::Release));
    let mut held = std::mem::take(&mut state.held);
    let recorded = std::mem::take(&mut state.recorded);
    for ticket in recorded {
        // The frame's objects go with its first ticket: all its tickets come back together.
        state.in_flight.push((ticket, flag.clone(), std::mem::take(&mut held)));
    }
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

/// The SDK's GPU times of one frame's tickets (milliseconds), for the main world's diagnostics.
#[derive(Default)]
struct FrameTimes {
    scene: f64,
    ao: f64,
    total: f64,
}

impl FrameTimes {
    fn add(&mut self, completed: &CompletedTask) {
        for t in &completed.timings {
            self.total += t.gpu_ms;
            match t.kind {
                TaskKind::AmbientOcclusion | TaskKind::DenoiseDiffuseOcclusion => self.ao += t.gpu_ms,
                _ => self.scene += t.gpu_ms,
            }
        }
    }

    fn publish(&self, timings: &HybridRtTimings) {
        let mut out = timings.0.lock();
        if self.scene > 0.0 {
            out.push(("scene".into(), self.scene));
        }
        if self.ao > 0.0 {
            out.push(("ao".into(), self.ao));
        }
        out.push(("frame".into(), self.total));
    }
}
