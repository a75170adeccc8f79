//! Many shadowed lights (`TraceManyLightsTask`): spatiotemporal reservoir resampling of direct
//! lighting (ReSTIR DI, Bitterli et al. 2020), shaders/include/many_lights.glsl.
//!
//! The anchors: Kickstart RT stops at 32 shadowed lights, each with a ray at every pixel it
//! reaches (so do we, in `TraceMultiShadowTask`); RTXDI and Bevy Solari resample. What this
//! one takes from them and where it differs:
//! - The light list lives on the GPU in the context and changes by ranges
//!   (`LightListUpdate::Write`): a moving light uploads 64 bytes, not the list. The power
//!   distribution (a prefix sum, one group) is rebuilt only when the list changed; every frame
//!   128 tiles of 1,024 lights are drawn from it (RTXDI's presampling), each tile a stratified
//!   set, so a pixel's candidates cost one cached fetch each, whatever the list's length.
//! - Lights keep their index, so last frame's samples need no remapping table (RTXDI asks the
//!   engine for one): a sample's light is re-evaluated with this frame's data, and a light
//!   removed (or switched off) has a zero target and dies the next frame.
//! - Candidates: local lights by power and one directional light (disjoint strategies, so the
//!   multiple-importance weights are exact without evaluating both densities).
//! - Two passes: candidates (+ their visibility, optional in the biased mode) + temporal reuse
//!   (ray pass 1); spatial reuse + the shading ray + the reservoir kept (ray pass 2).
//! - Merging weighs a sample by how likely each merged reservoir was to produce it
//!   (generalized RIS, Lin et al. 2022): the temporal merge by the balance heuristic of the two
//!   reservoirs' confidence-weighted targets, the spatial merge by pairwise MIS (Bitterli 2022:
//!   each neighbour paired with the pixel, O(neighbours) target evaluations). RTXDI's default
//!   and Bitterli et al.'s 1/Z weights count every reservoir that could produce a sample alike,
//!   so a sample that a neighbour barely reaches and this pixel sees brightly keeps the
//!   neighbour's large contribution weight: a firefly that reuse then spreads and keeps.
//!   Measured against brute force, one frame's error halves and the biased mode's darkening
//!   falls from -3.5% to -0.7%. The biased mode's targets leave visibility out (no rays: one
//!   shadow ray a pixel in all by default); the unbiased mode's include a merged reservoir's
//!   visibility of the sample it is weighed for (a shadow ray per neighbour).
//! - A light written this frame (moved, recoloured) ends the confidence of the histories that
//!   hold it: their weights were made for the light as it was. Histories are 8 frames long by
//!   default, not RTXDI's 20: the denoiser averages frames, and frames that share samples for
//!   20 frames average to less (measured: a third less error after denoising with 8).
//! - Outputs are demodulated diffuse and specular (with hit distance), the denoisers' inputs.
use super::constants::TraceCommonGpu;
use super::descriptors::{optional_or, Slot};
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::memory::{Buffer, Memory, MemoryKind};
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::gpu::sync;
use crate::shaders;
use crate::types::{
    Camera, InstanceInclusionMask, LightListUpdate, LightType, ManyLightsContextInput, MotionType, ResamplingMode, TaskKind,
    TraceCommon, TraceManyLightsTask, Viewport,
};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

/// Presampled tiles of local lights per frame (`u_c.sizes.y`), and lights per tile
/// (`HRT_ML_TILE`).
const PRESAMPLE_TILES: u32 = 128;
const PRESAMPLE_TILE: u32 = 1024;
/// Bytes per light (`LightGpu`), per CDF entry (vec2), per reservoir (uvec4), per surface (uvec2).
const LIGHT_BYTES: u64 = 64;
const CDF_BYTES: u64 = 8;
const RESERVOIR_BYTES: u64 = 16;
const SURFACE_BYTES: u64 = 8;

/// A many-lights context's GPU state (see `ManyLightsContextInput`).
pub(crate) struct ManyLightsState {
    pub input: ManyLightsContextInput,
    lights: Buffer,
    cdf: Buffer,
    presampled: Buffer,
    /// The temporal pass's reservoirs (read by the spatial pass's neighbours).
    temporal: Buffer,
    /// The reservoirs kept for next frame's temporal reuse.
    kept: Buffer,
    /// Each pixel's surface, for next frame's reuse.
    surfaces: Buffer,
    /// Lights in the list, and which are directional (for the candidates' strategies).
    pub count: u32,
    directional: Vec<bool>,
    directional_count: u32,
    /// The camera and viewport `kept` and `surfaces` were made with (None: no history).
    previous: Option<(Camera, Viewport)>,
}

