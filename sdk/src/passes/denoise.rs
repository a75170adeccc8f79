//! The denoisers' GPU side: the history a denoising context owns, and the compute passes that
//! filter (what they do and why: `types::denoise`). Every pass shares one push-descriptor
//! layout (shaders/include/denoise.glsl); a pass's step size travels as a push constant.
//!
//! Radiance: temporal (with the history clamp) → rotated-disk blur × `spatial_passes` (the
//! first keeps the histories, the last writes the output). AO while the scene changes: a
//! moving-object search first, and a temporal pass that restarts the pixels the moving objects
//! reach.
//! Shadows: prep → penumbra blur → temporal (writes the output).
use super::constants::LightGpu;
use super::constants::TraceCommonGpu;
use super::denoise_guide::{Guide, GuideKey, ViewInputs};
use super::descriptors::{self, Slot};
use super::{PassTask, Passes, Recording, World};
use crate::error::{Error, Result};
use crate::gpu::memory::{Image, Memory, MemoryKind, COLOR_RANGE};
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::gpu::sync;
use crate::shaders;
use crate::types::{Camera, ImageInput};
use crate::types::{DenoiseJob, DenoisingCommon, DenoisingContextInput, DenoisingMethod, MotionType, SignalType, TaskKind};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `DenoiseConstants` in shaders/include/denoise.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct DenoiseConstantsGpu {
    common: TraceCommonGpu,
    prev_world_to_clip: [f32; 16],
    prev_clip_to_world: [f32; 16],
    eye: [f32; 4],
    /// The previous camera position; w: `DenoiserSettings::fresh_history_taps`.
    prev_eye: [f32; 4],
    flags: [u32; 4],
    kinds: [u32; 4],
    motion_scale: [f32; 4],
    jitter_delta: [f32; 4],
    history: [f32; 4],
    stops: [f32; 4],
    /// The viewport the history was made in (x, y, width, height): with dynamic resolution it
    /// differs from this frame's, and reprojection lands in it.
    prev_viewport: [f32; 4],
    light: LightGpu,
}

/// The spatial passes' names (`PassTiming::pass`); as many as `DenoiserSettings::spatial_passes`
/// allows.
const BLUR_PASS_NAMES: [&str; 6] = ["blur_1", "blur_2", "blur_3", "blur_4", "blur_5", "blur_6"];

/// Smallest blur radius scale, reached once a pixel has a quarter of the longest history.
const MIN_RADIUS_SCALE: f32 = 0.25;

const HISTORY_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// The shadow history: visibility and history length as two halves (packHalf2x16).
const SHADOW_HISTORY_FORMAT: vk::Format = vk::Format::R32_UINT;
/// The shadow passes' tile map: one texel per 8x8 tile (R32_UINT: storage use needs no
/// extended-format feature).
const TILE_FORMAT: vk::Format = vk::Format::R32_UINT;
/// Pixels per tile side (the passes' workgroup size).
const TILE: u32 = 8;
/// Pixels per side of the tiles AO's moving objects stamp (HRT_MOVING_STAMP_TILE).
const STAMP_TILE: u32 = 32;
/// For how many recordings after the scene last changed the AO denoiser looks for moving
/// objects (`DenoiserSettings::moving_object_reach`): an engine may record its BVH work and
/// its frame in separate command buffers.
const MOVING_RECORDINGS: u64 = 4;

/// What a denoising context keeps between frames: single history images, overwritten in place
/// once the frame's first pass has read them (radiance: slow and fast RGBA16F per signal, 16
/// bytes a pixel; AO: both in one RGBA16F, 8; shadows: one image of two halves, 4, as
/// SIGMA's); the previous camera. The G-buffer its passes test against is
/// its view's guide (`denoise_guide`); the passes' intermediates are not kept: every context
/// shares one `TempPool`.
pub(crate) struct DenoiserState {
    pub input: DenoisingContextInput,
    /// Its guide: its view's, or its own.
    pub guide: GuideKey,
    /// The guide frame its history was written against: history continues only from the
    /// guide's previous frame.
    guide_frame: u64,
    /// Per radiance signal: slow history (RGB + 2nd moment).
    history: Vec<Image>,
    /// Per radiance signal but AO: fast history (RGB + history length). AO keeps (slow, moment,
    /// fast, length) in its `history` image.
    fast: Vec<Image>,
    /// Shadows: the one history image (visibility + length), overwritten in place each frame
    /// (the prep pass copies what the later passes read of it into the intermediates).
    shadow_history: Option<Image>,
    /// AO: the 32x32 tiles a moving object's occlusion reaches, stamped with the frame
    /// (u_motion_tiles in shaders/include/denoise.glsl).
    motion_tiles: Option<Image>,
    initialized: bool,
    previous_camera: Option<Camera>,
    previous_jitter: [f32; 2],
    /// The viewport of the last task: another one invalidates the history.
    previous_viewport: [u32; 4],
}

