//! The direct-lighting cache's side of recording: surfel layouts of new geometry, layout
//! uploads, and per-instance cache allocation (under the budget), fills and clears.
//! (Injection and its resolve are a render task: `passes::inject`; relighting another:
//! `passes::relight`.)
//!
//! Sizing a cache needs the geometry's edge lengths, which live on the GPU. Like BLAS
//! compaction, this never stalls: the ticket that copies a geometry also builds its layout on
//! the GPU (`passes::surfel_layout`) and reads back only its sample count — or, for a mesh too
//! big for one dispatch, copies the geometry to a read-back buffer for the CPU builder; when
//! that ticket comes back the layout is installed (or built and uploaded by the next
//! recording), and every instance of the geometry gets its cache. Until then an instance reads
//! as its `initial_tile_color` and injection skips it.
use super::budget::{self, Candidate};
use super::container::Task;
use super::journal::{Held, Journal, Slot};
use super::record::Recorder;
use super::working_set::Readback;
use super::State;
use crate::cache::layout;
use crate::error::Result;
use crate::gpu::commands::Commands;
use crate::gpu::deferred::Garbage;
use crate::gpu::memory::{Buffer, Memory, MemoryKind};
use crate::gpu::sync::{self, Hazards};
use crate::passes::{surfel_layout, Recording};
use crate::scene::geometry::{self, GeometryLayout, SurfelGpu};
use crate::scene::instance::Placement;
use crate::types::{GeometryHandle, InstanceHandle, SurfelType};
use ash::vk;
use gpu_allocator::MemoryLocation;

