//! The sample's hybrid renderer: an engine's frame with hybrid-rt in it, written the way the
//! integration guide (docs/integration.md) tells an engine to do it.
//!
//! Per frame, in one command buffer the sample owns:
//! 1. its own raster G-buffer of the main camera and of a low-resolution "lidar" camera that
//!    sweeps the scene (`raster`);
//! 2. **one SDK task container**: the scene's changes (the moving cube's instance update, the
//!    waving flag's geometry update, which refits its BLAS), a throttled BVH build, light
//!    injection of *last* frame's lit images (main and lidar: the lit image of this frame
//!    needs this frame's shadows, so the cache runs a frame behind, which a cache averaging
//!    over many frames does not notice), shadows of the sun and the point light (main view:
//!    1 ray and denoised; lidar view: 1 ray, raw), AO, diffuse GI and reflections (1 ray each)
//!    with their denoisers (specular and diffuse in one task), and the debug visualisations
//!    asked for;
//! 3. its deferred direct lighting of both views (`lighting`), then the composite
//!    (direct + GI x albedo x AO + Fresnel x reflections), then the view of the chosen mode.
//!
//! Two frames are in flight: each slot has its command buffer, fence, constant buffers,
//! G-buffer, lit image and the flag's vertex buffer; before a slot is reused its fence is
//! waited on and its SDK ticket handed back (which is also where per-task GPU times come
//! from). The images written and read within a frame (shadows, AO, GI, reflections, the
//! composite) are shared by both slots: one queue runs the frames in order and every frame
//! starts with a barrier on the previous one's writes.
use crate::gpu::{spirv, ComputePass};
use crate::lighting::{LightingPass, Visibility};
use crate::mesh_buffers::{Vertex, VERTEX_STRIDE};
use crate::modes::Mode;
use crate::raster::{self, Draw, GBufferPass, MeshBuffers, VertexAttributes};
use crate::scene::SampleScene;
use crate::skinning::SkinningPass;
use ash::vk;
use glam::Vec3;
use hybrid_rt::*;
use hybrid_rt_host::scene::Camera;
use hybrid_rt_host::{Host, HostImage, HostResult};

mod inputs;
mod many_lights;
mod resources;
mod schedule;
mod stats;

use resources::{source, Denoisers, Slot, Work};
pub use stats::Stats;

const SLOTS: usize = 2;
const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

/// Log-average luminance the automatic exposure maps the composite to (`Renderer::auto_expose`).
const AUTO_EXPOSURE_KEY: f64 = 0.18;
/// The view id of the main camera's denoising contexts (`DenoisingContextInput::view_id`).
const MAIN_VIEW: u32 = 1;

/// The cameras of one frame: the main view's and the lidar's, and last frame's of each.
#[derive(Clone, Copy)]
struct FrameCameras {
    main: Camera,
    lidar: Camera,
    prev_main: Camera,
    prev_lidar: Camera,
}