fn is_shadow(signal: SignalType) -> bool {
    matches!(signal, SignalType::Shadow | SignalType::MultiShadow)
}

impl DenoiserState {
    /// The history of a context for `input`, reading the guide `guide`.
    pub fn new(memory: &Memory, input: &DenoisingContextInput, guide: GuideKey) -> Result<DenoiserState> {
        let shadow = is_shadow(input.signal);
        let signals = if shadow { 0 } else { signal_count(input.signal) };
        let ao = input.signal == SignalType::DiffuseOcclusion;
        // AO keeps its fast history in its history image's spare channels.
        let fast_signals = if ao { 0 } else { signals };
        // Radiance: the slow histories, then the fast ones, of HISTORY_FORMAT. Shadows: one.
        // AO: its moving-object stamps, one texel per STAMP_TILE pixels.
        let (w, h) = (input.max_width, input.max_height);
        let specs = std::iter::repeat_n(("denoiser", HISTORY_FORMAT, w, h), signals + fast_signals)
            .chain(std::iter::repeat_n(("denoiser", SHADOW_HISTORY_FORMAT, w, h), shadow as usize))
            .chain(std::iter::repeat_n(
                ("denoiser motion tiles", TILE_FORMAT, w.div_ceil(STAMP_TILE), h.div_ceil(STAMP_TILE)),
                ao as usize,
            ));
        let mut images = create_all(memory, specs)?.into_iter();
        let history = images.by_ref().take(signals).collect();
        let fast = images.by_ref().take(fast_signals).collect();
        let shadow_history = if shadow { images.next() } else { None };
        let motion_tiles = images.next();
        Ok(DenoiserState {
            input: *input,
            guide,
            guide_frame: 0,
            history,
            fast,
            shadow_history,
            motion_tiles,
            initialized: false,
            previous_camera: None,
            previous_jitter: [0.0; 2],
            previous_viewport: [0; 4],
        })
    }

    /// The history bookkeeping a task advances, for the state digest.
    #[cfg(feature = "fault-injection")]
    pub fn digest(&self) -> String {
        format!(
            "initialized {} guide {:?} frame {} camera {:?} viewport {:?}",
            self.initialized, self.guide, self.guide_frame, self.previous_camera, self.previous_viewport
        )
    }

    /// Whether a task starts over: asked to, nothing recorded yet, spatial only, or a history
    /// its view's guide no longer describes (the context skipped the view's previous frame).
    /// A viewport that changed (dynamic resolution) keeps the history: reprojection maps this
    /// frame's pixels into the previous viewport, where the history lies.
    fn must_reset(&self, c: &DenoisingCommon, guide_frame: u64) -> bool {
        c.reset_history
            || !self.initialized
            || self.guide_frame + 1 != guide_frame
            || self.input.method == DenoisingMethod::SpatialOnly
    }

    /// After a task: its history now continues from `guide_frame`, `c`'s camera and `viewport`.
    fn recorded(&mut self, guide_frame: u64, c: &DenoisingCommon, viewport: [u32; 4]) {
        self.initialized = true;
        self.guide_frame = guide_frame;
        (self.previous_camera, self.previous_jitter, self.previous_viewport) = (Some(c.camera), c.camera_jitter, viewport);
    }

    /// Every image, for (deferred) destruction.
    pub fn into_images(self) -> Vec<Image> {
        let DenoiserState { history, fast, shadow_history, motion_tiles, .. } = self;
        history.into_iter().chain(fast).chain(shadow_history).chain(motion_tiles).collect()
    }

    fn images(&self) -> impl Iterator<Item = &Image> {
        self.history.iter().chain(&self.fast).chain(&self.shadow_history).chain(&self.motion_tiles)
    }
}