impl Recorder<'_> {
    /// Sizes the surfel layouts of freshly registered geometry (after the geometry copies):
    /// layouts are built on the GPU and only their sample count is read back; a mesh too
    /// big for one dispatch of the passes copies the geometry to a read-back buffer for the
    /// CPU builder.
    pub fn record_readbacks(&mut self, handles: &[GeometryHandle]) -> Result<()> {
        // Layouts built again with a smaller resolution limit (too many samples before).
        let mut jobs: Vec<(GeometryHandle, Option<u32>)> = handles.iter().map(|&h| (h, None)).collect();
        jobs.extend(std::mem::take(&mut self.st.scene.relayout).into_iter().map(|(h, limit)| (h, Some(limit))));
        if jobs.is_empty() {
            return Ok(());
        }
        let max_groups = self.device.limits.max_dispatch_groups[0];
        let max_tiles = surfel_layout::max_triangles(max_groups);
        let mut copied = false;
        let mut plans = Vec::new();
        for (h, limit) in jobs {
            let st = &mut *self.st;
            let g = st.scene.geometries.get(h)?;
            let (Some(copy), Some(l)) = (g.copy.as_ref(), g.layout) else { continue };
            let (copy_raw, copy_address, build_id) = (copy.raw, copy.address, g.build_id);
            let surfels = g.input.surfels;
            let (t, v) = (l.primitive_count as u64, l.vertex_count as u64);
            let on_gpu = match surfels.surfel_type {
                SurfelType::Tiles => t > 0 && t <= max_tiles,
                SurfelType::MeshColors => surfel_layout::mesh_colors_fits(max_groups, t, v),
            };
            if on_gpu {
                // Forced direct tile mapping: one sample per triangle from the start.
                let first = if surfels.maps_directly_from_start() { 1 } else { surfels.tile_resolution_limit };
                let limit = limit.unwrap_or(first.clamp(1, layout::MAX_RESOLUTION));
                plans.push(self.plan_gpu_layout(h, build_id, copy_address, l, surfels, limit)?);
                continue;
            }
            let cmd = self.cmd;
            if !copied {
                self.hazards.read_write(cmd, sync::TRANSFER_READ, sync::TRANSFER_WRITE);
                copied = true;
            }
            let readback = self.memory.create_buffer(
                "geometry read-back",
                l.total_bytes(),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                MemoryKind::Readback,
            )?;
            let region = [vk::BufferCopy { src_offset: 0, dst_offset: 0, size: l.total_bytes() }];
            cmd.copy_buffer(copy_raw, readback.raw, &region);
            self.st.scene.cache_stats.readback_bytes += l.total_bytes();
            self.st.working_sets[self.ws].readbacks.push(Readback::Geometry { geometry: h, build_id, buffer: readback });
        }
        // Every layout of the recording together: one barrier per pass, not per pass per mesh.
        if !plans.is_empty() {
            let st = &mut *self.st;
            let ws = &mut st.working_sets[self.ws];
            let mut r = Recording::maintenance(self.device, self.cmd, &mut ws.ring, &mut self.hazards, self.seed);
            st.passes.surfel_layout.record(&mut r, &plans);
        }
        Ok(())
    }

    /// Makes the buffers of a layout built on the GPU from the geometry's copy, and the plan
    /// of its passes (`passes::surfel_layout`; recorded with the recording's others).
    fn plan_gpu_layout(
        &mut self,
        h: GeometryHandle,
        build_id: u64,
        copy: u64,
        l: GeometryLayout,
        surfels: crate::types::SurfelSettings,
        limit: u32,
    ) -> Result<surfel_layout::Plan> {
        let (t, v) = (l.primitive_count as u64, l.vertex_count as u64);
        let tiles = surfels.surfel_type == SurfelType::Tiles;
        let memory = self.memory;
        let words = memory.create_buffer(
            "surfel layout",
            t * if tiles { 8 } else { 36 },
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
            MemoryKind::Cache,
        )?;
        let made = (|| -> Result<(Buffer, Buffer)> {
            let scratch_words =
                if tiles { surfel_layout::scratch_words(t) } else { surfel_layout::mesh_colors_scratch_words(t, v) };
            let scratch = memory.create_buffer(
                "surfel layout scratch",
                scratch_words * 4,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
                MemoryKind::BuildScratch,
            )?;
            match memory.create_buffer(
                "surfel layout count",
                16,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                MemoryKind::Readback,
            ) {
                Ok(result) => Ok((scratch, result)),
                Err(e) => {
                    memory.destroy_buffer(scratch);
                    Err(e)
                }
            }
        })();
        let (scratch, result) = match made {
            Ok(b) => b,
            Err(e) => {
                memory.destroy_buffer(words);
                return Err(e);
            }
        };
        let st = &mut *self.st;
        let (positions, indices, unit) = (copy, copy + l.index_offset(), surfels.tile_unit_length);
        let plan = if tiles {
            let job = surfel_layout::TilesJob {
                positions,
                indices,
                triangles: l.primitive_count,
                unit,
                limit,
                words: words.address,
                scratch: scratch.address,
                result: result.raw,
                result_address: result.address,
            };
            st.passes.surfel_layout.plan_tiles(&job)
        } else {
            let job = surfel_layout::MeshColorsJob {
                positions,
                indices,
                triangles: l.primitive_count,
                vertices: l.vertex_count,
                unit,
                limit,
                words: words.raw,
                words_address: words.address,
                scratch: scratch.raw,
                scratch_address: scratch.address,
                result: result.raw,
                result_address: result.address,
            };
            st.passes.surfel_layout.plan_mesh_colors(&job)
        };
        self.journal.retire_at_commit(Garbage::Buffer(scratch));
        let surfel_type = surfels.surfel_type;
        st.working_sets[self.ws].readbacks.push(Readback::Counted { geometry: h, build_id, surfel_type, words, result, limit });
        Ok(plan)
    }

    /// Uploads new layouts, gives instances the caches their layouts need (filled with their
    /// initial colour) and runs the container's clear tasks. Before any tracing.
    pub fn update_caches(&mut self, tasks: &[Task]) -> Result<()> {
        let clears: Vec<InstanceHandle> =
            tasks.iter().filter_map(|t| if let Task::ClearCache(c) = t { Some(c.instance) } else { None }).collect();
        let (device, memory, cmd) = (self.device, self.memory, self.cmd);
        let (hazards, journal) = (&mut self.hazards, &mut self.journal);
        let st = &mut *self.st;
        if !st.scene.caches_dirty && clears.is_empty() {
            return Ok(());
        }

        // 1. Layouts: a staging buffer (freed when this ticket is back — layouts are too big
        //    and too rare for the per-frame upload ring) -> device-local buffers.
        let pending: Vec<(GeometryHandle, u64)> = st
            .scene
            .geometries
            .iter()
            .filter_map(|(h, g)| g.pending_layout.as_ref().map(|l| (h, l.words.len() as u64 * 4)))
            .collect();
        if !pending.is_empty() {
            let total: u64 = pending.iter().map(|(_, size)| size.div_ceil(16) * 16).sum();
            let mut staging = memory.create_buffer(
                "surfel layout staging",
                total,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
                MemoryKind::Readback,
            )?;
            let made = Self::upload_layouts(st, journal, memory, cmd, hazards, &pending, &mut staging);
            journal.retire_at_commit(Garbage::Buffer(staging));
            made?;
        }

        // 2. Caches for instances whose geometry has a (new) layout; 3. clears.
        let mut fills: Vec<(u64, u64, [f32; 3])> = Vec::new();
        if st.scene.caches_dirty {
            // Every instance whose geometry has a layout its cache was not made for.
            let mut candidates = Vec::new();
            for (h, rec) in st.scene.instances.iter() {
                let Some(p) = rec.placement else { continue };
                let Some((count, id)) =
                    st.scene.geometries.get(p.geometry).ok().and_then(|g| g.surfel.as_ref()).map(|s| (s.sample_count, s.id))
                else {
                    continue;
                };
                if p.cache.is_some_and(|(_, made_for)| made_for == id) {
                    continue;
                }
                candidates.push(Candidate { handle: h, samples: count as u64, layout_id: id, last_used: rec.last_used });
            }
            // With a budget: the most recently used first, room made by evictions.
            for c in budget::admit(st, journal, candidates) {
                let (h, count, id) = (c.handle, c.samples, c.layout_id);
                let Some(p) = st.scene.instances.get(h)?.placement else { continue };
                let range = st.cache_pool.allocate(memory, count)?;
                journal.allocated_cache(range);
                journal.touch_instance(h, Some(p));
                if let Some((old, _)) = p.cache {
                    st.cache_pool.free_after(st.next_serial, old);
                }
                fills.push((range.address, range.count, p.initial_tile_color));
                if let Some(pl) = st.scene.instances.get_mut(h)?.placement.as_mut() {
                    pl.cache = Some((range, id));
                    pl.evicted = false;
                }
            }
            st.scene.caches_dirty = false;
        }
        for h in clears {
            if let Some(Placement { cache: Some((r, _)), initial_tile_color, .. }) = st.scene.instances.get(h)?.placement {
                fills.push((r.address, r.count, initial_tile_color));
            }
        }
        let ws = &mut st.working_sets[self.ws];
        let mut r = Recording::maintenance(device, cmd, &mut ws.ring, hazards, self.seed);
        for (address, count, color) in fills {
            st.passes.cache_ops.fill(&mut r, address, count, color);
        }
        Ok(())
    }

    /// Copies each pending layout through `staging` into a buffer of its own and makes it the
    /// geometry's surfel layout (the one it replaces waits in the journal).
    #[allow(clippy::too_many_arguments)]
    fn upload_layouts(
        st: &mut State,
        journal: &mut Journal,
        memory: &Memory,
        cmd: &Commands,
        hazards: &mut Hazards,
        pending: &[(GeometryHandle, u64)],
        staging: &mut Buffer,
    ) -> Result<()> {
        hazards.write(cmd, sync::TRANSFER_WRITE);
        let mut offset = 0u64;
        for &(h, size) in pending {
            let buffer = memory.create_buffer(
                "surfel layout",
                size,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
                MemoryKind::Cache,
            )?;
            let g = st.scene.geometries.get_mut(h)?;
            let Some(l) = g.pending_layout.take() else {
                memory.destroy_buffer(buffer);
                continue;
            };
            staging.mapped()[offset as usize..(offset + size) as usize].copy_from_slice(bytemuck::cast_slice(&l.words));
            let region = [vk::BufferCopy { src_offset: offset, dst_offset: 0, size }];
            cmd.copy_buffer(staging.raw, buffer.raw, &region);
            offset += size.div_ceil(16) * 16;
            st.scene.next_layout_id += 1;
            let fresh = SurfelGpu {
                buffer,
                sample_count: l.sample_count,
                surfel_type: l.surfel_type,
                id: st.scene.next_layout_id,
                max_resolution: l.max_resolution,
            };
            let old = g.surfel.replace(fresh);
            journal.replaced(Slot::Surfel(h), old.map(Held::Surfel));
            journal.took_layout(h, l);
        }
        Ok(())
    }
}

