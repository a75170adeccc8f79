//! Cache relighting from the engine's lights (`RelightCacheTask`, shaders/relight.rgen).
//!
//! Kickstart RT's cache only knows what a camera has injected; its guide has engines fly a
//! "lidar" camera around to fill it, and a surface no camera saw stays at its initial colour
//! in every reflection and GI ray. Here the engine may hand us its lights and each instance's
//! albedo, and the surfaces no camera has injected are lit with shadow rays — the approach of
//! Lumen's surface cache and Bevy Solari's world cache, which light their caches from the
//! scene's lights rather than from the screen.
//!
//! Cost is bounded per build: a cursor walks the instances' caches round-robin across builds,
//! `max_samples` samples at a time, in one launch whatever the number of instances (a job
//! list says which instance and triangles each range of invocations lights).
use super::constants::LightGpu;
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::scene::Scene;
use crate::shaders;
use crate::types::{InstanceInclusionMask, RelightCacheTask, SurfelType, TaskKind, MAX_SHADOW_LIGHTS};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// Jobs one launch takes (the size of `RelightJobs` in the shader): a build whose budget would
/// need more (many tiny instances) stops there and the cursor goes on next build.
const MAX_JOBS: usize = 1024;
/// The launch's width (`HRT_RELIGHT_WIDTH`).
const WIDTH: u32 = 4096;

/// `RelightConstants` in shaders/relight.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct RelightConstantsGpu {
    counts: [u32; 4],
    params: [u32; 4],
    sky: [f32; 4],
    lights: [LightGpu; MAX_SHADOW_LIGHTS],
}

/// Where the relight walk stopped: the next instance slot and triangle to light.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RelightCursor {
    pub slot: usize,
    pub triangle: u32,
}

/// One build's work: runs of triangles as (instance slot, first triangle, samples per
/// triangle, first invocation), and the total invocations.
#[derive(Debug, Default, PartialEq)]
pub(crate) struct RelightPlan {
    pub jobs: Vec<[u32; 4]>,
    pub invocations: u32,
}

/// Samples per triangle of a layout at its largest resolution (the launch's per-triangle
/// extent; smaller triangles leave the rest idle).
fn samples_per_triangle(surfel_type: SurfelType, r: u32) -> u32 {
    match surfel_type {
        SurfelType::Tiles => r * r,
        SurfelType::MeshColors => (r + 1) * (r + 2) / 2,
    }
}

/// Plans up to `budget` invocations from `cursor` over every instance with a cache, at most
/// once round, and moves the cursor past them.
pub(crate) fn plan(scene: &Scene, cursor: &mut RelightCursor, budget: u32) -> RelightPlan {
    // (slot, triangles, samples per triangle) of every instance with a cache, in slot order.
    let cached: Vec<(usize, u32, u32)> = scene
        .instances
        .iter()
        .filter_map(|(h, rec)| {
            let p = rec.placement?;
            p.cache?;
            let g = scene.geometries.get(p.geometry).ok()?;
            let surfel = g.surfel.as_ref()?;
            let slot = scene.instances.index_of(h).ok()? as usize;
            Some((slot, g.layout?.primitive_count, samples_per_triangle(surfel.surfel_type, surfel.max_resolution)))
        })
        .collect();
    let mut plan = RelightPlan::default();
    if cached.is_empty() {
        return plan;
    }
    // Start at the cursor's instance (or the next one with a cache), wrapping once.
    let start = cached.iter().position(|c| c.0 >= cursor.slot).unwrap_or(0);
    if cached[start].0 != cursor.slot {
        cursor.triangle = 0;
    }
    let mut left = budget as u64;
    for k in 0..=cached.len() {
        let (slot, triangles, spt) = cached[(start + k) % cached.len()];
        let first = if k == 0 { cursor.triangle.min(triangles) } else { 0 };
        // Wrapped back to the start: only the triangles before the cursor's remain.
        let end = if k == cached.len() { cursor.triangle.min(triangles) } else { triangles };
        if first >= end {
            continue;
        }
        let spt = spt.max(1);
        let take = ((end - first) as u64).min(left / spt as u64) as u32;
        if take == 0 || plan.jobs.len() == MAX_JOBS {
            *cursor = RelightCursor { slot, triangle: first };
            return plan;
        }
        plan.jobs.push([slot as u32, first, spt, plan.invocations]);
        plan.invocations += take * spt;
        left -= (take * spt) as u64;
        *cursor = if first + take < triangles {
            RelightCursor { slot, triangle: first + take }
        } else {
            RelightCursor { slot: slot + 1, triangle: 0 }
        };
        if first + take < end {
            return plan;
        }
    }
    plan
}

pub(crate) struct RelightPass {
    program: RtProgram,
}

impl RelightPass {
    /// Every pass is made with the G-buffer sampler (see `Passes`); this one samples nothing.
    pub fn new(b: &mut PipelineBuilder<'_>, _sampler: vk::Sampler) -> Result<RelightPass> {
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            Shaders::hit_record(shaders::RELIGHT_RGEN),
        )?;
        Ok(RelightPass { program })
    }

    fn record(&self, r: &mut Recording<'_>, task: &RelightCacheTask, plan: &RelightPlan) {
        let mut lights = [LightGpu::default(); MAX_SHADOW_LIGHTS];
        for (g, l) in lights.iter_mut().zip(&task.lights) {
            *g = LightGpu::new(l);
        }
        let constants = RelightConstantsGpu {
            counts: [plan.jobs.len() as u32, plan.invocations, task.lights.len() as u32, r.seed],
            params: [
                task.history_frames,
                InstanceInclusionMask::SHADOWS.bits() as u32,
                task.bounce as u32,
                InstanceInclusionMask::DIFFUSE_GI.bits() as u32,
            ],
            sky: [task.sky[0], task.sky[1], task.sky[2], 0.0],
            lights,
        };
        let mut jobs = [[0u32; 4]; MAX_JOBS];
        jobs[..plan.jobs.len()].copy_from_slice(&plan.jobs);
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let job_ubo = r.ring.push(bytemuck::cast_slice(&jobs), r.device.ubo_alignment);
        let slots = [Slot::Tlas(r.tlas), Slot::Uniform(ubo), Slot::Uniform(job_ubo)];
        let height = plan.invocations.div_ceil(WIDTH);
        self.program.run(r, &slots, WIDTH.min(plan.invocations), height, Writes::Storage);
    }
}

impl PassTask for RelightCacheTask {
    fn kind(&self) -> TaskKind {
        TaskKind::CacheRelight
    }
    fn upload_bytes(&self) -> u64 {
        // Two blocks, each aligned on its own.
        (std::mem::size_of::<RelightConstantsGpu>() + MAX_JOBS * 16) as u64 + 256
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        let plan = plan(world.scene, world.relight_cursor, self.max_samples);
        if plan.invocations == 0 {
            return;
        }
        passes.relight.record(r, self, &plan);
    }
}