/// One image per format, all or none (a failure frees the ones already made).
/// Creates the images `specs` names (debug name, format, width, height), all or none.
fn create_all(memory: &Memory, specs: impl Iterator<Item = (&'static str, vk::Format, u32, u32)>) -> Result<Vec<Image>> {
    let mut made = Vec::new();
    for (name, format, width, height) in specs {
        match memory.create_image(name, format, width, height, MemoryKind::Denoiser) {
            Ok(image) => made.push(image),
            Err(e) => {
                for image in made {
                    memory.destroy_image(image);
                }
                return Err(e);
            }
        }
    }
    Ok(made)
}

fn signal_count(signal: SignalType) -> usize {
    if signal == SignalType::SpecularAndDiffuse {
        2
    } else {
        1
    }
}

/// The passes' intermediate images, shared by every denoising context of an `ExecuteContext`:
/// a task writes them before it reads them and leaves nothing in them for the next (tasks are
/// recorded one after another, with barriers between their passes), so one set the size of
/// the largest context serves all. A 1080p specular + diffuse context kept four of these
/// (33 MB each); the sample's four contexts kept ten.
#[derive(Default)]
pub(crate) struct TempPool {
    /// Per signal (two for specular + diffuse), a ping-pong pair.
    pairs: Vec<[Image; 2]>,
    /// The shadow passes' tile map (see shaders/include/denoise.glsl); made with the pairs.
    tiles: Option<Image>,
    width: u32,
    height: u32,
    initialized: bool,
}

impl TempPool {
    /// Grows the pool to serve `input` too. On success returns the images it replaced (still
    /// possibly in use by issued tickets: the caller retires them); on failure the pool is
    /// unchanged.
    pub fn ensure(&mut self, memory: &Memory, input: &DenoisingContextInput) -> Result<Vec<Image>> {
        let signals = signal_count(input.signal).max(self.pairs.len());
        let (width, height) = (input.max_width.max(self.width), input.max_height.max(self.height));
        if signals == self.pairs.len() && width == self.width && height == self.height {
            return Ok(Vec::new());
        }
        let specs = std::iter::repeat_n(("denoiser intermediate", HISTORY_FORMAT, width, height), 2 * signals)
            .chain(std::iter::once(("denoiser tiles", TILE_FORMAT, width.div_ceil(TILE), height.div_ceil(TILE))));
        let mut images = create_all(memory, specs)?;
        let tiles = images.pop();
        let mut images = images.drain(..);
        let pairs = (0..signals).map(|_| [images.next().expect("counted"), images.next().expect("counted")]).collect();
        let old = std::mem::replace(&mut self.pairs, pairs);
        let old_tiles = std::mem::replace(&mut self.tiles, tiles);
        (self.width, self.height, self.initialized) = (width, height, false);
        Ok(old.into_iter().flatten().chain(old_tiles).collect())
    }

    pub fn into_images(self) -> Vec<Image> {
        self.pairs.into_iter().flatten().chain(self.tiles).collect()
    }

    fn images(&self) -> impl Iterator<Item = &Image> {
        self.pairs.iter().flatten().chain(&self.tiles)
    }
}

/// The radiance passes of one signal type: their shaders specialized to its signals (count and
/// kinds), so a pipeline holds only the code, and the registers, its signals need.
struct RadiancePipelines {
    temporal: vk::Pipeline,
    /// AO's temporal pass that also restarts pixels near moving objects (HRT_MOVING_OBJECTS),
    /// used while the scene changes; the plain one the rest of the time.
    temporal_moving: Option<vk::Pipeline>,
    blur: vk::Pipeline,
    /// The first blur pass with `DenoiserSettings::fresh_history_taps` (HRT_FRESH_TAPS), for
    /// the signal types with diffuse: the taps' loop costs the passes without it.
    blur_fresh: Option<vk::Pipeline>,
}

impl RadiancePipelines {
    /// The first blur pass's pipeline for `fresh_history_taps` taps.
    fn first_blur(&self, fresh_history_taps: u32) -> vk::Pipeline {
        match self.blur_fresh {
            Some(fresh) if fresh_history_taps > 0 => fresh,
            _ => self.blur,
        }
    }
}

/// The radiance signal types, in `RadiancePipelines` order, with their specialization
/// constants (HRT_SIGNALS, HRT_KIND0, HRT_KIND1 in shaders/include/denoise.glsl).
const RADIANCE_SIGNALS: [(SignalType, [u32; 3]); 4] = [
    (SignalType::SpecularAndDiffuse, [2, 1, 0]),
    (SignalType::Specular, [1, 1, 1]),
    (SignalType::Diffuse, [1, 0, 0]),
    (SignalType::DiffuseOcclusion, [1, 2, 2]),
];

pub(crate) struct DenoisePass {
    layout: vk::PipelineLayout,
    radiance: Vec<RadiancePipelines>,
    shadow_prep: vk::Pipeline,
    shadow_blur: vk::Pipeline,
    /// The shadow blur without its edge-aligned kernel (HRT_EDGE_BLUR 0), for still frames
    /// (`needs_edge_blur`): the kernel's code, merely present, slows the pass.
    shadow_blur_still: vk::Pipeline,
    shadow_temporal: vk::Pipeline,
    /// AO's moving-object search (shaders/denoise_moving.comp).
    moving: vk::Pipeline,
}

/// Binding order of shaders/include/denoise.glsl: 6 sampled (depth, normals, roughness,
/// motion, input 0/1), 16 storage, 1 uniform buffer, 1 sampled (the input mask), 3 storage
/// (the tile map, the shadow history, the moving-object tiles).
const SAMPLED_BINDINGS: usize = 6;
const STORAGE_BINDINGS: usize = 16;

impl DenoisePass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<DenoisePass> {
        let mut bindings: Vec<Binding> = (0..SAMPLED_BINDINGS)
            .map(|_| Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) })
            .collect();
        bindings.extend((0..STORAGE_BINDINGS).map(|_| Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None }));
        bindings.push(Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None });
        bindings.push(Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) });
        bindings.extend((0..3).map(|_| Binding { ty: vk::DescriptorType::STORAGE_IMAGE, sampler: None }));
        let set_layout = b.set_layout(&bindings, vk::ShaderStageFlags::COMPUTE)?;
        let layout = b.layout(Some(set_layout), 16, vk::ShaderStageFlags::COMPUTE)?;
        let mut radiance = Vec::with_capacity(RADIANCE_SIGNALS.len());
        for (signal, constants) in RADIANCE_SIGNALS {
            let moving = [constants[0], constants[1], constants[2], 1];
            let fresh = [constants[0], constants[1], constants[2], 0, 1];
            let has_diffuse = matches!(signal, SignalType::SpecularAndDiffuse | SignalType::Diffuse);
            radiance.push(RadiancePipelines {
                temporal: b.compute_specialized(layout, shaders::DENOISE_TEMPORAL_COMP, &constants)?,
                temporal_moving: if signal == SignalType::DiffuseOcclusion {
                    Some(b.compute_specialized(layout, shaders::DENOISE_TEMPORAL_COMP, &moving)?)
                } else {
                    None
                },
                blur: b.compute_specialized(layout, shaders::DENOISE_BLUR_COMP, &constants)?,
                blur_fresh: if has_diffuse {
                    Some(b.compute_specialized(layout, shaders::DENOISE_BLUR_COMP, &fresh)?)
                } else {
                    None
                },
            });
        }
        Ok(DenoisePass {
            layout,
            radiance,
            shadow_prep: b.compute(layout, shaders::DENOISE_SHADOW_PREP_COMP)?,
            shadow_blur: b.compute(layout, shaders::DENOISE_SHADOW_BLUR_COMP)?,
            // Constants 0-4 at the shader's defaults (the shadow passes ignore them).
            shadow_blur_still: b.compute_specialized(layout, shaders::DENOISE_SHADOW_BLUR_COMP, &[2, 1, 0, 0, 0, 0])?,
            shadow_temporal: b.compute(layout, shaders::DENOISE_SHADOW_TEMPORAL_COMP)?,
            moving: b.compute(layout, shaders::DENOISE_MOVING_COMP)?,
        })
    }

    /// The shadow blur's pipeline, with or without its edge-aligned kernel.
    fn shadow_blur_for(&self, edge: bool) -> vk::Pipeline {
        if edge {
            self.shadow_blur
        } else {
            self.shadow_blur_still
        }
    }

    /// Records one denoise task against its context's state and guide (and advances both),
    /// with the shared intermediates of `temps`; `serial` is the recording's, `scene_changed`
    /// the serial of the last one that changed the scene (`Scene::changed_at`).
    pub fn record(
        &self,
        r: &mut Recording<'_>,
        (state, guide): (&mut DenoiserState, &mut Guide),
        temps: &mut TempPool,
        job: &DenoiseJob,
        (serial, scene_changed): (u64, u64),
    ) {
        // The pool grows with every context made (`ExecuteContext::create_denoising_context`),
        // so it always serves a live context's task; recording nothing beats an out-of-bounds
        // index should that ever not hold.
        let Some(tiles) = temps.tiles.as_ref().map(Image::input) else {
            log::error!("the denoisers' shared intermediates do not exist: task skipped");
            return;
        };
        if temps.pairs.len() < job.count {
            log::error!("the denoisers' shared intermediates do not serve this task: skipped");
            return;
        }
        let stage = vk::PipelineStageFlags2::COMPUTE_SHADER;
        initialize_images(r, state, guide, temps);
        let (guide_frame, [guide_prev, guide_cur]) = guide.begin_task(serial, matches!(state.guide, GuideKey::View(_)));
        // History written by earlier command buffers: the recording's hazard tracker starts
        // with their writes pending (Hazards::after_earlier_submissions).

        let c = &job.common;
        let extent = (c.viewport.width, c.viewport.height);
        let viewport = [c.viewport.x, c.viewport.y, c.viewport.width, c.viewport.height];
        let reset = state.must_reset(c, guide_frame);
        let previous = c.previous_camera.or(state.previous_camera).unwrap_or(c.camera);
        let previous_viewport = if reset { viewport } else { state.previous_viewport };
        let constants = constants(job, &previous, state.previous_jitter, previous_viewport, r.seed, reset);
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);

        let shadow = is_shadow(job.signal);
        // The pool's first pair, and its second for a two-signal task.
        let second = job.count.min(temps.pairs.len()) - 1;
        let temp_pair = |k: usize| -> [ImageInput; 2] { [temps.pairs[0][k].input(), temps.pairs[second][k].input()] };
        let temps_in = [temp_pair(0), temp_pair(1)];
        // Per signal (a one-signal task binds its image twice). Shadows keep no radiance
        // histories: those bindings get stand-ins of the declared format (never read).
        let per_signal = |v: &[Image]| -> [ImageInput; 2] {
            match v.first() {
                Some(first) if !shadow => [first.input(), v[v.len().min(2) - 1].input()],
                _ => temps_in[0],
            }
        };
        // The kept histories are single: read by the temporal pass, overwritten in place by the
        // first blur pass (shaders/include/denoise.glsl). This frame's fast history passes
        // between the two through the second image of each signal's pair, which the first blur
        // pass reads at each pixel before it writes its output there.
        let hist_prev = per_signal(&state.history);
        let hist_cur = hist_prev;
        let fast_prev = per_signal(&state.fast);
        let fast_cur = temps_in[1];
        let shadow_history = state.shadow_history.as_ref().map_or(tiles, Image::input);
        let motion_tiles = state.motion_tiles.as_ref().map_or(tiles, Image::input);
        let gb_prev = guide.images()[guide_prev].input();
        let gb_cur = guide.images()[guide_cur].input();
        let stand_in = temps_in[0][0];
        let roughness = descriptors::optional_or(&c.roughness.image, &stand_in);
        let motion = descriptors::optional_or(&c.motion.image, &stand_in);
        let mask = descriptors::optional_or(&c.input_mask, &stand_in);

        // Workgroups: one invocation per pixel, or per 4x4 block (AO's moving-object search).
        let pixel_groups = (extent.0.div_ceil(TILE), extent.1.div_ceil(TILE));
        let block_groups = (extent.0.div_ceil(4 * TILE), extent.1.div_ceil(4 * TILE));
        let dispatch = |r: &mut Recording<'_>,
                        name: &'static str,
                        pipeline: vk::Pipeline,
                        (src, dst): (usize, usize),
                        push: [u32; 4],
                        groups: (u32, u32)| {
            r.hazards.read_write(r.cmd, sync::shader_read(stage), sync::shader_write(stage));
            let span = r.begin_pass(name);
            let slots = [
                Slot::Sampled(&c.depth.image),
                Slot::Sampled(&c.normals.image),
                Slot::Sampled(roughness),
                Slot::Sampled(motion),
                Slot::Sampled(&job.inputs[0]),
                Slot::Sampled(&job.inputs[1]),
                Slot::Storage(&job.outputs[0]),
                Slot::Storage(&job.outputs[1]),
                Slot::Storage(&gb_prev),
                Slot::Storage(&gb_cur),
                Slot::Storage(&hist_prev[0]),
                Slot::Storage(&hist_prev[1]),
                Slot::Storage(&hist_cur[0]),
                Slot::Storage(&hist_cur[1]),
                Slot::Storage(&fast_prev[0]),
                Slot::Storage(&fast_prev[1]),
                Slot::Storage(&fast_cur[0]),
                Slot::Storage(&fast_cur[1]),
                Slot::Storage(&temps_in[src][0]),
                Slot::Storage(&temps_in[src][1]),
                Slot::Storage(&temps_in[dst][0]),
                Slot::Storage(&temps_in[dst][1]),
                Slot::Uniform(ubo),
                Slot::Sampled(mask),
                Slot::Storage(&tiles),
                Slot::Storage(&shadow_history),
                Slot::Storage(&motion_tiles),
            ];
            let bind = vk::PipelineBindPoint::COMPUTE;
            // The slots match the set layout; inputs were validated when scheduled.
            r.cmd.bind_pipeline(bind, pipeline);
            descriptors::push(r.cmd, bind, self.layout, &slots);
            r.cmd.push_constants(self.layout, vk::ShaderStageFlags::COMPUTE, bytemuck::bytes_of(&push));
            r.cmd.dispatch(groups.0, groups.1, 1);
            r.end_pass(span);
        };

        if shadow {
            dispatch(r, "shadow_prep", self.shadow_prep, (1, 0), [0; 4], pixel_groups);
            let blur = self.shadow_blur_for(needs_edge_blur(state, c, &previous, reset, (serial, scene_changed)));
            dispatch(r, "shadow_blur", blur, (0, 1), [0; 4], pixel_groups);
            dispatch(r, "shadow_temporal", self.shadow_temporal, (1, 0), [0; 4], pixel_groups);
        } else {
            // Every radiance signal type has its pipelines (RADIANCE_SIGNALS).
            let Some(k) = RADIANCE_SIGNALS.iter().position(|(s, _)| *s == job.signal) else { return };
            let p = &self.radiance[k];
            let passes = c.settings.spatial_passes;
            // The tiles' stamp: the guide frame (never 0, which cleared tiles hold).
            let stamp = (guide_frame as u32).max(1);
            let temporal = match p.temporal_moving {
                Some(restarting) if looks_for_moving_objects(state, c, reset, (serial, scene_changed)) => {
                    let reach = c.settings.moving_object_reach;
                    let push = [stamp, 0, ((previous == c.camera) as u32) << 2, reach.to_bits()];
                    dispatch(r, "moving_objects", self.moving, (1, 0), push, block_groups);
                    restarting
                }
                _ => p.temporal,
            };
            dispatch(r, "temporal", temporal, (1, 0), [stamp, 0, 0, 0], pixel_groups);
            // The first blur pass keeps the histories: without spatial passes it runs once,
            // filtering nothing, and writes the output.
            if passes == 0 {
                dispatch(r, "keep", p.blur, (0, 1), [0, 1, 1, 0], pixel_groups);
            }
            let first_blur = p.first_blur(c.settings.fresh_history_taps);
            for (i, name) in (0..passes).zip(BLUR_PASS_NAMES) {
                let src = i as usize % 2;
                let push = [i, (i + 1 == passes) as u32, 0, 0];
                dispatch(r, name, if i == 0 { first_blur } else { p.blur }, (src, 1 - src), push, pixel_groups);
            }
        }
        temps.initialized = true;
        state.recorded(guide_frame, c, viewport);
    }
}