/// What the renderer does per frame. Defaults in `Default`.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Side of the square lidar view. Default 256 (the guide's 256-512: its pixels must be
    /// no larger than a cache sample where it looks, or samples get no light).
    pub lidar_size: u32,
    /// Shadow rays per pixel and light of the lidar view. Default 1: its lit image only feeds
    /// the caches' running average (`injection_window` frames), which averages the noise; at
    /// 256x256 every extra ray is another full trace latency on a mostly idle GPU (4 rays
    /// cost 3.3x one on an H200).
    pub lidar_rays: u32,
    /// BLAS builds per frame (`BvhBuildTask::max_blas_build_count`). Default 4: the default
    /// scene's 12 meshes take three frames, as a level streaming in would.
    pub max_blas_build_count: u32,
    /// `BvhBuildTask::tlas_max_refits`. Default 15: the sample's moving instances (the cube,
    /// the forest's drifting canopies) move slowly and locally, so a TLAS refit costs
    /// nothing measurable in trace time and spares most frames a full build.
    pub tlas_max_refits: u32,
    /// Rays per pixel of the main view's shadow, AO, GI and reflection traces. Default 1.
    pub rays_per_pixel: u32,
    /// Trace half the pixels each frame (checkerboard) and let the denoisers fill the rest.
    /// Default false.
    pub checkerboard: bool,
    /// Where every trace's random numbers come from (`TraceCommon::random_numbers`). Default
    /// the SDK's default sequences.
    pub random_numbers: RandomNumbers,
    /// Frames over which injection averages a cache sample. Default 24 (the guide's 200
    /// suits a static level; the sample's cube moves and its shadow with it).
    pub injection_window: f32,
    /// `DirectLightingInjectionTask::injection_resolution_stride` of the main view (the lidar
    /// always injects every pixel). Default 0: the view's height over 540 (1 up to 1079
    /// lines, 2 at 1080p and 1440p, 4 at 2160p), about as many injected pixels as a 960x540
    /// view, which is still several per cache sample where the camera looks.
    pub injection_stride: u32,
    /// Multiplies radiance before tone mapping. Default 1.
    pub exposure: f32,
    /// The colour of cache samples no camera has lit yet (`InstanceInput::initial_tile_color`).
    /// Default black; magenta (`--magenta-unlit`) makes coverage holes visible while
    /// integrating, as the guide suggests.
    pub unlit_color: [f32; 3],
    /// Cache samples relit from the scene's lights per frame (`RelightCacheTask::max_samples`;
    /// 0: no relighting). Default 65,536: the room's 17 caches (about 40,000 samples) are all
    /// relit every frame, the forest's round-robin in a few dozen.
    pub relight_samples: u32,
    /// Shade the mirror's reflections from the sun and the point light with shadow rays
    /// (`TraceSpecularTask::hit_lighting`, pixels of roughness up to 0.1) instead of the
    /// cache: sharp shadow edges in the mirror, but surfaces lit only by the bounce (the
    /// column's back) read one cache sample's residual, unfiltered, so they stay noisier
    /// than the cache's interpolation for the first frames. Default false.
    pub hit_lighting: bool,
    /// `InitSettings::cache_budget_bytes` (0: none, the default): over it, the caches of the
    /// instances unused longest are evicted (the report says how many).
    pub cache_budget_bytes: u64,
    /// `InitSettings::time_passes`: the report breaks each denoiser's time down by pass.
    /// Default false.
    pub time_passes: bool,
    /// Scatter this many small lights through the scene and shade them with the SDK's
    /// resampled direct lighting (`TraceManyLightsTask`), denoised; 0 (the default): none.
    pub many_lights: u32,
    /// `DenoiserSettings::fresh_history_taps` of the reflections + GI denoiser: extra blur taps
    /// where diffuse history is fresh. Default 0 (the SDK's default).
    pub fresh_history_taps: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 640,
            height: 360,
            lidar_size: 256,
            lidar_rays: 1,
            unlit_color: [0.0; 3],
            max_blas_build_count: 4,
            tlas_max_refits: 15,
            rays_per_pixel: 1,
            checkerboard: false,
            random_numbers: RandomNumbers::Default,
            injection_window: 24.0,
            injection_stride: 0,
            exposure: 1.0,
            relight_samples: 65_536,
            hit_lighting: false,
            cache_budget_bytes: 0,
            many_lights: 0,
            fresh_history_taps: 0,
            time_passes: false,
        }
    }
}

pub struct Renderer<'h> {
    host: &'h Host,
    pub ctx: ExecuteContext,
    container: TaskContainer,
    pub scene: SampleScene,
    pub settings: Settings,
    geometries: Vec<GeometryHandle>,
    pub instances: Vec<InstanceHandle>,
    meshes: MeshBuffers,
    gbuffer: GBufferPass,
    lighting: LightingPass,
    skinning: SkinningPass,
    composite: ComputePass,
    view: ComputePass,
    slots: Vec<Slot>,
    work: Work,
    denoisers: Denoisers,
    /// `Settings::many_lights`: the lights and their SDK contexts and images.
    many: Option<many_lights::ManyLights>,
    /// Have the many-lights task write its debug output (the `many_lights_debug` mode) in
    /// the frames recorded while set; like the SDK debug views, a cost only when shown.
    pub many_lights_debug: bool,
    frame: u64,
    last_slot: usize,
    prev_transforms: Vec<glam::Affine3A>,
    /// The last frame's animation time (the flag's previous vertices).
    prev_time: f32,
    /// The furthest a GI or reflection ray needs to go: the scene's diagonal.
    reach: f32,
    pub stats: Stats,
}

fn sdk_err(e: hybrid_rt::Error) -> String {
    e.to_string()
}

/// Mesh `i` as the SDK registers it: its buffers, its cache's tile size, its cut-out's alpha
/// test, and the base-colour texture relighting and hit lighting read (texture x the
/// instance's tint), with the texture coordinates either needs.
fn sdk_geometry_input(scene: &SampleScene, meshes: &MeshBuffers, i: usize, allow_update: bool) -> GeometryInput {
    let cutout = scene.cutouts.get(i).copied().flatten().and_then(|c| Some((meshes.texture_input(c.texture)?, c.cutoff)));
    let albedo = scene.mesh_albedo_texture(i).and_then(|k| meshes.texture_input(k));
    GeometryInput {
        allow_update,
        surfels: SurfelSettings { tile_unit_length: scene.tile_unit_length, ..Default::default() },
        uvs: (cutout.is_some() || albedo.is_some()).then(|| meshes.uv_input(i)),
        alpha_test: cutout.map(|(texture, cutoff)| AlphaTestInput { texture, cutoff, ..Default::default() }),
        albedo_texture: albedo.map(|texture| AlbedoTextureInput { texture }),
        ..meshes.geometry_input(i)
    }
}

