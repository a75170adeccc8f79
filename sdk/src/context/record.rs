//! One recording: the order in which a container's work goes into the engine's command buffer.
//!
//! 1. BVH work (timed as `Bvh`): scene tasks applied to the registries with their geometry
//!    copies (`scene`), throttled BLAS builds, refits and compactions, the TLAS (`bvh`).
//! 2. Cache maintenance (`CacheUpdate`): new surfel layouts, new and cleared caches (`cache`).
//! 3. Render tasks in scheduled order, each timed under its own kind. How a task records is its
//!    [`PassTask`](crate::passes::PassTask)'s business; this loop only sizes the upload ring,
//!    writes the instance table once, and hands each task a `Recording`.
use super::container::Task;
use super::journal::Journal;
use super::State;
use crate::error::Result;
use crate::gpu::commands::Commands;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::sync::{self, Hazards};
use crate::gpu::timestamps::Span;
use crate::passes::{blue_noise, Recording, RenderTask, World};
use crate::scene::table;
use crate::types::{RandomNumbers, TaskKind};
use ash::vk;
use std::sync::atomic::{AtomicBool, Ordering};

/// One recording in progress: the context's state, the working set it records into, and the
/// engine's command buffer.
pub(super) struct Recorder<'a> {
    pub device: &'a Device,
    pub memory: &'a Memory,
    pub st: &'a mut State,
    /// Index of the working set this ticket will own.
    pub ws: usize,
    /// The ticket's serial.
    pub serial: u64,
    /// What seeds the recording's random sequences and checkerboard phase: the container's
    /// frame index, or the serial.
    pub seed: u32,
    /// What the build records, replayed into the engine's buffer once it has succeeded.
    pub cmd: &'a Commands,
    pub hazards: Hazards,
    /// Set once the "no ray queries, using the pipeline" warning was logged.
    pub warned_inline: &'a AtomicBool,
    /// What the recording changed, to commit or undo (see `journal`).
    pub journal: Journal,
}