/// Whether an AO task looks for moving objects (and restarts the pixels they reach): while the
/// scene changes (`scene_changed_recently`), with a reach (DenoiserSettings::moving_object_reach),
/// and with a history to restart.
fn looks_for_moving_objects(
    state: &DenoiserState,
    c: &DenoisingCommon,
    reset: bool,
    (serial, scene_changed): (u64, u64),
) -> bool {
    state.motion_tiles.is_some()
        && c.settings.moving_object_reach > 0.0
        && !reset
        && scene_changed_recently((serial, scene_changed))
}

/// Whether the scene changed within MOVING_RECORDINGS recordings of `serial` (`scene_changed`:
/// the last recording that changed it, 0 for none).
fn scene_changed_recently((serial, scene_changed): (u64, u64)) -> bool {
    scene_changed != 0 && serial.saturating_sub(scene_changed) <= MOVING_RECORDINGS
}

/// Whether the shadow blur needs its edge-aligned kernel this frame: it serves pixels with a
/// short history, which a still frame does not make — one whose camera (matrices, jitter and
/// viewport) is last frame's, whose scene has not changed within MOVING_RECORDINGS recordings,
/// and whose history was not reset.
fn needs_edge_blur(
    state: &DenoiserState,
    c: &DenoisingCommon,
    previous: &Camera,
    reset: bool,
    (serial, scene_changed): (u64, u64),
) -> bool {
    let viewport = [c.viewport.x, c.viewport.y, c.viewport.width, c.viewport.height];
    let camera_moved = *previous != c.camera || state.previous_jitter != c.camera_jitter || state.previous_viewport != viewport;
    reset || camera_moved || scene_changed_recently((serial, scene_changed))
}