impl ManyLightsState {
    /// Allocates every buffer the context needs, all or none.
    pub fn new(memory: &Memory, input: &ManyLightsContextInput) -> Result<ManyLightsState> {
        let pixels = input.max_width as u64 * input.max_height as u64;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let specs: [(&'static str, u64); 6] = [
            ("many-lights light list", input.max_lights as u64 * LIGHT_BYTES),
            ("many-lights power distribution", input.max_lights as u64 * CDF_BYTES),
            ("many-lights presampled lights", (PRESAMPLE_TILES as u64 + 1) * PRESAMPLE_TILE as u64 * CDF_BYTES),
            ("many-lights reservoirs", pixels * RESERVOIR_BYTES),
            ("many-lights kept reservoirs", pixels * RESERVOIR_BYTES),
            ("many-lights surfaces", pixels * SURFACE_BYTES),
        ];
        let mut made: Vec<Buffer> = Vec::new();
        for (name, size) in specs {
            match memory.create_buffer(name, size, usage, MemoryLocation::GpuOnly, MemoryKind::ManyLights) {
                Ok(b) => made.push(b),
                Err(e) => {
                    for b in made {
                        memory.destroy_buffer(b);
                    }
                    return Err(e);
                }
            }
        }
        let mut it = made.into_iter();
        let mut next = || it.next().expect("six buffers made");
        Ok(ManyLightsState {
            input: *input,
            lights: next(),
            cdf: next(),
            presampled: next(),
            temporal: next(),
            kept: next(),
            surfaces: next(),
            count: 0,
            directional: Vec::new(),
            directional_count: 0,
            previous: None,
        })
    }

    /// Every buffer, for (deferred) destruction.
    pub fn into_buffers(self) -> Vec<Buffer> {
        vec![self.lights, self.cdf, self.presampled, self.temporal, self.kept, self.surfaces]
    }

    /// The list's length after `update`, or why it cannot apply (checked at build; recording
    /// checks again, since two tasks of one build may both change the list).
    pub fn count_after(&self, update: &LightListUpdate) -> std::result::Result<u32, String> {
        let max = self.input.max_lights as u64;
        let count = match update {
            LightListUpdate::Keep => self.count as u64,
            LightListUpdate::Replace(l) => l.len() as u64,
            LightListUpdate::Write { first, lights } => {
                if *first > self.count {
                    return Err(format!("first {first} is beyond the list's {} lights", self.count));
                }
                (self.count as u64).max(*first as u64 + lights.len() as u64)
            }
        };
        if count > max {
            return Err(format!("{count} lights exceed the context's max_lights {max}"));
        }
        Ok(count as u32)
    }

    /// Applies `update` to the CPU's view of the list (length, directional lights); returns the
    /// first light it writes.
    fn apply(&mut self, update: &LightListUpdate, count: u32) -> u32 {
        let first = match update {
            LightListUpdate::Keep => return 0,
            LightListUpdate::Replace(_) => 0,
            LightListUpdate::Write { first, .. } => *first,
        };
        self.directional.resize(count as usize, false);
        for (i, l) in update.lights().iter().enumerate() {
            self.directional[first as usize + i] = l.light_type == LightType::Directional;
        }
        self.directional_count = self.directional.iter().filter(|d| **d).count() as u32;
        self.count = count;
        first
    }
}

/// `ManyLightsConstants` in shaders/include/many_lights.glsl.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ManyLightsConstantsGpu {
    common: TraceCommonGpu,
    prev_world_to_clip: [f32; 16],
    prev_clip_to_world: [f32; 16],
    prev_eye: [f32; 4],
    prev_viewport: [f32; 4],
    counts: [u32; 4],
    modes: [u32; 4],
    params: [f32; 4],
    addr0: [u32; 4],
    addr1: [u32; 4],
    addr2: [u32; 4],
    sizes: [u32; 4],
    changed: [u32; 4],
}

/// The push constants of many_lights_cdf.comp.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct CdfPush {
    lights: u64,
    cdf: u64,
    count: u32,
    pad: [u32; 3],
}

/// The push constants of many_lights_presample.comp.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct PresamplePush {
    cdf: u64,
    presampled: u64,
    count: u32,
    tiles: u32,
    seed: u32,
    pad: u32,
}

fn split(address: u64) -> [u32; 2] {
    [address as u32, (address >> 32) as u32]
}

pub(crate) struct ManyLightsPass {
    compute_layout: vk::PipelineLayout,
    cdf: vk::Pipeline,
    presample: vk::Pipeline,
    temporal: RtProgram,
    spatial: RtProgram,
}

