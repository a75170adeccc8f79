//! BVH recording: compactions of BLASes built earlier, throttled BLAS builds and refits in one
//! batch, compacted-size queries, and the working set's TLAS.
use super::journal::{Held, Slot};
use super::record::Recorder;
use crate::error::Result;
use crate::gpu::memory::MemoryKind;
use crate::gpu::sync;
use crate::scene::blas::{self, BuildJob};
use crate::scene::geometry::BlasState;
use crate::scene::{instance, tlas};
use crate::types::{BuildHint, GeometryHandle};
use ash::vk;

impl Recorder<'_> {
    /// Compactions, throttled BLAS builds and refits, in one batch where possible.
    pub fn record_blas_work(&mut self, max_builds: u32) -> Result<()> {
        let (device, memory, cmd, serial) = (self.device, self.memory, self.cmd, self.serial);
        let d = &device.raw;
        let st = &mut *self.st;
        let journal = &mut self.journal;

        // Compactions of BLASes built in earlier tickets.
        let ready = std::mem::take(&mut st.scene.compaction_ready);
        let mut declared = false;
        for h in ready {
            let Ok(g) = st.scene.geometries.get_mut(h) else { continue };
            let (Some(size), Some(src)) = (g.compacted_size, g.blas.as_ref().map(|b| b.accel)) else { continue };
            let compact = blas::create(device, memory, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, size, MemoryKind::Blas)?;
            if let Some(name) = &g.name {
                device.name(compact.accel, &format!("BLAS {name}"));
            }
            let dst = compact.accel;
            journal.touch_geometry(h, g.meta());
            g.compacted_size = None;
            let old = g.blas.replace(compact);
            journal.replaced(Slot::Blas(h), old.map(Held::Accel));
            if !declared {
                self.hazards.read_write(cmd, sync::AS_COPY, sync::AS_COPY);
                declared = true;
            }
            let info = vk::CopyAccelerationStructureInfoKHR::default()
                .src(src)
                .dst(dst)
                .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
            cmd.copy_acceleration_structure(info);
            st.scene.snapshot_dirty = true;
        }

        // Plan the batch: refits first (not throttled), then up to max_builds queued builds.
        let mut jobs: Vec<BuildJob> = Vec::new();
        let mut compaction_candidates: Vec<(GeometryHandle, u64, vk::AccelerationStructureKHR)> = Vec::new();
        let mut scratch_total = 0u64;
        let align = device.scratch_alignment;
        let refits = std::mem::take(&mut st.scene.refit_queue);
        for h in refits {
            let Ok(g) = st.scene.geometries.get_mut(h) else { continue };
            if !g.needs_refit {
                continue;
            }
            journal.touch_geometry(h, g.meta());
            g.needs_refit = false;
            let (Some(layout), Some(copy), Some(b)) = (g.layout, g.copy.as_ref(), g.blas.as_ref()) else { continue };
            // Refits keep the flags the BLAS was built with.
            let (geometry, flags, sizes) = blas::describe(device, copy.address, &layout, g.provisional);
            jobs.push(BuildJob {
                geometry,
                flags,
                refit: true,
                dst: b.accel,
                primitive_count: layout.primitive_count,
                scratch_offset: scratch_total,
            });
            scratch_total += sizes.update_scratch_size.div_ceil(align) * align;
            // A deformed mesh (a skinned character) changes what its surroundings see.
            st.scene.changed_at = serial;
        }
        let mut built = 0;
        // Fast first builds of this recording, rebuilt for fast trace at a later one.
        let mut rebuild_later = Vec::new();
        while built < max_builds {
            // New registrations first, then the quality rebuilds of earlier fast builds.
            let (h, rebuild) = match st.scene.build_queue.pop_front() {
                Some(h) => (h, false),
                None => match st.scene.quality_queue.pop_front() {
                    Some((h, id)) if st.scene.geometries.get(h).is_ok_and(|g| g.build_id == id && g.provisional) => (h, true),
                    Some(_) => continue,
                    None => break,
                },
            };
            let Ok(g) = st.scene.geometries.get_mut(h) else { continue };
            let (Some(layout), Some(copy)) = (g.layout, g.copy.as_ref()) else { continue };
            let provisional = !rebuild && layout.build_hint == BuildHint::FastThenTrace && !layout.allow_update;
            let (geometry, flags, sizes) = blas::describe(device, copy.address, &layout, provisional);
            let fresh = blas::create(
                device,
                memory,
                vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                sizes.acceleration_structure_size,
                MemoryKind::Blas,
            )?;
            if let Some(name) = &g.name {
                device.name(fresh.accel, &format!("BLAS {name}"));
            }
            let dst = fresh.accel;
            journal.touch_geometry(h, g.meta());
            let old = g.blas.replace(fresh);
            journal.replaced(Slot::Blas(h), old.map(Held::Accel));
            g.state = BlasState::Ready;
            g.needs_refit = false;
            g.provisional = provisional;
            if provisional {
                rebuild_later.push((h, g.build_id));
            } else if blas::compacts(&layout) {
                compaction_candidates.push((h, g.build_id, dst));
            }
            jobs.push(BuildJob {
                geometry,
                flags,
                refit: false,
                dst,
                primitive_count: layout.primitive_count,
                scratch_offset: scratch_total,
            });
            scratch_total += sizes.build_scratch_size.div_ceil(align) * align;
            st.scene.snapshot_dirty = true;
            built += 1;
        }
        st.scene.quality_queue.extend(rebuild_later);
        if jobs.is_empty() {
            return Ok(());
        }
        let scratch = self.ensure_scratch(scratch_total)?;
        self.hazards.read_write(cmd, sync::AS_BUILD_READ, sync::AS_BUILD_WRITE);
        blas::record_batch(cmd, scratch, &jobs);

        // Ask for compacted sizes; read back when this ticket completes.
        if !compaction_candidates.is_empty() {
            let n = compaction_candidates.len() as u32;
            self.working_set().ensure_compaction_slots(d, n)?;
            self.hazards.read(cmd, sync::AS_BUILD_READ);
            let ws = self.working_set();
            let accels: Vec<_> = compaction_candidates.iter().map(|c| c.2).collect();
            cmd.reset_query_pool(ws.compaction_pool, 0, n);
            cmd.write_compacted_sizes(accels, ws.compaction_pool);
            ws.compactions = compaction_candidates.iter().map(|c| (c.0, c.1)).collect();
        }
        Ok(())
    }

    /// Rebuilds this working set's TLAS when the snapshot changed since it last did.
    /// Builds this working set's TLAS from the snapshot, or refits it (`max_refits`, see
    /// `BvhBuildTask::tlas_max_refits`) when only instance transforms changed since its last
    /// full build.
    pub fn record_tlas(&mut self, max_refits: u32) -> Result<()> {
        let (device, memory, cmd) = (self.device, self.memory, self.cmd);
        let version = self.st.scene.snapshot_version;
        if self.working_set().tlas.version == version {
            return Ok(());
        }
        let count = self.st.scene.snapshot.len() as u32;
        let refittable = max_refits > 0;
        let key = if refittable { tlas::topology_key(&self.st.scene.snapshot) } else { 0 };
        let sizes = tlas::sizes(device, count, refittable);
        let scratch = self.ensure_scratch(sizes.build_scratch_size.max(sizes.update_scratch_size))?;
        self.ensure_ring(self.st.scene.snapshot.len() as u64 * 64 + 256)?;
        let st = &mut *self.st;
        let ws = &mut st.working_sets[self.ws];
        let fresh_storage = match ws.tlas.ensure_storage(device, memory, sizes.acceleration_structure_size)? {
            Some(old) => {
                self.journal.replaced(Slot::Tlas, old.map(Held::Accel));
                true
            }
            None => false,
        };
        let refit = refittable && !fresh_storage && ws.tlas.refit.is_some_and(|r| r.key == key && r.done < max_refits);
        let upload = ws.ring.push(instance::instance_bytes(&st.scene.snapshot), 16);
        self.hazards.read_write(cmd, sync::AS_BUILD_READ, sync::AS_BUILD_WRITE);
        let how = if refit { tlas::Build::Refit } else { tlas::Build::Full { refittable } };
        ws.tlas.record_build(cmd, upload, count, scratch, how);
        ws.tlas.version = version;
        ws.tlas.refit = match (refittable, ws.tlas.refit) {
            (false, _) => None,
            (true, Some(r)) if refit => Some(tlas::Refit { key, done: r.done + 1 }),
            (true, _) => Some(tlas::Refit { key, done: 0 }),
        };
        Ok(())
    }
}
