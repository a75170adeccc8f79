//! Scene tasks at build time: handle states checked in task order (before anything is
//! recorded), then geometry and instance tasks applied to the registries with the geometry
//! copies recorded.
use super::container::Task;
use super::journal::{Held, Slot};
use super::record::Recorder;
use super::State;
use crate::error::{Error, HandleProblem, Result};
use crate::gpu::deferred::Garbage;
use crate::gpu::device::Limits;
use crate::gpu::memory::{Buffer, MemoryKind};
use crate::gpu::sync;
use crate::passes::geometry_pack::{AlbedoJob, AlphaJob, PackJob, PackMode};
use crate::passes::{Recording, World};
use crate::scene::geometry::{self, BlasState, CopyPlan, GeometryLayout};
use crate::scene::instance::Placement;
use crate::types::*;
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::collections::HashMap;

/// Checks handle states in task order (a register earlier in the container counts), before
/// anything is recorded; render tasks check theirs through their `PassTask`.
pub(super) fn validate_handles(st: &mut State, tasks: &[Task], limits: &Limits) -> Result<()> {
    let mut geometry_registered: HashMap<GeometryHandle, bool> = HashMap::new();
    let mut instance_registered: HashMap<InstanceHandle, bool> = HashMap::new();
    let problem = |field, kind, raw, problem, name: &Option<String>| {
        Err(Error::InvalidHandle { field, kind, raw, problem, name: name.clone() })
    };
    let scene = &st.scene;
    for task in tasks {
        match task {
            Task::Geometry(t) => {
                let g = scene.geometries.get(t.handle).map_err(|e| e.for_field("GeometryTask.handle"))?;
                let registered = *geometry_registered.entry(t.handle).or_insert(g.registered());
                match t.operation {
                    TaskOperation::Register if registered => {
                        return problem(
                            "GeometryTask.handle",
                            GeometryHandle::KIND,
                            t.handle.0,
                            HandleProblem::AlreadyRegistered,
                            &g.name,
                        )
                    }
                    TaskOperation::Update if !registered => {
                        return problem(
                            "GeometryTask.handle",
                            GeometryHandle::KIND,
                            t.handle.0,
                            HandleProblem::NotRegistered,
                            &g.name,
                        )
                    }
                    TaskOperation::Update => {
                        if let Some(old) = g.layout.filter(|l| l.allow_update) {
                            let new = GeometryLayout::of(&t.input)?;
                            if !t.input.allow_update
                                || new.primitive_count != old.primitive_count
                                || new.vertex_count != old.vertex_count
                                || new.component_count != old.component_count
                            {
                                return Err(Error::invalid(
                                    "GeometryTask.input",
                                    format!(
                                        "an update of allow_update geometry {:#x}{} must keep allow_update, its parts and their vertex and triangle counts (the BLAS is refitted)",
                                        t.handle.0,
                                        g.label()
                                    ),
                                ));
                            }
                        }
                    }
                    _ => {}
                }
                geometry_registered.insert(t.handle, true);
            }
            Task::Instance(t) => {
                let rec = scene.instances.get(t.handle).map_err(|e| e.for_field("InstanceTask.handle"))?;
                let registered = *instance_registered.entry(t.handle).or_insert(rec.placement.is_some());
                match t.operation {
                    InstanceOperation::Register if registered => {
                        return problem(
                            "InstanceTask.handle",
                            InstanceHandle::KIND,
                            t.handle.0,
                            HandleProblem::AlreadyRegistered,
                            &rec.name,
                        )
                    }
                    InstanceOperation::Update | InstanceOperation::Remove if !registered => {
                        return problem(
                            "InstanceTask.handle",
                            InstanceHandle::KIND,
                            t.handle.0,
                            HandleProblem::NotRegistered,
                            &rec.name,
                        )
                    }
                    _ => {}
                }
                if t.operation != InstanceOperation::Remove {
                    // Shaders find an instance's record by its 24-bit TLAS custom index.
                    if scene.instances.index_of(t.handle)? >= 1 << 24 {
                        return Err(Error::invalid("InstanceTask.handle", "its slot is beyond the TLAS's 24-bit custom index"));
                    }
                    let g = scene.geometries.get(t.input.geometry).map_err(|e| e.for_field("InstanceTask.input.geometry"))?;
                    if !*geometry_registered.get(&t.input.geometry).unwrap_or(&g.registered()) {
                        return problem(
                            "InstanceTask.input.geometry",
                            GeometryHandle::KIND,
                            t.input.geometry.0,
                            HandleProblem::NotRegistered,
                            &g.name,
                        );
                    }
                }
                instance_registered.insert(t.handle, t.operation != InstanceOperation::Remove);
            }
            Task::ClearCache(t) => {
                scene.instances.get(t.instance).map_err(|e| e.for_field("ClearCacheTask.instance"))?;
            }
            Task::BvhBuild(_) | Task::Render(_) => {}
        }
    }
    if !instance_registered.is_empty() {
        let placed =
            scene.instances.iter().filter(|(h, r)| instance_registered.get(h).copied().unwrap_or(r.placement.is_some())).count()
                as u64;
        if placed > limits.max_instance_count {
            return Err(Error::invalid(
                "InstanceTask",
                format!("{placed} instances would exceed the device's maxInstanceCount {}", limits.max_instance_count),
            ));
        }
    }
    let world = World {
        scene: &st.scene,
        cache_pool: &st.cache_pool,
        denoisers: &mut st.denoisers,
        many_lights: &mut st.many_lights,
        denoise_temps: &mut st.denoise_temps,
        denoise_guides: &mut st.denoise_guides,
        view_inputs: Default::default(),
        serial: 0,
        limits,
        relight_cursor: &mut st.relight_cursor,
    };
    for task in tasks {
        if let Task::Render(r) = task {
            r.describe().check(&world)?;
        }
    }
    Ok(())
}

