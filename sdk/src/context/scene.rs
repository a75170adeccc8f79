//! Scene tasks at build time: handle states checked in task order (before anything is
//! recorded), then geometry and instance tasks applied to the registries with the geometry
//! copies recorded.
use super::container::Task;
use super::journal::{Held, Slot};
use super::record::Recorder;
use super::State;
use crate::error::{Error, HandleProblem, Result};
use crate::gpu::device::Limits;
use crate::gpu::sync;
use crate::passes::index_check::IndexCheckJob;
use crate::passes::{Recording, World};
use crate::scene::geometry::{self, BlasState, GeometryLayout};
use crate::scene::instance::Placement;
use crate::types::*;
use ash::vk;
use std::collections::HashMap;

/// Checks handle states in task order (a register earlier in the container counts), before
/// anything is recorded; render tasks check theirs through their `PassTask`.
pub(super) fn validate_handles(st: &mut State, tasks: &[Task], limits: &Limits) -> Result<()> {
    let mut geometry_registered: HashMap<GeometryHandle, bool> = HashMap::new();
    let mut instance_registered: HashMap<InstanceHandle, bool> = HashMap::new();
    let problem = |kind, raw, problem| Err(Error::InvalidHandle { kind, raw, problem });
    let scene = &st.scene;
    for task in tasks {
        match task {
            Task::Geometry(t) => {
                let g = scene.geometries.get(t.handle)?;
                let registered = *geometry_registered.entry(t.handle).or_insert(g.registered());
                match t.operation {
                    TaskOperation::Register if registered => {
                        return problem(GeometryHandle::KIND, t.handle.0, HandleProblem::AlreadyRegistered)
                    }
                    TaskOperation::Update if !registered => {
                        return problem(GeometryHandle::KIND, t.handle.0, HandleProblem::NotRegistered)
                    }
                    TaskOperation::Update => {
                        if let Some(old) = g.layout.filter(|l| l.allow_update) {
                            let new = GeometryLayout::of(&t.input)?;
                            if !t.input.allow_update
                                || new.primitive_count != old.primitive_count
                                || new.vertex_count != old.vertex_count
                                || new.index_type != old.index_type
                            {
                                return Err(Error::invalid(
                                    "GeometryTask.input",
                                    "an update of an allow_update geometry must keep allow_update and its vertex, index and triangle counts (the BLAS is refitted)",
                                ));
                            }
                        }
                    }
                    _ => {}
                }
                geometry_registered.insert(t.handle, true);
            }
            Task::Instance(t) => {
                let rec = scene.instances.get(t.handle)?;
                let registered = *instance_registered.entry(t.handle).or_insert(rec.placement.is_some());
                match t.operation {
                    InstanceOperation::Register if registered => {
                        return problem(InstanceHandle::KIND, t.handle.0, HandleProblem::AlreadyRegistered)
                    }
                    InstanceOperation::Update | InstanceOperation::Remove if !registered => {
                        return problem(InstanceHandle::KIND, t.handle.0, HandleProblem::NotRegistered)
                    }
                    _ => {}
                }
                if t.operation != InstanceOperation::Remove {
                    // Shaders find an instance's record by its 24-bit TLAS custom index.
                    if scene.instances.index_of(t.handle)? >= 1 << 24 {
                        return Err(Error::invalid("InstanceTask.handle", "its slot is beyond the TLAS's 24-bit custom index"));
                    }
                    let g = scene.geometries.get(t.input.geometry)?;
                    if !*geometry_registered.get(&t.input.geometry).unwrap_or(&g.registered()) {
                        return problem(GeometryHandle::KIND, t.input.geometry.0, HandleProblem::NotRegistered);
                    }
                }
                instance_registered.insert(t.handle, t.operation != InstanceOperation::Remove);
            }
            Task::ClearCache(t) => {
                scene.instances.get(t.instance)?;
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
    let world = World { scene: &st.scene, cache_pool: &st.cache_pool, denoisers: &mut st.denoisers, limits };
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
        let (d, cmd) = (&self.device.raw, self.cmd);
        let mut copies_declared = false;
        let mut read_back: Vec<GeometryHandle> = Vec::new();
        let mut indexed: Vec<GeometryHandle> = Vec::new();
        for task in tasks {
            match task {
                Task::Geometry(t) => {
                    if !copies_declared {
                        self.hazards.write(d, cmd, sync::TRANSFER_WRITE);
                        copies_declared = true;
                    }
                    let layout = GeometryLayout::of(&t.input)?;
                    let meta = self.st.scene.geometries.get(t.handle)?.meta();
                    let copy = geometry::record_copy(d, self.memory, cmd, &t.input, &layout)?;
                    let st = &mut *self.st;
                    self.journal.touch_geometry(t.handle, meta);
                    let g = st.scene.geometries.get_mut(t.handle)?;
                    let old = g.copy.replace(copy);
                    self.journal.replaced(Slot::Copy(t.handle), old.map(Held::Buffer));
                    g.layout = Some(layout);
                    g.input = t.input;
                    if layout.index_type.is_some() && !indexed.contains(&t.handle) {
                        indexed.push(t.handle);
                    }
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
        self.record_index_checks(&indexed)?;
        self.record_readbacks(&read_back)
    }

    /// Index checks of this recording's copies (`passes::index_check`), counted into the
    /// working set's host-visible counters, read when the ticket is back.
    fn record_index_checks(&mut self, handles: &[GeometryHandle]) -> Result<()> {
        if handles.is_empty() {
            return Ok(());
        }
        let n = handles.len() as u32;
        let counters = self.ensure_index_counters(n)?;
        let (device, cmd) = (self.device, self.cmd);
        let d = &device.raw;
        self.hazards.write(d, cmd, sync::TRANSFER_WRITE);
        unsafe { d.cmd_fill_buffer(cmd, counters, 0, n as u64 * 4, 0) };
        let st = &mut *self.st;
        let ws = &mut st.working_sets[self.ws];
        let base = ws.index_counters.as_ref().map_or(0, |b| b.address);
        let mut jobs = Vec::with_capacity(handles.len());
        for (slot, &h) in handles.iter().enumerate() {
            let g = st.scene.geometries.get(h)?;
            let (Some(copy), Some(l)) = (g.copy.as_ref(), g.layout) else { continue };
            jobs.push(IndexCheckJob {
                indices: copy.address + l.index_offset,
                counter: base + slot as u64 * 4,
                triangle_count: l.primitive_count,
                vertex_count: l.vertex_count,
                index_size: l.index_size() as u32,
            });
            ws.index_checks.push((h, copy.raw, slot as u32));
        }
        let mut r = Recording {
            device,
            cmd,
            ring: &mut ws.ring,
            hazards: &mut self.hazards,
            tlas: vk::AccelerationStructureKHR::null(),
            seed: 0,
            instance_table: 0,
            inline: false,
            floor: false,
        };
        st.passes.index_check.record(&mut r, &jobs);
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
            cache: keep,
        });
        st.scene.caches_dirty = true;
        if let Some(p) = placement {
            st.scene.geometries.get_mut(p.geometry)?.instance_refs += 1;
        }
        st.scene.instances.get_mut(t.handle)?.placement = placement;
        st.scene.snapshot_dirty = true;
        Ok(())
    }
}