impl Recorder<'_> {
    /// Opens a timed (and, with debug utils, labelled) span of the recording.
    pub fn begin(&mut self, kind: TaskKind, task_index: u32) -> Span {
        let cmd = self.cmd;
        self.device.begin_label(cmd, &format!("{kind:?}"));
        self.working_set().timer.begin(cmd, kind, task_index)
    }

    pub fn end(&mut self, span: Span) {
        let cmd = self.cmd;
        self.working_set().timer.end(cmd, span);
        self.device.end_label(cmd);
    }

    /// Records every task of a container (validated: errors here are Vulkan/memory failures).
    /// `labels` (task index, label) name the render tasks' debug-utils regions.
    pub fn record(&mut self, tasks: &[Task], labels: &[(u32, String)]) -> Result<()> {
        let cmd = self.cmd;
        let ws = self.working_set();
        ws.ring.reset();
        ws.timer.reset(cmd);

        // ---- BVH work: copies, builds, refits, compactions, TLAS.
        let first_bvh =
            tasks.iter().position(|t| matches!(t, Task::Geometry(_) | Task::Instance(_) | Task::BvhBuild(_))).map(|i| i as u32);
        let has_render = tasks.iter().any(|t| matches!(t, Task::Render(_)));
        let bvh_span = first_bvh.map(|i| self.begin(TaskKind::Bvh, i));
        self.apply_scene_tasks(tasks)?;
        let max_builds: Option<u32> = tasks
            .iter()
            .filter_map(|t| if let Task::BvhBuild(b) = t { Some(b.max_blas_build_count) } else { None })
            .reduce(|a, b| a.saturating_add(b));
        // A TLAS rebuilt in a frame without a BVH task (render tasks only) is rebuilt in full.
        let max_refits = tasks
            .iter()
            .filter_map(|t| if let Task::BvhBuild(b) = t { Some(b.tlas_max_refits) } else { None })
            .max()
            .unwrap_or(0);
        if let Some(max_builds) = max_builds {
            let span = self.begin(TaskKind::BlasBuild, first_bvh.unwrap_or(0));
            self.record_blas_work(max_builds)?;
            self.end(span);
        }
        if max_builds.is_some() || has_render {
            if self.st.scene.snapshot_dirty {
                self.journal.saved_snapshot(std::mem::take(&mut self.st.scene.snapshot));
                self.st.scene.rebuild_snapshot();
                self.st.scene.changed_at = self.serial;
            }
            if self.working_set().tlas.version != self.st.scene.snapshot_version {
                let span = self.begin(TaskKind::TlasBuild, first_bvh.unwrap_or(0));
                self.record_tlas(max_refits)?;
                self.end(span);
            }
        }
        if let Some(span) = bvh_span {
            self.end(span);
        }

        // ---- Cache maintenance: new layouts, new caches, clears.
        if self.st.scene.caches_dirty || tasks.iter().any(|t| matches!(t, Task::ClearCache(_))) {
            let span = self.begin(TaskKind::CacheUpdate, 0);
            self.update_caches(tasks)?;
            self.end(span);
        }

        // ---- Render tasks, in scheduled order.
        self.record_render(tasks, labels)?;

        // ---- What the host reads when the ticket is back (read-backs, index-check counters)
        // must reach the host domain.
        // ---- The completion marker, after everything else: the ticket's serial, read when it
        // comes back. With it, read-backs and counters reach the host domain.
        let cmd = self.cmd;
        self.hazards.write(cmd, sync::TRANSFER_WRITE);
        let marker = self.st.working_sets[self.ws].marker.raw;
        let serial = self.serial;
        cmd.fill_buffer(marker, 0, 4, serial as u32);
        cmd.fill_buffer(marker, 4, 4, (serial >> 32) as u32);
        self.hazards.read(cmd, sync::HOST_READ);
        Ok(())
    }

    fn record_render(&mut self, tasks: &[Task], labels: &[(u32, String)]) -> Result<()> {
        let renders: Vec<(u32, &RenderTask)> = tasks
            .iter()
            .enumerate()
            .filter_map(|(i, t)| if let Task::Render(r) = t { Some((i as u32, r)) } else { None })
            .collect();
        if renders.is_empty() {
            return Ok(());
        }
        let align = self.device.ubo_alignment;
        let task_bytes: u64 = renders.iter().map(|(_, t)| t.upload_bytes() + align).sum();
        // The blue-noise tile travels in the ring, and only in recordings that ask for it.
        let wants_blue_noise = renders
            .iter()
            .any(|(_, t)| t.describe().trace_common().is_some_and(|c| c.random_numbers == RandomNumbers::BlueNoise));
        let blue_noise_bytes = if wants_blue_noise { std::mem::size_of_val(blue_noise::tile()) as u64 + 16 } else { 0 };
        self.ensure_ring(table::instance_table_bytes(&self.st.scene) + 16 + task_bytes + blue_noise_bytes)?;
        // With a cache budget: per-instance usage flags, cleared, set by the shaders that use
        // an instance, copied for the host when the ticket comes back (see `budget`).
        let usage = if self.st.cache_budget > 0 {
            let slots = self.st.scene.instances.slot_count().max(1) as u32;
            let (flags, address, readback) = self.ensure_usage(slots)?;
            self.working_set().usage_slots = slots;
            Some((flags, address, readback, slots as u64 * 4))
        } else {
            None
        };
        if let Some((flags, _, _, bytes)) = usage {
            let cmd = self.cmd;
            self.hazards.write(cmd, sync::TRANSFER_WRITE);
            cmd.fill_buffer(flags, 0, bytes, 0);
        }

        let (device, cmd, seed) = (self.device, self.cmd, self.seed);
        let st = &mut *self.st;
        let ws = &mut st.working_sets[self.ws];
        let instance_table = ws.ring.push(bytemuck::cast_slice(&table::instance_table(&st.scene)), 16).address;
        let blue_noise =
            if wants_blue_noise { ws.ring.push(bytemuck::cast_slice(blue_noise::tile().as_slice()), 16).address } else { 0 };
        let tlas = ws.tlas_handle();
        let mut world = World {
            scene: &st.scene,
            cache_pool: &st.cache_pool,
            denoisers: &mut st.denoisers,
            many_lights: &mut st.many_lights,
            denoise_temps: &mut st.denoise_temps,
            denoise_guides: &mut st.denoise_guides,
            view_inputs: Default::default(),
            serial: self.serial,
            relight_cursor: &mut st.relight_cursor,
            limits: &device.limits,
        };
        for (index, task) in renders {
            let describe = task.describe();
            // Inline ray queries where asked for and available; otherwise the pipeline (once a
            // warning says so).
            let wants_inline = describe.trace_common().is_some_and(|c| c.use_inline_rt);
            if wants_inline && !device.ray_query && !self.warned_inline.swap(true, Ordering::Relaxed) {
                log::warn!("use_inline_rt: the device has no VK_KHR_ray_query enabled; using the ray-tracing pipeline");
            }
            let kind = describe.kind();
            match labels.binary_search_by_key(&index, |(i, _)| *i) {
                Ok(at) => device.begin_label(cmd, &format!("{} ({kind:?}, task {index})", labels[at].1)),
                Err(_) => device.begin_label(cmd, &format!("{kind:?} (task {index})")),
            }
            let span = ws.timer.begin(cmd, kind, index);
            let mut r = Recording {
                device,
                cmd,
                ring: &mut ws.ring,
                hazards: &mut self.hazards,
                tlas,
                seed,
                instance_table,
                usage: usage.map_or(0, |u| u.1),
                blue_noise,
                inline: wants_inline && device.ray_query,
                floor: st.passes.floor,
                task_timer: Some((&mut ws.timer, kind, index)),
            };
            task.record(&mut r, &st.passes, &mut world);
            ws.timer.end(cmd, span);
            device.end_label(cmd);
        }
        if let Some((flags, _, readback, bytes)) = usage {
            self.hazards.read_write(cmd, sync::TRANSFER_READ, sync::TRANSFER_WRITE);
            let region = [vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes }];
            // The host reads the copy after the ticket's marker.
            cmd.copy_buffer(flags, readback, &region);
        }
        Ok(())
    }
}