impl<'h> Renderer<'h> {
    pub fn new(host: &'h Host, scene: SampleScene, settings: Settings) -> HostResult<Renderer<'h>> {
        let (w, h) = (settings.width, settings.height);
        let ctx = host
            .create_context(&InitSettings {
                supported_working_sets: SLOTS as u32,
                cache_budget_bytes: settings.cache_budget_bytes,
                time_passes: settings.time_passes,
                ..Default::default()
            })
            .map_err(sdk_err)?;
        let mut container = ctx.create_task_container();
        let attributes: Vec<_> = (0..scene.scene.meshes.len()).map(|k| scene.vertex_attributes(k)).collect();
        let meshes = MeshBuffers::upload(host, &scene.scene, &attributes, &scene.textures)?;
        // Register every mesh and instance (one BLAS per mesh; the flag's may be refit).
        let geometries = ctx.create_geometry_handles(scene.scene.meshes.len());
        for (i, &handle) in geometries.iter().enumerate() {
            let input = sdk_geometry_input(&scene, &meshes, i, scene.is_deforming(i));
            let task = GeometryTask { handle, operation: TaskOperation::Register, input };
            // SAFETY: the engine's buffers the task names are alive.
            schedule::schedule(&mut container, schedule::BVH_LABEL, |c| unsafe { c.schedule_geometry(&task) })?;
        }
        let instances = ctx.create_instance_handles(scene.scene.instances.len());
        for (i, &handle) in instances.iter().enumerate() {
            let inst = &scene.scene.instances[i];
            let input = InstanceInput {
                geometry: geometries[inst.mesh],
                transform: scene.transform(i, 0.0),
                initial_tile_color: settings.unlit_color,
                albedo: scene.diffuse_albedo(i),
                emission: scene.emission(i),
                ..Default::default()
            };
            let task = InstanceTask { handle, operation: InstanceOperation::Register, input };
            schedule::schedule(&mut container, schedule::BVH_LABEL, |c| c.schedule_instance(&task))?;
        }
        let skinning = SkinningPass::new(host, &scene)?;
        let mut slots = Vec::new();
        for _ in 0..SLOTS {
            // The flag's vertices of the slot's frame, then of the frame before (see write_deformed).
            let rest = scene.deformer.as_ref().map(|d| deformed_vertices(&scene, d, 0.0).repeat(2));
            let posed = skinning.posed_buffers(host, &scene)?;
            slots.push(Slot::new(host, w, h, settings.lidar_size, rest.as_deref(), posed, scene.camera_path.at(0.0))?);
        }
        let work = Work::new(host, w, h, settings.lidar_size, scene.file_lights.len())?;
        let context = |signal| {
            // One view: the four contexts of the main camera share one denoiser guide.
            let view_id = MAIN_VIEW;
            ctx.create_denoising_context(&DenoisingContextInput {
                max_width: w,
                max_height: h,
                signal,
                view_id,
                ..Default::default()
            })
        };
        let denoisers = Denoisers {
            sun: context(SignalType::Shadow).map_err(sdk_err)?,
            point: context(SignalType::Shadow).map_err(sdk_err)?,
            ao: context(SignalType::DiffuseOcclusion).map_err(sdk_err)?,
            radiance: context(SignalType::SpecularAndDiffuse).map_err(sdk_err)?,
            lights: match scene.file_lights.is_empty() {
                true => None,
                false => Some(context(SignalType::MultiShadow).map_err(sdk_err)?),
            },
        };
        let many = match settings.many_lights {
            0 => None,
            n => {
                let lights = many_lights::scatter(scene.bounds(), scene.lights.point_intensity, n as usize);
                Some(many_lights::ManyLights::new(host, &ctx, lights, w, h)?)
            }
        };
        let prev_transforms = scene.transforms(0.0);
        let (lo, hi) = scene.bounds();
        let reach = (hi - lo).length().max(1.0);
        Ok(Renderer {
            host,
            ctx,
            container,
            scene,
            settings,
            geometries,
            instances,
            meshes,
            gbuffer: GBufferPass::new(host)?,
            lighting: LightingPass::new(host)?,
            skinning,
            composite: ComputePass::new(host, spirv::COMPOSITE_COMP, 7, 1)?,
            view: ComputePass::new(host, spirv::VIEW_COMP, 1, 2)?,
            slots,
            work,
            denoisers,
            many,
            many_lights_debug: false,
            frame: 0,
            last_slot: 0,
            prev_transforms,
            prev_time: 0.0,
            reach,
            stats: Stats::default(),
        })
    }

    /// Waits for the next slot's previous frame, hands its ticket back (collecting its GPU
    /// times) and starts its command buffer. Returns the slot.
    pub fn begin_frame(&mut self) -> HostResult<usize> {
        let slot = (self.frame % SLOTS as u64) as usize;
        self.retire(slot)?;
        let s = &mut self.slots[slot];
        // SAFETY: the slot's previous submission finished (retire waited on its fence).
        unsafe {
            self.host
                .device
                .reset_command_buffer(s.cmd, vk::CommandBufferResetFlags::empty())
                .map_err(|e| format!("reset: {e:?}"))?;
            self.host.device.reset_fences(&[s.fence]).map_err(|e| format!("reset fence: {e:?}"))?;
        }
        self.host.begin(s.cmd)?;
        Ok(slot)
    }

    pub fn command_buffer(&self, slot: usize) -> vk::CommandBuffer {
        self.slots[slot].cmd
    }

    /// Waits for `slot`'s frame, if any, and hands its ticket back.
    fn retire(&mut self, slot: usize) -> HostResult<()> {
        let s = &mut self.slots[slot];
        if !s.recorded {
            return Ok(());
        }
        // SAFETY: the fence belongs to this device.
        unsafe { self.host.device.wait_for_fences(&[s.fence], true, u64::MAX) }.map_err(|e| format!("wait: {e:?}"))?;
        s.recorded = false;
        let mut sdk: Vec<(String, f64)> = Vec::new();
        let mut sdk_passes: Vec<(String, f64)> = Vec::new();
        if let Some(ticket) = s.ticket.take() {
            let done = self.ctx.mark_gpu_task_completed(ticket).map_err(sdk_err)?;
            // A label's tasks (and a task label's passes) of one frame are summed.
            let sum_into =
                |list: &mut Vec<(String, f64)>, label: String, gpu_ms: f64| match list.iter_mut().find(|(l, _)| *l == label) {
                    Some((_, ms)) => *ms += gpu_ms,
                    None => list.push((label, gpu_ms)),
                };
            for t in &done.timings {
                sum_into(&mut sdk, schedule::timing_label(&done, t), t.gpu_ms);
            }
            for p in &done.pass_timings {
                let Some(task) = done.timings.iter().find(|t| t.task_index == p.task_index) else { continue };
                sum_into(&mut sdk_passes, format!("{}: {}", schedule::timing_label(&done, task), p.pass), p.gpu_ms);
            }
            if s.frame == 0 {
                self.stats.first_frame_bvh_ms = done.gpu_ms(TaskKind::Bvh);
            }
        }
        let passes: Vec<(String, f64)> = s.timer.read(self.host).into_iter().map(|(l, ms)| (l.to_string(), ms)).collect();
        if s.frame > 0 {
            Stats::add(&mut self.stats.sdk, sdk);
            Stats::add(&mut self.stats.sdk_passes, sdk_passes);
            Stats::add(&mut self.stats.passes, passes);
            self.stats.frames += 1;
        }
        Ok(())
    }

    /// The lidar camera at `frame`: it turns a quarter-circle-and-a-bit per frame and nods up
    /// and down, so within a dozen frames every wall, the floor and the sky side have been in
    /// its 110-degree view.
    fn lidar_camera(&self, frame: u64) -> Camera {
        let yaw = frame as f32 * 0.45;
        let pitch = (frame as f32 * 0.9).sin() * 0.5 - 0.25;
        let dir = Vec3::new(yaw.cos() * pitch.cos(), pitch.sin(), yaw.sin() * pitch.cos());
        let eye = self.scene.lidar_eye;
        Camera { fov_y_radians: 110f32.to_radians(), ..Camera::look_at(eye, eye + dir) }
    }

    /// Records the frame into `slot`'s command buffer: `camera` at `time` seconds; `debug` are
    /// the SDK debug visualisations to trace this frame; `view` the mode to put into the view
    /// images (for a window or a capture).
    pub fn record_frame(
        &mut self,
        slot: usize,
        camera: Camera,
        time: f32,
        debug: &[DebugOutput],
        view: Option<Mode>,
    ) -> HostResult<()> {
        let host = self.host;
        let prev = (slot + SLOTS - 1) % SLOTS;
        let frame = self.frame;
        let lidar = self.lidar_camera(frame);
        let (prev_main, prev_lidar) =
            if frame == 0 { (camera, lidar) } else { (self.slots[prev].camera, self.slots[prev].lidar_camera) };
        let cameras = FrameCameras { main: camera, lidar, prev_main, prev_lidar };
        let cmd = self.slots[slot].cmd;
        self.slots[slot].timer.begin(host, cmd);
        // The previous frame's writes (this queue's last submission) before anything of this one.
        host.full_barrier(cmd);

        // --- The engine's scene: animate and skin, then rasterize both views.
        // The rig posed once: its animated instances and its skins.
        let pose = self.scene.rig.pose(time);
        let transforms = self.scene.transforms_posed(time, &pose);
        let mut deformed: Vec<(usize, vk::Buffer)> = self.write_deformed(slot, time)?.into_iter().collect();
        if !self.scene.rig.skinned.is_empty() {
            let s = &self.slots[slot];
            deformed.extend(self.skinning.record(host, cmd, slot, &self.scene, time, &pose, &s.posed)?);
            host.full_barrier(cmd);
            self.slots[slot].timer.mark(host, cmd, "skinning");
        }
        self.record_gbuffers(slot, &transforms, &deformed, &cameras)?;
        self.slots[slot].timer.mark(host, cmd, "raster G-buffers (main + lidar)");

        // --- The SDK: one container for everything of this frame.
        self.schedule_frame(slot, &transforms, &deformed, &cameras, debug, time)?;
        // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
        let ticket = unsafe { self.ctx.build_gpu_task(&mut self.container, cmd) }.map_err(sdk_err)?;
        let s = &mut self.slots[slot];
        s.ticket = Some(ticket);
        s.timer.mark(host, cmd, "SDK (all tasks)");
        host.full_barrier(cmd);

        // --- The engine's lighting and composite.
        self.record_lighting(slot, &cameras)?;
        self.slots[slot].timer.mark(host, cmd, "direct lighting (main + lidar)");
        host.full_barrier(cmd);
        self.record_composite(slot, &camera)?;
        self.slots[slot].timer.mark(host, cmd, "composite");
        if let Some(mode) = view {
            host.full_barrier(cmd);
            self.record_view(cmd, slot, mode)?;
            self.slots[slot].timer.mark(host, cmd, "view");
        }
        let s = &mut self.slots[slot];
        s.camera = camera;
        s.lidar_camera = lidar;
        s.frame = frame;
        self.prev_transforms = transforms;
        self.prev_time = time;
        self.last_slot = slot;
        Ok(())
    }

    /// Writes the deforming mesh's vertices at `time` into `slot`'s vertex buffer, and after
    /// them its vertices of the frame before (for its motion vectors: the CPU writes a slot
    /// while the other slot's frame may still read it, so each slot keeps both): the mesh and
    /// the buffer, where the scene has one.
    fn write_deformed(&self, slot: usize, time: f32) -> HostResult<Option<(usize, vk::Buffer)>> {
        let (Some(d), Some(buffer)) = (&self.scene.deformer, &self.slots[slot].deformed) else { return Ok(None) };
        let before = if self.frame == 0 { time } else { self.prev_time };
        let mut vertices = deformed_vertices(&self.scene, d, time);
        vertices.extend(deformed_vertices(&self.scene, d, before));
        self.host.write_buffer(buffer, bytemuck::cast_slice(&vertices))?;
        Ok(Some((self.scene.scene.instances[d.instance].mesh, buffer.buffer)))
    }

    /// Where each deforming mesh's vertices of the frame before this one (in `slot`) are: the
    /// flag's after its current ones in this slot's buffer, a skinned mesh's in the other
    /// slot's (the skinning pass rewrites it only after the next frame's opening barrier).
    /// Empty for the first frame: nothing moved before it.
    fn prev_deformed(&self, slot: usize) -> Vec<(usize, vk::Buffer, vk::DeviceSize)> {
        if self.frame == 0 {
            return Vec::new();
        }
        let mut out = Vec::new();
        if let (Some(d), Some(buffer)) = (&self.scene.deformer, &self.slots[slot].deformed) {
            let mesh = self.scene.scene.instances[d.instance].mesh;
            let half = self.scene.scene.meshes[mesh].positions.len() as u64 * VERTEX_STRIDE as u64;
            out.push((mesh, buffer.buffer, half));
        }
        let prev = &self.slots[(slot + SLOTS - 1) % SLOTS];
        for (m, b) in self.scene.rig.skinned.iter().zip(&prev.posed) {
            out.push((m.mesh, b.buffer, 0));
        }
        out
    }

    /// The raster G-buffers of the main view and of the lidar view, every instance at
    /// `transforms` (the deforming mesh from its vertex buffer of this frame).
    fn record_gbuffers(
        &mut self,
        slot: usize,
        transforms: &[glam::Affine3A],
        deformed: &[(usize, vk::Buffer)],
        cameras: &FrameCameras,
    ) -> HostResult<()> {
        let scene = &self.scene;
        let before = self.prev_deformed(slot);
        let draws: Vec<Draw> = (0..transforms.len())
            .map(|i| Draw {
                mesh: scene.scene.instances[i].mesh,
                transform: transforms[i],
                prev_transform: self.prev_transforms[i],
                material: scene.materials[i],
                vertex_buffer: deformed.iter().find(|(m, _)| *m == scene.scene.instances[i].mesh).map(|&(_, b)| b),
                prev_vertex_buffer: before.iter().find(|(m, ..)| *m == scene.scene.instances[i].mesh).map(|&(_, b, o)| (b, o)),
                textures: scene.material_textures.get(i).copied().unwrap_or_default(),
                alpha_cutoff: scene.cutouts.get(scene.scene.instances[i].mesh).copied().flatten().map_or(0.0, |c| c.cutoff),
            })
            .collect();
        let (host, s) = (self.host, &self.slots[slot]);
        let (main, lidar) = (&cameras.main, &cameras.lidar);
        self.gbuffer.record(host, s.cmd, 2 * slot, &s.main.targets, &self.meshes, &draws, main, &cameras.prev_main)?;
        // The lidar view has no use for motion: its previous camera is its current one.
        self.gbuffer.record(host, s.cmd, 2 * slot + 1, &s.lidar.targets, &self.meshes, &draws, lidar, lidar)
    }

    /// The engine's deferred direct lighting of both views, from the SDK's shadows (the main
    /// view's denoised, the lidar view's raw traces).
    fn record_lighting(&mut self, slot: usize, cameras: &FrameCameras) -> HostResult<()> {
        let (host, lights, wk, s) = (self.host, self.scene.lights, &self.work, &self.slots[slot]);
        let file = &self.scene.file_lights;
        let main_vis = Visibility {
            sun: &wk.sun,
            point: &wk.point,
            file_lights: wk.lights.as_ref().map(|l| &l.denoised),
            layout: GENERAL,
            raw_trace: false,
        };
        self.lighting.record(host, s.cmd, 2 * slot, &s.main.targets, &cameras.main, &lights, file, main_vis, &s.main.lit)?;
        if let Some(many) = &mut self.many {
            host.full_barrier(s.cmd);
            many.compose(host, s.cmd, slot, &s.main.targets, &s.main.lit)?;
        }
        let lidar_vis = Visibility {
            sun: &wk.lidar_sun,
            point: &wk.lidar_point,
            file_lights: wk.lights.as_ref().map(|l| &l.lidar.packed),
            layout: GENERAL,
            raw_trace: true,
        };
        let lidar_targets = &s.lidar.targets;
        self.lighting.record(host, s.cmd, 2 * slot + 1, lidar_targets, &cameras.lidar, &lights, file, lidar_vis, &s.lidar.lit)
    }

    /// The sun and the point light as the SDK's shadow and relight tasks take them: their
    /// intensities are the lighting pass's (sun: irradiance at normal incidence; point:
    /// irradiance x d²), so relit cache samples match the lit image the cameras inject.
    fn lights(&self) -> (LightInfo, LightInfo) {
        let l = &self.scene.lights;
        let sun = LightInfo {
            direction: -l.sun_direction,
            angular_extent: self.scene.sun_angular_extent,
            intensity: l.sun_intensity,
            ..Default::default()
        };
        let point = LightInfo {
            light_type: LightType::Point,
            position: l.point_position,
            radius: self.scene.point_radius,
            intensity: l.point_intensity,
            ..Default::default()
        };
        (sun, point)
    }

    /// Every light that shines, as the SDK's relighting and hit lighting take them: the sun
    /// and the point light where they are on, and the file's lights.
    fn shining_lights(&self) -> Vec<LightInfo> {
        let (sun, point) = self.lights();
        let file = self.scene.file_lights.iter().copied();
        [sun, point].into_iter().filter(|l| l.intensity > 0.0).chain(file).take(MAX_SHADOW_LIGHTS).collect()
    }

    fn record_composite(&mut self, slot: usize, camera: &Camera) -> HostResult<()> {
        let (w, h) = (self.settings.width, self.settings.height);
        let t = &self.slots[slot].main.targets;
        let clip_to_world = (camera.view_to_clip(w as f32 / h as f32) * camera.world_to_view()).inverse();
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        #[repr(C)]
        struct CompositeGpu {
            clip_to_world: [f32; 16],
            eye: [f32; 4],
            sky: [f32; 4],
            terms: [f32; 4],
        }
        let sky = self.scene.sky;
        let constants = CompositeGpu {
            clip_to_world: clip_to_world.to_cols_array(),
            eye: camera.eye.extend(1.0).to_array(),
            sky: [sky[0], sky[1], sky[2], w as f32],
            terms: [1.0, 1.0, 1.0, h as f32],
        };
        let wk = &self.work;
        let read = raster::READ;
        let sampled = [
            (&t.depth, read),
            (&t.normal_roughness, read),
            (&t.albedo_metalness, read),
            (&self.slots[slot].main.lit, GENERAL),
            (&wk.diffuse, GENERAL),
            (&wk.ao, GENERAL),
            (&wk.specular, GENERAL),
        ];
        self.composite.dispatch(
            self.host,
            self.slots[slot].cmd,
            slot,
            &sampled,
            &[&wk.composite],
            bytemuck::bytes_of(&constants),
            w,
            h,
        )
    }

    fn record_view(&mut self, cmd: vk::CommandBuffer, slot: usize, mode: Mode) -> HostResult<()> {
        let (w, h) = (self.settings.width, self.settings.height);
        let m = mode.mapping();
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        #[repr(C)]
        struct ViewGpu {
            swizzle: [f32; 16],
            bias: [f32; 4],
            params: [f32; 4],
        }
        let constants = ViewGpu {
            swizzle: m.swizzle.to_cols_array(),
            bias: m.bias.to_array(),
            // Exposure is for radiance: masks, normals and debug colours are shown as they are.
            params: [
                if m.tone_map { self.settings.exposure } else { 1.0 },
                if m.tone_map { 1.0 } else { 0.0 },
                w as f32,
                h as f32,
            ],
        };
        let sampled = [source(&self.work, &self.slots[slot], self.many.as_ref(), mode)];
        self.view.dispatch(
            self.host,
            cmd,
            slot,
            &sampled,
            &[&self.work.linear, &self.work.display],
            bytemuck::bytes_of(&constants),
            w,
            h,
        )
    }

    /// Ends and submits `slot`'s frame with `waits` and `signals` (a window's swapchain
    /// semaphores), fenced by the slot's fence.
    pub fn submit_frame(
        &mut self,
        slot: usize,
        waits: &[(vk::Semaphore, vk::PipelineStageFlags)],
        signals: &[vk::Semaphore],
    ) -> HostResult<()> {
        let s = &mut self.slots[slot];
        let d = &self.host.device;
        let cmds = [s.cmd];
        let (wait_sems, wait_stages): (Vec<_>, Vec<_>) = waits.iter().copied().unzip();
        let mut info = vk::SubmitInfo::default().command_buffers(&cmds);
        // Empty lists stay null (an empty slice would still set the pointers).
        if !waits.is_empty() {
            info = info.wait_semaphores(&wait_sems).wait_dst_stage_mask(&wait_stages);
        }
        if !signals.is_empty() {
            info = info.signal_semaphores(signals);
        }
        // SAFETY: the command buffer was recorded by `record_frame`; the fence was reset.
        unsafe {
            d.end_command_buffer(s.cmd).map_err(|e| format!("end: {e:?}"))?;
            d.queue_submit(self.host.queue, &[info], s.fence).map_err(|e| format!("submit: {e:?}"))?;
        }
        s.recorded = true;
        self.frame += 1;
        Ok(())
    }

    /// Begin, record (with `view`) and submit one frame with no window.
    pub fn render(&mut self, camera: Camera, time: f32, debug: &[DebugOutput], view: Option<Mode>) -> HostResult<()> {
        let slot = self.begin_frame()?;
        self.record_frame(slot, camera, time, debug, view)?;
        self.submit_frame(slot, &[], &[])
    }

    /// Waits for every frame in flight and hands their tickets back.
    pub fn finish(&mut self) -> HostResult<()> {
        for slot in 0..SLOTS {
            self.retire(slot)?;
        }
        Ok(())
    }

    /// After `finish`: skinned mesh `mesh`'s vertices as the last frame's skinning pass wrote
    /// them (None: the mesh is not skinned).
    pub fn posed_vertices(&self, mesh: usize) -> HostResult<Option<Vec<Vertex>>> {
        let Some(k) = self.scene.rig.skinned.iter().position(|m| m.mesh == mesh) else { return Ok(None) };
        let bytes = self.skinning.posed_bytes(mesh).ok_or("not skinned")?;
        let host = self.host;
        let readback = host.create_buffer(
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT | vk::MemoryPropertyFlags::HOST_CACHED,
        )?;
        let source = self.slots[self.last_slot].posed[k].buffer;
        let copied = host.run(|cmd| {
            host.full_barrier(cmd);
            // SAFETY: cmd is recording; both buffers hold `bytes`.
            unsafe {
                host.device.cmd_copy_buffer(
                    cmd,
                    source,
                    readback.buffer,
                    &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes }],
                )
            };
            host.full_barrier(cmd);
        });
        let vertices = copied.map(|()| {
            let bytes = readback.mapped_bytes().unwrap_or_default();
            bytes
                .chunks_exact(VERTEX_STRIDE as usize)
                .map(|v| std::array::from_fn(|i| f32::from_le_bytes([v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3]])))
                .collect()
        });
        host.destroy_buffer(readback);
        vertices.map(Some)
    }

    /// After `finish`: `mode` of the last frame as linear RGBA (EXR) and sRGB RGBA8 (PNG).
    pub fn capture(&mut self, mode: Mode) -> HostResult<(Vec<[f32; 4]>, Vec<u8>)> {
        let slot = self.last_slot;
        let host = self.host;
        let cmd = host.allocate_command_buffer()?;
        host.begin(cmd)?;
        host.full_barrier(cmd);
        self.record_view(cmd, slot, mode)?;
        host.full_barrier(cmd);
        let fence = host.submit(cmd)?;
        host.wait(fence)?;
        let linear = bytemuck::cast_slice(&host.read_image(&self.work.linear, GENERAL)?).to_vec();
        let display = host.read_image(&self.work.display, GENERAL)?;
        Ok((linear, display))
    }

    /// Sets `settings.exposure` from the last frame's composite so its log-average luminance
    /// maps to AUTO_EXPOSURE_KEY (Reinhard's key value, 0.18: mid-grey) before the tone curve:
    /// a scene lit 10x brighter gets a tenth of the exposure instead of clipping its whites.
    /// Returns the exposure (clamped to 1/32..32; 1 for a black frame).
    pub fn auto_expose(&mut self) -> HostResult<f32> {
        let (linear, _) = self.capture(Mode::Composite)?;
        let logs: Vec<f64> = linear
            .iter()
            .map(|t| 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2])
            .filter(|l| l.is_finite() && *l > 0.0)
            .map(|l| (l as f64 + 1e-4).ln())
            .collect();
        let exposure = if logs.is_empty() {
            1.0
        } else {
            let mean = (logs.iter().sum::<f64>() / logs.len() as f64).exp();
            (AUTO_EXPOSURE_KEY / mean).clamp(1.0 / 32.0, 32.0) as f32
        };
        self.settings.exposure = exposure;
        Ok(exposure)
    }

    /// The display image (RGBA8, GENERAL) the view pass writes: a window blits it.
    pub fn display_image(&self) -> &HostImage {
        &self.work.display
    }

    /// Bytes of every instance's direct-lighting cache.
    pub fn cache_bytes(&self) -> u64 {
        self.instances.iter().map(|h| self.ctx.instance_cache_bytes(*h).unwrap_or(0)).sum()
    }

    pub fn destroy(mut self) -> HostResult<()> {
        self.finish()?;
        let host = self.host;
        let d = &self.denoisers;
        for d in [Some(d.sun), Some(d.point), Some(d.ao), Some(d.radiance), d.lights].into_iter().flatten() {
            self.ctx.destroy_denoising_context(d).map_err(sdk_err)?;
        }
        if let Some(many) = self.many.take() {
            many.destroy(host, &self.ctx)?;
        }
        drop(self.container);
        drop(self.ctx);
        for s in self.slots {
            s.destroy(host);
        }
        self.work.destroy(host);
        self.meshes.destroy(host);
        self.skinning.destroy(host);
        self.gbuffer.destroy(host);
        self.lighting.destroy(host);
        self.composite.destroy(host);
        self.view.destroy(host);
        Ok(())
    }
}

/// The deforming mesh's vertices at `time`: its positions and their normals, recomputed (the
/// cloth's shading follows its waves).
fn deformed_vertices(scene: &SampleScene, d: &crate::scene::Deformer, time: f32) -> Vec<Vertex> {
    let positions = d.positions(time);
    let mesh = scene.scene.instances[d.instance].mesh;
    let normals = crate::scene::vertex_normals(&positions, &scene.scene.meshes[mesh].indices);
    // The rest pose's tangents would tilt with the waves: the cloth's normal maps (it has none)
    // would take their frame from screen derivatives.
    let attributes = VertexAttributes { normals: &normals, tangents: &[], ..scene.vertex_attributes(mesh) };
    raster::interleave(&positions, attributes)
}