impl State {
    /// A ticket came back: builds the surfel layouts of the geometry it read back, or installs
    /// the ones the GPU built. `max_samples` bounds one geometry's cache (see
    /// `cache::layout::build`).
    pub(super) fn finish_readbacks(&mut self, memory: &Memory, ws_index: usize, max_samples: u64) {
        let readbacks = std::mem::take(&mut self.working_sets[ws_index].readbacks);
        for readback in readbacks {
            match readback {
                Readback::Geometry { geometry: h, build_id, buffer } => {
                    if let Ok(g) = self.scene.geometries.get_mut(h) {
                        if let (true, Some(gl), Some(bytes)) = (g.build_id == build_id, g.layout, buffer.mapped_bytes()) {
                            let (positions, triangles) = geometry::read_geometry(bytes, &gl);
                            g.pending_layout = layout::build(&positions, &triangles, &g.input.surfels, max_samples);
                            self.scene.caches_dirty = true;
                        }
                    }
                    // The ticket is complete: nothing on the GPU reads this buffer any more.
                    memory.destroy_buffer(buffer);
                }
                Readback::Counted { geometry: h, build_id, surfel_type, words, result, limit } => {
                    let counted = result
                        .mapped_bytes()
                        .and_then(|b| b.get(..8))
                        .map(|b| (u32::from_le_bytes([b[0], b[1], b[2], b[3]]), u32::from_le_bytes([b[4], b[5], b[6], b[7]])));
                    memory.destroy_buffer(result);
                    let current = self.scene.geometries.get(h).is_ok_and(|g| g.build_id == build_id);
                    // Triangles outnumbering the threshold times the samples: map the geometry
                    // directly instead, one sample per triangle (built again at limit 1).
                    let direct = |samples: u32| {
                        self.scene
                            .geometries
                            .get(h)
                            .ok()
                            .and_then(|g| g.layout.map(|l| (g.input.surfels, l.primitive_count)))
                            .is_some_and(|(s, triangles)| {
                                limit > 1 && samples > 0 && s.maps_directly(triangles as u64, samples as u64)
                            })
                    };
                    match counted {
                        Some((samples, _)) if current && direct(samples) => {
                            self.scene.relayout.push((h, 1));
                            memory.destroy_buffer(words);
                        }
                        Some((samples, max_resolution)) if current && samples > 0 && samples as u64 <= max_samples => {
                            self.install_gpu_layout(h, words, surfel_type, samples, max_resolution);
                        }
                        Some((samples, _)) if current && limit > 1 => {
                            // Samples grow with the limit squared where it binds: scale it by
                            // sqrt(budget / samples) (a saturated count only overestimates),
                            // at least halving; the next recording builds it again.
                            let scale = (max_samples as f64 / samples.max(1) as f64).sqrt();
                            let next = ((limit as f64 * scale).floor() as u32).clamp(1, limit / 2);
                            log::warn!(
                                "surfel layout: {samples} samples at tile_resolution_limit {limit}, over {max_samples}; trying {next}"
                            );
                            self.scene.relayout.push((h, next));
                            memory.destroy_buffer(words);
                        }
                        _ => {
                            if current {
                                log::error!("surfel layout needs more than {max_samples} samples: no cache");
                            }
                            memory.destroy_buffer(words);
                        }
                    }
                }
            }
        }
    }

    /// Makes a GPU-built layout the geometry's (the one it replaces goes once the tickets in
    /// flight are done with it).
    fn install_gpu_layout(
        &mut self,
        h: GeometryHandle,
        words: Buffer,
        surfel_type: SurfelType,
        samples: u32,
        max_resolution: u32,
    ) {
        self.scene.next_layout_id += 1;
        let fresh = SurfelGpu {
            buffer: words,
            sample_count: samples,
            surfel_type,
            id: self.scene.next_layout_id,
            max_resolution: max_resolution.max(1),
        };
        let last_issued = self.next_serial.saturating_sub(1);
        if let Ok(g) = self.scene.geometries.get_mut(h) {
            g.pending_layout = None;
            if let Some(old) = g.surfel.replace(fresh) {
                self.deferred.retire(last_issued, Garbage::Buffer(old.buffer));
            }
            self.scene.caches_dirty = true;
        }
    }
}
