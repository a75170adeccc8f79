//! Bevy's render world: the SDK's context on Bevy's device, the scene sync before the cameras
//! render, AO and a light's shadow per camera between Bevy's SSAO and its opaque pass, tickets
//! handed back once the queue has done the frame.
mod deferred;
mod effects;
mod lighting;

use crate::scene::{extract_instances, ExtractedInstances, SceneMirror};
use crate::HybridRtTimings;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::schedule::camera_driver;
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::log::{error, warn};
use bevy::pbr::deferred::deferred_lighting;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::mesh::allocator::{MeshAllocator, MeshAllocatorSettings};
use bevy::render::mesh::RenderMesh;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::{RenderAdapter, RenderContext, RenderDevice, RenderGraph, RenderGraphSystems, RenderQueue};
use bevy::render::view::RetainedViewEntity;
use bevy::render::{ExtractSchedule, RenderApp};
use effects::{extract_lights, skip_replaced_ssao, trace_ao, trace_shadow, Effect, ExtractedLights, ViewDenoiser};
use hybrid_rt::{BvhBuildTask, CompletedTask, GpuTicket, InitSettings, TaskKind};
use hybrid_rt_wgpu::{prepare, wgpu, RtDevice};
use lighting::{trace_lighting, ViewImage};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// The SDK's working sets (tickets in flight at once): frames in flight (3) x tickets a frame
/// (the scene's, and one camera's AO, shadow, and GI with reflections).
const WORKING_SETS: u32 = 12;

/// wgpu objects (reference-counted handles) kept until a ticket is back.
#[derive(Default)]
struct Held {
    buffers: Vec<wgpu::Buffer>,
    textures: Vec<wgpu::Texture>,
    views: Vec<wgpu::TextureView>,
}

/// The SDK in Bevy's render world.
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
    /// Per camera and effect: the denoiser's context and the noisy trace it reads.
    views: HashMap<(RetainedViewEntity, Effect), ViewDenoiser>,
    /// Frames rendered (for dropping the contexts of cameras gone).
    frame: u64,
    /// Per camera tracing reflections: its deferred G-buffer decoded for the SDK.
    decoded: HashMap<RetainedViewEntity, ViewImage>,
    /// Per camera, what its traces left this frame for the composite (emptied each frame).
    composites: HashMap<RetainedViewEntity, deferred::CompositeRequest>,
    /// The deferred G-buffer's decode and composite pipelines (made when a deferred camera
    /// first needs them).
    deferred: Option<deferred::DeferredPasses>,
    /// Messages already logged: a refused input is reported once, not every frame.
    warned: Warnings,
}

impl Drop for HybridRt {
    /// The render world goes with the app: the queue finishes the frames still in flight and
    /// their tickets go back, so the SDK's context is destroyed with nothing outstanding.
    fn drop(&mut self) {
        let Some(rt) = self.rt.as_ref() else { return };
        if self.in_flight.is_empty() && self.recorded.is_empty() {
            return;
        }
        if let Err(e) = rt.device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }) {
            return error!("hybrid-rt: the queue did not finish at exit ({e}): the SDK keeps its frames' objects");
        }
        // Recorded tickets never submitted (the app stopped mid-frame) ran nothing: back too.
        let tickets = self.in_flight.drain(..).map(|(ticket, _, _)| ticket).chain(self.recorded.drain(..));
        for ticket in tickets {
            let _ = rt.context().mark_gpu_task_completed(ticket);
        }
    }
}

/// A camera's denoiser state is dropped after this many frames without it (a camera despawned,
/// its effect's component removed or disabled), freeing the denoiser's history.
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

pub(crate) fn build(app: &mut App, timings: HybridRtTimings) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    // The SDK copies positions and indices out of Bevy's mesh slabs.
    render_app.world_mut().get_resource_or_init::<MeshAllocatorSettings>().extra_buffer_usages |= wgpu::BufferUsages::COPY_SRC;
    render_app
        .insert_resource(timings)
        .init_resource::<HybridRt>()
        .init_resource::<ExtractedInstances>()
        .init_resource::<ExtractedLights>()
        .add_systems(ExtractSchedule, (extract_instances, extract_lights))
        .add_systems(RenderGraph, sync_scene.in_set(RenderGraphSystems::Render).before(camera_driver))
        .add_systems(RenderGraph, skip_replaced_ssao.in_set(RenderGraphSystems::Render).before(camera_driver))
        .add_systems(RenderGraph, track_submission.after(RenderGraphSystems::Submit))
        // After Bevy's SSAO (before MainPass), before whichever pass reads the AO texture: the
        // forward opaque pass, or the deferred lighting pass of a deferred camera.
        .add_systems(Core3d, trace_ao.in_set(Core3dSystems::MainPass).before(main_opaque_pass_3d).before(deferred_lighting))
        .add_systems(Core3d, trace_shadow.in_set(Core3dSystems::MainPass).before(main_opaque_pass_3d))
        // After the opaque pass lit the view target (forward, or deferred lighting then the
        // forward opaque pass), before transparent surfaces are drawn over it.
        .add_systems(
            Core3d,
            (trace_lighting, deferred::composite)
                .chain()
                .in_set(Core3dSystems::MainPass)
                .after(main_opaque_pass_3d)
                .before(main_transparent_pass_3d),
        );
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
    state.decoded.retain(|_, image| frame - image.last_used <= VIEW_GRACE_FRAMES);
    state.composites.clear();
    let histories = |effect: Effect| state.views.keys().filter(|(_, e)| *e == effect).count() as f64;
    let counts = [
        ("ao_histories", histories(Effect::Ao)),
        ("shadow_histories", histories(Effect::Shadow)),
        ("gi_histories", histories(Effect::Gi)),
        ("reflections_histories", histories(Effect::Reflections)),
    ];
    timings.0.lock().extend(counts.map(|(name, n)| (name.to_string(), n)));
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

/// The SDK's GPU times of one frame's tickets (milliseconds), for the main world's diagnostics.
#[derive(Default)]
struct FrameTimes {
    scene: f64,
    ao: f64,
    shadow: f64,
    gi: f64,
    reflections: f64,
    total: f64,
    /// Per task kind (`TaskKind as usize`).
    tasks: Vec<f64>,
}

impl FrameTimes {
    fn add(&mut self, completed: &CompletedTask) {
        for t in &completed.timings {
            self.total += t.gpu_ms;
            let at = t.kind as usize;
            if self.tasks.len() <= at {
                self.tasks.resize(at + 1, 0.0);
            }
            self.tasks[at] += t.gpu_ms;
            match t.kind {
                TaskKind::AmbientOcclusion | TaskKind::DenoiseDiffuseOcclusion => self.ao += t.gpu_ms,
                TaskKind::Shadow | TaskKind::DenoiseShadow => self.shadow += t.gpu_ms,
                TaskKind::DirectLightingInjection | TaskKind::Diffuse | TaskKind::DenoiseDiffuse => self.gi += t.gpu_ms,
                TaskKind::Specular | TaskKind::DenoiseSpecular => self.reflections += t.gpu_ms,
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
        if self.shadow > 0.0 {
            out.push(("shadow".into(), self.shadow));
        }
        if self.gi > 0.0 {
            out.push(("gi".into(), self.gi));
        }
        if self.reflections > 0.0 {
            out.push(("reflections".into(), self.reflections));
        }
        out.push(("frame".into(), self.total));
        for kind in TaskKind::ALL {
            if let Some(&ms) = self.tasks.get(*kind as usize).filter(|ms| **ms > 0.0) {
                out.push((format!("task/{}", kind.name()), ms));
            }
        }
    }
}