impl ManyLightsPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<ManyLightsPass> {
        let compute_layout = b.layout(None, 32, vk::ShaderStageFlags::COMPUTE)?;
        let cdf = b.compute(compute_layout, shaders::MANY_LIGHTS_CDF_COMP)?;
        let presample = b.compute(compute_layout, shaders::MANY_LIGHTS_PRESAMPLE_COMP)?;
        use vk::DescriptorType as T;
        let sampled = || Binding { ty: T::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) };
        let storage = || Binding { ty: T::STORAGE_IMAGE, sampler: None };
        // After the G-buffer trace's own: roughness, motion, specular output, debug output.
        let bindings = super::gbuffer_bindings(sampler, &[sampled(), sampled(), storage(), storage()]);
        let temporal = RtProgram::new(
            b,
            &bindings,
            Shaders::hit_record_trace(shaders::MANY_LIGHTS_TEMPORAL_RGEN, shaders::MANY_LIGHTS_TEMPORAL_COMP),
        )?;
        let spatial = RtProgram::new(
            b,
            &bindings,
            Shaders::hit_record_trace(shaders::MANY_LIGHTS_SPATIAL_RGEN, shaders::MANY_LIGHTS_SPATIAL_COMP),
        )?;
        Ok(ManyLightsPass { compute_layout, cdf, presample, temporal, spatial })
    }

    fn record(&self, r: &mut Recording<'_>, task: &TraceManyLightsTask, state: &mut ManyLightsState) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        // 1. The light list's changes, and its power distribution.
        let update = match state.count_after(&task.lights) {
            Ok(_) if matches!(task.lights, LightListUpdate::Keep) => None,
            Ok(count) => Some(count),
            Err(e) => {
                // Checked at build against the list before it; a second task of the same
                // build changed the list since.
                log::error!("TraceManyLightsTask.lights: {e}: the list is left unchanged");
                None
            }
        };
        let mut changed = [0u32; 2];
        if let Some(count) = update {
            let first = state.apply(&task.lights, count);
            changed = [first, first + task.lights.lights().len() as u32];
            let lights: Vec<LightGpuStd> = task.lights.lights().iter().map(LightGpuStd::new).collect();
            if !lights.is_empty() {
                let upload = r.ring.push(bytemuck::cast_slice(&lights), 16);
                r.hazards.write(r.cmd, sync::TRANSFER_WRITE);
                let region =
                    vk::BufferCopy { src_offset: upload.offset, dst_offset: first as u64 * LIGHT_BYTES, size: upload.size };
                r.cmd.copy_buffer(upload.buffer, state.lights.raw, &[region]);
            }
            if state.count > 0 {
                let span = r.begin_pass("light distribution");
                r.hazards.read_write(r.cmd, sync::shader_read(compute), sync::shader_write(compute));
                r.cmd.bind_pipeline(vk::PipelineBindPoint::COMPUTE, self.cdf);
                let push = CdfPush { lights: state.lights.address, cdf: state.cdf.address, count: state.count, pad: [0; 3] };
                r.cmd.push_constants(self.compute_layout, vk::ShaderStageFlags::COMPUTE, bytemuck::bytes_of(&push));
                r.cmd.dispatch(1, 1, 1);
                r.end_pass(span);
            }
        }
        // 2. This frame's presampled lights.
        if state.count > 0 {
            let span = r.begin_pass("presample");
            r.hazards.read_write(r.cmd, sync::shader_read(compute), sync::shader_write(compute));
            r.cmd.bind_pipeline(vk::PipelineBindPoint::COMPUTE, self.presample);
            let push = PresamplePush {
                cdf: state.cdf.address,
                presampled: state.presampled.address,
                count: state.count,
                tiles: PRESAMPLE_TILES,
                seed: r.seed,
                pad: 0,
            };
            r.cmd.push_constants(self.compute_layout, vk::ShaderStageFlags::COMPUTE, bytemuck::bytes_of(&push));
            r.cmd.dispatch(((PRESAMPLE_TILES + 1) * PRESAMPLE_TILE).div_ceil(256), 1, 1);
            r.end_pass(span);
        }
        // 3. The two ray passes.
        let constants = constants(task, state, r.seed, changed);
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let c = &task.common;
        let mut slots = super::gbuffer_slots(r.tlas, c, &task.diffuse_output, ubo);
        slots.extend([
            Slot::Sampled(optional_or(&c.roughness.image, &c.normals.image)),
            Slot::Sampled(optional_or(&task.motion.image, &c.normals.image)),
            Slot::Storage(&task.specular_output),
            Slot::Storage(optional_or(&task.debug_output, &task.diffuse_output)),
            super::input_mask_slot(c),
        ]);
        let vp = &c.viewport;
        if task.settings.mode != ResamplingMode::PowerSampling {
            let span = r.begin_pass("candidates + temporal");
            self.temporal.run(r, &slots, vp.width, vp.height, Writes::Storage);
            r.end_pass(span);
        }
        let span = r.begin_pass("spatial + shade");
        self.spatial.run(r, &slots, vp.width, vp.height, Writes::Storage);
        r.end_pass(span);
        state.previous = Some((c.camera, c.viewport));
    }
}