/// SDK-owned images start UNDEFINED; they live in GENERAL from the first task that uses them
/// on. That task resets history, so their contents are never read before written; the
/// intermediates are written before they are read by every task.
fn initialize_images(r: &mut Recording<'_>, state: &DenoiserState, guide: &mut Guide, temps: &TempPool) {
    if state.initialized && temps.initialized && guide.initialized {
        return;
    }
    let fresh_state = (!state.initialized).then(|| state.images()).into_iter().flatten();
    let fresh_temps = (!temps.initialized).then(|| temps.images()).into_iter().flatten();
    let fresh_guide = (!guide.initialized).then(|| guide.images().iter()).into_iter().flatten();
    let barriers: Vec<_> = fresh_state
        .chain(fresh_temps)
        .chain(fresh_guide)
        .map(|i| {
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::NONE)
                .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                // Sampled too: a history image stands in for a missing roughness or motion
                // input, and a bound descriptor counts as read.
                .dst_access_mask(
                    vk::AccessFlags2::SHADER_SAMPLED_READ
                        | vk::AccessFlags2::SHADER_STORAGE_READ
                        | vk::AccessFlags2::SHADER_STORAGE_WRITE,
                )
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(vk::ImageLayout::GENERAL)
                .image(i.raw)
                .subresource_range(COLOR_RANGE)
        })
        .collect();
    r.cmd.image_barriers(barriers);
    guide.initialized = true;
    // AO's moving-object stamps: a stamp left in reused memory must not match a frame. (The
    // transitions above wait for nothing; the clear waits for them.)
    if let (false, Some(tiles)) = (state.initialized, &state.motion_tiles) {
        let clear = sync::Use { stages: vk::PipelineStageFlags2::CLEAR, access: vk::AccessFlags2::TRANSFER_WRITE };
        let transitions = sync::Use { stages: vk::PipelineStageFlags2::COMPUTE_SHADER, access: vk::AccessFlags2::NONE };
        r.cmd.barrier(transitions, clear);
        r.hazards.write(r.cmd, clear);
        let zero = vk::ClearColorValue { uint32: [0; 4] };
        // The image is in GENERAL (the barrier above) and has TRANSFER_DST usage.
        r.cmd.clear_color_image(tiles.raw, vk::ImageLayout::GENERAL, zero, COLOR_RANGE);
    }
}