impl Recorder<'_> {
    /// Applies geometry and instance tasks to the registries and records the geometry copies
    /// (and the read-backs of geometry that needs a surfel layout).
    pub fn apply_scene_tasks(&mut self, tasks: &[Task]) -> Result<()> {
        // One staging buffer holds every geometry task's engine regions; it is freed when the
        // ticket is back (or at once if this build fails).
        let mut plans = Vec::new();
        let mut staging_bytes = 0u64;
        for task in tasks {
            if let Task::Geometry(t) = task {
                let plan = CopyPlan::of(&t.input)?;
                let base = staging_bytes;
                staging_bytes = base
                    .checked_add(plan.staging_bytes)
                    .and_then(|b| b.checked_next_multiple_of(16))
                    .ok_or_else(|| Error::invalid("GeometryTask", "this container's geometry staging overflows"))?;
                plans.push((plan, base));
            }
        }
        let staging = if plans.is_empty() {
            None
        } else {
            Some(self.memory.create_buffer(
                "geometry staging",
                staging_bytes,
                vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
                MemoryKind::Readback,
            )?)
        };
        let applied = self.apply_with_staging(tasks, &plans, staging.as_ref());
        if let Some(s) = staging {
            self.journal.retire_at_commit(Garbage::Buffer(s));
        }
        applied
    }

    fn apply_with_staging(&mut self, tasks: &[Task], plans: &[(CopyPlan, u64)], staging: Option<&Buffer>) -> Result<()> {
        let cmd = self.cmd;
        if let Some(s) = staging {
            self.hazards.write(cmd, sync::TRANSFER_WRITE);
            for (plan, base) in plans {
                plan.record_staging(cmd, s.raw, *base);
            }
        }
        let mut read_back: Vec<GeometryHandle> = Vec::new();
        let mut packs: Vec<(GeometryHandle, usize)> = Vec::new();
        let mut next_plan = 0;
        for task in tasks {
            match task {
                Task::Geometry(t) => {
                    let layout = plans[next_plan].0.layout;
                    packs.push((t.handle, next_plan));
                    next_plan += 1;
                    let record = self.st.scene.geometries.get(t.handle)?;
                    let (meta, meta_name) = (record.meta(), record.name.clone());
                    let copy = geometry::create_copy(self.memory, &layout)?;
                    if let Some(name) = &meta_name {
                        self.device.name(copy.raw, &format!("geometry copy {name}"));
                    }
                    let st = &mut *self.st;
                    self.journal.touch_geometry(t.handle, meta);
                    let g = st.scene.geometries.get_mut(t.handle)?;
                    let old = g.copy.replace(copy);
                    self.journal.replaced(Slot::Copy(t.handle), old.map(Held::Buffer));
                    g.layout = Some(layout);
                    g.input = t.input.clone();
                    let refit = t.operation == TaskOperation::Update && layout.allow_update && g.blas.is_some();
                    if refit {
                        g.needs_refit = true;
                        st.scene.refit_queue.push(t.handle);
                    } else {
                        read_back.retain(|h| *h != t.handle);
                        read_back.push(t.handle);
                        g.build_id += 1;
                        g.compacted_size = None;
                        if g.blas.is_none() {
                            g.state = BlasState::Queued;
                        }
                        if !st.scene.build_queue.contains(&t.handle) {
                            st.scene.build_queue.push_back(t.handle);
                        }
                    }
                }
                Task::Instance(t) => self.apply_instance_task(t)?,
                _ => {}
            }
        }
        if let Some(s) = staging {
            self.record_packs(&packs, plans, s)?;
        }
        self.record_readbacks(&read_back)
    }

    /// Packs this recording's copies from staging (`passes::geometry_pack`), bad triangles
    /// counted per geometry task into the working set's host-visible counters, read when the
    /// ticket is back.
    fn record_packs(&mut self, packs: &[(GeometryHandle, usize)], plans: &[(CopyPlan, u64)], staging: &Buffer) -> Result<()> {
        let n = packs.len() as u32;
        let counters = self.ensure_index_counters(n)?;
        let (device, cmd) = (self.device, self.cmd);
        self.hazards.write(cmd, sync::TRANSFER_WRITE);
        cmd.fill_buffer(counters, 0, n as u64 * 4, 0);
        let st = &mut *self.st;
        let ws = &mut st.working_sets[self.ws];
        let base = ws.index_counters.as_ref().map_or(0, |b| b.address);
        let (mut jobs, mut alpha_jobs, mut albedo_jobs) = (Vec::new(), Vec::new(), Vec::new());
        for (slot, &(h, plan_index)) in packs.iter().enumerate() {
            let g = st.scene.geometries.get(h)?;
            let Some(copy) = g.copy.as_ref() else { continue };
            let (plan, span) = &plans[plan_index];
            let indices = copy.address + plan.layout.index_offset();
            for p in &plan.parts {
                jobs.push(PackJob {
                    src_vertices: staging.address + span + p.staging_vertices,
                    dst_vertices: copy.address + p.vertex_base as u64 * geometry::VERTEX_STRIDE,
                    src_indices: staging.address + span + p.staging_indices,
                    dst_indices: indices + p.triangle_base as u64 * 12,
                    counter: base + slot as u64 * 4,
                    stride: p.stride,
                    vertex_count: p.vertex_count,
                    triangle_count: p.triangle_count,
                    index_size: p.index_size,
                    first_vertex: p.first_vertex,
                    vertex_base: p.vertex_base,
                    rows: p.rows(),
                    mode: PackMode::Positions,
                });
                // Per-vertex attributes: one word per vertex from staging into their section.
                let attribute = |src: u64, dst: u64, stride: u32, mode: PackMode| PackJob {
                    src_vertices: staging.address + span + src,
                    dst_vertices: copy.address + dst,
                    src_indices: 0,
                    dst_indices: 0,
                    counter: base + slot as u64 * 4,
                    stride,
                    vertex_count: p.vertex_count,
                    triangle_count: 0,
                    index_size: 0,
                    first_vertex: 0,
                    vertex_base: p.vertex_base,
                    rows: p.rows(),
                    mode,
                };
                if p.color_buffer != vk::Buffer::null() {
                    let dst = plan.layout.color_offset() + p.vertex_base as u64 * geometry::COLOR_STRIDE;
                    jobs.push(attribute(p.staging_colors, dst, p.color_stride, PackMode::Colors(p.color_format)));
                }
                if p.uv_buffer != vk::Buffer::null() {
                    let dst = plan.layout.uv_offset() + p.vertex_base as u64 * geometry::UV_STRIDE;
                    jobs.push(attribute(p.staging_uvs, dst, p.uv_stride, PackMode::Uvs(p.uv_format)));
                }
            }
            if let Some(a) = g.input.alpha_test.as_ref() {
                let l = &plan.layout;
                alpha_jobs.push(AlphaJob {
                    texture: a.texture,
                    channel: a.channel,
                    dst: copy.address + l.alpha_offset(),
                    width: l.alpha_width,
                    height: l.alpha_height,
                    pitch_words: l.alpha_pitch_words(),
                });
            }
            if let Some(a) = g.input.albedo_texture.as_ref() {
                let l = &plan.layout;
                albedo_jobs.push(AlbedoJob {
                    texture: a.texture,
                    dst: copy.address + l.albedo_offset(),
                    width: l.albedo_width,
                    height: l.albedo_height,
                });
            }
            ws.index_checks.push((h, copy.raw, slot as u32));
        }
        let mut r = Recording::maintenance(device, cmd, &mut ws.ring, &mut self.hazards, 0);
        st.passes.geometry_pack.record(&mut r, &jobs);
        st.passes.geometry_pack.record_alpha(&mut r, &alpha_jobs);
        st.passes.geometry_pack.record_albedo(&mut r, &albedo_jobs);
        Ok(())
    }

    fn apply_instance_task(&mut self, t: &InstanceTask) -> Result<()> {
        let st = &mut *self.st;
        let mut old = st.scene.instances.get(t.handle)?.placement;
        self.journal.touch_instance(t.handle, old);
        // Both geometries' instance counts change.
        for h in old.map(|o| o.geometry).into_iter().chain((t.operation != InstanceOperation::Remove).then_some(t.input.geometry))
        {
            if let Ok(g) = st.scene.geometries.get(h) {
                self.journal.touch_geometry(h, g.meta());
            }
        }
        // Moving an instance keeps its lighting; a new geometry needs a new cache.
        let keep =
            old.filter(|o| t.operation == InstanceOperation::Update && o.geometry == t.input.geometry).and_then(|o| o.cache);
        if keep.is_some() {
            if let Some(o) = old.as_mut() {
                o.cache = None;
            }
        }
        st.unplace(old);
        let placement = (t.operation != InstanceOperation::Remove).then_some(Placement {
            geometry: t.input.geometry,
            transform: t.input.transform,
            mask: t.input.mask.bits(),
            initial_tile_color: t.input.initial_tile_color,
            albedo: t.input.albedo,
            emission: t.input.emission,
            cache: keep,
            evicted: false,
        });
        st.scene.caches_dirty = true;
        if let Some(p) = placement {
            st.scene.geometries.get_mut(p.geometry)?.instance_refs += 1;
        }
        let serial = st.next_serial;
        let rec = st.scene.instances.get_mut(t.handle)?;
        rec.placement = placement;
        // A new instance counts as used now: the cache budget places it like a fresh one.
        if t.operation == InstanceOperation::Register {
            rec.last_used = serial;
        }
        st.scene.snapshot_dirty = true;
        Ok(())
    }
}