/// `LightGpu` as the list's std430 array holds it (the same 64 bytes as the std140 block).
type LightGpuStd = super::constants::LightGpu;

/// `changed`: the lights this task wrote (first, end).
fn constants(task: &TraceManyLightsTask, state: &ManyLightsState, seed: u32, changed: [u32; 2]) -> ManyLightsConstantsGpu {
    let c: &TraceCommon = &task.common;
    let history = if task.reset_history { None } else { state.previous };
    let (prev_camera, prev_viewport) = history.unwrap_or((c.camera, c.viewport));
    let prev_world_to_clip = prev_camera.view_to_clip * prev_camera.world_to_view;
    let prev_eye = prev_camera.world_to_view.inverse().w_axis;
    let motion = if task.motion.image.image == vk::Image::null() {
        0
    } else {
        match task.motion.motion_type {
            MotionType::RgViewSpace => 1,
            MotionType::RgClipSpace => 2,
            MotionType::RgbWorldSpace => 3,
        }
    };
    let s = &task.settings;
    let lights = split(state.lights.address);
    let cdf = split(state.cdf.address);
    let presampled = split(state.presampled.address);
    let temporal = split(state.temporal.address);
    let kept = split(state.kept.address);
    let surfaces = split(state.surfaces.address);
    let pv = &prev_viewport;
    ManyLightsConstantsGpu {
        common: TraceCommonGpu::new(c, seed, InstanceInclusionMask::SHADOWS.bits()),
        prev_world_to_clip: prev_world_to_clip.to_cols_array(),
        prev_clip_to_world: prev_world_to_clip.inverse().to_cols_array(),
        prev_eye: [prev_eye.x, prev_eye.y, prev_eye.z, history.is_some() as u32 as f32],
        prev_viewport: [pv.x as f32, pv.y as f32, pv.width as f32, pv.height as f32],
        counts: [state.count, s.initial_candidates, s.spatial_samples, s.max_history],
        modes: [
            s.mode as u32,
            motion,
            (state.directional_count > 0) as u32,
            (task.debug_output.image != vk::Image::null()) as u32,
        ],
        params: [s.spatial_radius, task.motion.scale[0], task.motion.scale[1], task.motion.scale[2]],
        addr0: [lights[0], lights[1], cdf[0], cdf[1]],
        addr1: [presampled[0], presampled[1], temporal[0], temporal[1]],
        addr2: [kept[0], kept[1], surfaces[0], surfaces[1]],
        sizes: [state.input.max_width, PRESAMPLE_TILES, seed, (!s.candidate_visibility) as u32],
        changed: [changed[0], changed[1], 0, 0],
    }
}

impl PassTask for TraceManyLightsTask {
    fn kind(&self) -> TaskKind {
        TaskKind::ManyLights
    }
    fn upload_bytes(&self) -> u64 {
        // The constants and the lights, each aligned on its own.
        std::mem::size_of::<ManyLightsConstantsGpu>() as u64 + self.lights.lights().len() as u64 * LIGHT_BYTES + 512
    }
    fn trace_common(&self) -> Option<&TraceCommon> {
        Some(&self.common)
    }
    fn check(&self, world: &World<'_>) -> Result<()> {
        let state = world.many_lights.get(self.context).map_err(|e| e.for_field("TraceManyLightsTask.context"))?;
        let vp = &self.common.viewport;
        let (right, bottom) = (vp.x as u64 + vp.width as u64, vp.y as u64 + vp.height as u64);
        if right > state.input.max_width as u64 || bottom > state.input.max_height as u64 {
            return Err(crate::Error::invalid(
                "TraceManyLightsTask.common.viewport",
                format!("reaches ({right}, {bottom}), beyond the context's {}x{}", state.input.max_width, state.input.max_height),
            ));
        }
        state.count_after(&self.lights).map_err(|e| crate::Error::invalid("TraceManyLightsTask.lights", e))?;
        Ok(())
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        let Ok(state) = world.many_lights.get_mut(self.context) else { return };
        passes.many_lights.record(r, self, state);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[test]
    fn constants_match_glsl_std140() {
        assert_eq!(offset_of!(ManyLightsConstantsGpu, prev_world_to_clip), 384);
        assert_eq!(offset_of!(ManyLightsConstantsGpu, prev_eye), 512);
        assert_eq!(offset_of!(ManyLightsConstantsGpu, counts), 544);
        assert_eq!(offset_of!(ManyLightsConstantsGpu, sizes), 640);
        assert_eq!(offset_of!(ManyLightsConstantsGpu, changed), 656);
        assert_eq!(size_of::<ManyLightsConstantsGpu>(), 672);
        assert_eq!(size_of::<LightGpuStd>() as u64, LIGHT_BYTES);
        assert_eq!(size_of::<CdfPush>(), 32);
        assert_eq!(size_of::<PresamplePush>(), 32);
    }
}