fn constants(
    job: &DenoiseJob,
    previous: &Camera,
    previous_jitter: [f32; 2],
    previous_viewport: [u32; 4],
    seed: u32,
    reset: bool,
) -> DenoiseConstantsGpu {
    let c = &job.common;
    let trace = c.as_trace_common();
    let eye = c.camera.world_to_view.inverse().w_axis;
    let prev_eye = previous.world_to_view.inverse().w_axis;
    let prev_world_to_clip = previous.view_to_clip * previous.world_to_view;
    // World size of one pixel at unit view distance (perspective: 2 tan(fov/2) / height).
    let pixel_size = 2.0 / (c.camera.view_to_clip.y_axis.y.abs().max(1e-12) * c.viewport.height.max(1) as f32);
    let motion = if !c.motion.has_image() {
        0
    } else {
        match c.motion.motion_type {
            MotionType::RgViewSpace => 1,
            MotionType::RgClipSpace => 2,
            MotionType::RgbWorldSpace => 3,
        }
    };
    let kind = |s: SignalType| match s {
        SignalType::Diffuse => 0,
        SignalType::Specular => 1,
        SignalType::DiffuseOcclusion => 2,
        SignalType::Shadow => 3,
        SignalType::MultiShadow => 4,
        SignalType::SpecularAndDiffuse => unreachable!("split into its two signals"),
    };
    let s = &c.settings;
    let anti_lag = s.anti_lag as u32;
    let kinds = match job.signal {
        SignalType::SpecularAndDiffuse => [1, 0, 0, anti_lag],
        k => {
            [kind(k), kind(k), crate::gpu::formats::channel_count(job.inputs[0].format).is_some_and(|n| n >= 2) as u32, anti_lag]
        }
    };
    DenoiseConstantsGpu {
        common: TraceCommonGpu::new(&trace, seed, 0),
        prev_world_to_clip: prev_world_to_clip.to_cols_array(),
        prev_clip_to_world: prev_world_to_clip.inverse().to_cols_array(),
        eye: [eye.x, eye.y, eye.z, pixel_size],
        prev_eye: [prev_eye.x, prev_eye.y, prev_eye.z, s.fresh_history_taps as f32],
        flags: [motion, job.count as u32, reset as u32, s.anti_firefly as u32],
        kinds,
        motion_scale: [c.motion.scale[0], c.motion.scale[1], c.motion.scale[2], 0.0],
        jitter_delta: [previous_jitter[0] - c.camera_jitter[0], previous_jitter[1] - c.camera_jitter[1], 0.0, 0.0],
        history: [s.max_history_frames as f32, s.fast_history_frames as f32, s.history_clamp_sigma, MIN_RADIUS_SCALE],
        stops: [s.luminance_sigma, s.normal_power, s.plane_distance_sigma, s.max_shadow_blur_radius],
        prev_viewport: previous_viewport.map(|v| v as f32),
        light: LightGpu::new(&job.light),
    }
}

impl PassTask for DenoiseJob {
    fn kind(&self) -> TaskKind {
        match self.signal {
            SignalType::Specular => TaskKind::DenoiseSpecular,
            SignalType::Diffuse => TaskKind::DenoiseDiffuse,
            SignalType::SpecularAndDiffuse => TaskKind::DenoiseSpecularAndDiffuse,
            SignalType::DiffuseOcclusion => TaskKind::DenoiseDiffuseOcclusion,
            SignalType::Shadow => TaskKind::DenoiseShadow,
            SignalType::MultiShadow => TaskKind::DenoiseMultiShadow,
        }
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<DenoiseConstantsGpu>() as u64
    }
    /// At build: the context still exists, denoises this task's signal and is large enough,
    /// and a view's tasks in the container denoise one camera's G-buffer.
    fn check(&self, world: &World<'_>) -> Result<()> {
        let field = crate::context::validate::denoise_context_field(self.signal);
        let state = world.denoisers.get(self.context).map_err(|e| e.for_field(field))?;
        if state.input.signal != self.signal {
            return Err(Error::invalid(
                field,
                format!("the context denoises {:?}, the task is {:?}", state.input.signal, self.signal),
            ));
        }
        // History is kept at the pixels' own coordinates: the viewport's far corner must fit.
        let vp = &self.common.viewport;
        let (right, bottom) = (vp.x as u64 + vp.width as u64, vp.y as u64 + vp.height as u64);
        if right > state.input.max_width as u64 || bottom > state.input.max_height as u64 {
            return Err(Error::invalid(
                "DenoisingCommon.viewport",
                format!("reaches ({right}, {bottom}), beyond the context's {}x{}", state.input.max_width, state.input.max_height),
            ));
        }
        if state.input.view_id != 0 {
            ViewInputs::of(&self.common).check(state.input.view_id, &mut world.view_inputs.borrow_mut())?;
        }
        Ok(())
    }
    /// Its context was checked at build (`check`).
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        let Ok(state) = world.denoisers.get_mut(self.context) else { return };
        let Some(guide) = world.denoise_guides.get_mut(&state.guide) else { return };
        passes.denoise.record(r, (state, guide), world.denoise_temps, self, (world.serial, world.scene.changed_at));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    /// std140 offsets of DenoiseConstants (TraceCommon is 384 bytes, LightGpu 64).
    #[test]
    fn layout_matches_glsl_std140() {
        assert_eq!(offset_of!(DenoiseConstantsGpu, prev_world_to_clip), 384);
        assert_eq!(offset_of!(DenoiseConstantsGpu, eye), 512);
        assert_eq!(offset_of!(DenoiseConstantsGpu, flags), 544);
        assert_eq!(offset_of!(DenoiseConstantsGpu, stops), 624);
        assert_eq!(offset_of!(DenoiseConstantsGpu, prev_viewport), 640);
        assert_eq!(offset_of!(DenoiseConstantsGpu, light), 656);
        assert_eq!(size_of::<DenoiseConstantsGpu>(), 720);
    }
}
