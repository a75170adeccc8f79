//! The direct-lighting cache's side of recording: read-backs of new geometry for their surfel
//! layouts, layout uploads, per-instance cache allocation and fills, the instance table, and
//! injection with its resolve.
//!
//! Sizing a cache needs the geometry's edge lengths, which live on the GPU. Like BLAS
//! compaction, this never stalls: the ticket that copies a geometry also copies it to a
//! read-back buffer; when that ticket comes back the CPU builds the layout; the next recording
//! uploads it and gives every instance of the geometry its cache. Until then an instance reads
//! as its `initial_tile_color` and injection skips it.
use super::*;
use crate::cache::layout;
use crate::cache::table::{InstanceGpu, HAS_CACHE};
use crate::scene::geometry::SurfelGpu;

impl State {
    /// Frees deferred GPU objects and cache ranges that no in-flight ticket can still use.
    pub(super) fn collect_garbage(&mut self, device: &Device, memory: &Memory) {
        let oldest = self.in_flight().min();
        self.deferred.collect(device, memory, oldest);
        let (free, keep): (Vec<_>, Vec<_>) =
            self.cache_frees.drain(..).partition(|(serial, _)| oldest.map_or(true, |o| o > *serial));
        self.cache_frees = keep;
        for (_, r) in free {
            self.cache_pool.free(r);
        }
    }

    /// A cache range leaves use: freed once the tickets that may touch it are back.
    pub(super) fn free_cache(&mut self, range: CacheRange) {
        self.cache_frees.push((self.next_serial, range));
    }
}

impl Shared {
    /// Copies freshly registered geometry to read-back buffers (after the geometry copies).
    pub(super) fn record_readbacks(
        &self,
        st: &mut State,
        ws_index: usize,
        handles: &[GeometryHandle],
        cmd: vk::CommandBuffer,
        hazards: &mut Hazards,
    ) -> Result<()> {
        if handles.is_empty() {
            return Ok(());
        }
        let d = &self.device.raw;
        hazards.read_write(d, cmd, sync::TRANSFER_READ, sync::TRANSFER_WRITE);
        for &h in handles {
            let g = st.geometries.get(h)?;
            let (Some(copy), Some(l)) = (g.copy.as_ref(), g.layout) else { continue };
            let readback = self.memory.create_buffer(
                "geometry read-back",
                l.total_bytes(),
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
                MemoryKind::Readback,
            )?;
            let region = [vk::BufferCopy { src_offset: 0, dst_offset: 0, size: l.total_bytes() }];
            unsafe { d.cmd_copy_buffer(cmd, copy.raw, readback.raw, &region) };
            let build_id = g.build_id;
            st.working_sets[ws_index].readbacks.push((h, build_id, readback));
        }
        Ok(())
    }

    /// A ticket came back: builds the surfel layouts of the geometry it read back.
    pub(super) fn finish_readbacks(&self, st: &mut State, ws_index: usize) {
        let readbacks = std::mem::take(&mut st.working_sets[ws_index].readbacks);
        for (h, build_id, buffer) in readbacks {
            if let Ok(g) = st.geometries.get_mut(h) {
                if let (true, Some(gl), Some(bytes)) = (g.build_id == build_id, g.layout, buffer.mapped_bytes()) {
                    let (positions, triangles) = layout::read_geometry(bytes, &gl);
                    g.pending_layout = Some(layout::build(&positions, &triangles, &g.input.surfels));
                    st.caches_dirty = true;
                }
            }
            // The ticket is complete: nothing on the GPU reads this buffer any more.
            self.memory.destroy_buffer(buffer);
        }
    }

    /// Uploads new layouts, gives instances the caches their layouts need (filled with their
    /// initial colour) and runs the container's clear tasks. Before any tracing.
    pub(super) fn update_caches(
        &self,
        st: &mut State,
        ws_index: usize,
        cmd: vk::CommandBuffer,
        hazards: &mut Hazards,
        tasks: &[Task],
        serial: u64,
    ) -> Result<()> {
        let clears: Vec<InstanceHandle> =
            tasks.iter().filter_map(|t| if let Task::ClearCache(c) = t { Some(c.instance) } else { None }).collect();
        if !st.caches_dirty && clears.is_empty() {
            return Ok(());
        }
        let device = &self.device;
        let d = &device.raw;

        // 1. Layouts: a staging buffer (freed when this ticket is back — layouts are too big
        //    and too rare for the per-frame upload ring) -> device-local buffers.
        let pending: Vec<GeometryHandle> =
            st.geometries.iter().filter(|(_, g)| g.pending_layout.is_some()).map(|(h, _)| h).collect();
        let bytes: u64 = pending
            .iter()
            .filter_map(|h| {
                st.geometries.get(*h).ok()?.pending_layout.as_ref().map(|l| (l.words.len() as u64 * 4).div_ceil(16) * 16)
            })
            .sum();
        let mut staging = if pending.is_empty() {
            None
        } else {
            hazards.write(d, cmd, sync::TRANSFER_WRITE);
            Some(self.memory.create_buffer(
                "surfel layout staging",
                bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
                MemoryKind::Readback,
            )?)
        };
        let mut offset = 0u64;
        for h in pending {
            let g = st.geometries.get_mut(h)?;
            let Some(l) = g.pending_layout.take() else { continue };
            let Some(staging) = staging.as_mut() else { break };
            let size = l.words.len() as u64 * 4;
            let buffer = self.memory.create_buffer(
                "surfel layout",
                size,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
                MemoryKind::Cache,
            )?;
            staging.mapped()[offset as usize..(offset + size) as usize].copy_from_slice(bytemuck::cast_slice(&l.words));
            let region = [vk::BufferCopy { src_offset: offset, dst_offset: 0, size }];
            unsafe { d.cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region) };
            offset += size.div_ceil(16) * 16;
            st.next_layout_id += 1;
            let id = st.next_layout_id;
            let g = st.geometries.get_mut(h)?;
            let fresh = SurfelGpu {
                buffer,
                sample_count: l.sample_count,
                surfel_type: l.surfel_type,
                id,
                max_resolution: l.max_resolution,
            };
            if let Some(old) = g.surfel.replace(fresh) {
                st.deferred.retire(serial, Garbage::Buffer(old.buffer));
            }
        }
        if let Some(staging) = staging {
            st.deferred.retire(serial, Garbage::Buffer(staging));
        }

        // 2. Caches for instances whose geometry has a (new) layout; 3. clears.
        let mut fills: Vec<(u64, u64, [f32; 3])> = Vec::new();
        if st.caches_dirty {
            let handles: Vec<InstanceHandle> = st.instances.iter().map(|(h, _)| h).collect();
            for h in handles {
                let Some(p) = st.instances.get(h)?.placement else { continue };
                let Some((count, id)) =
                    st.geometries.get(p.geometry).ok().and_then(|g| g.surfel.as_ref()).map(|s| (s.sample_count, s.id))
                else {
                    continue;
                };
                if p.cache.is_some_and(|(_, made_for)| made_for == id) {
                    continue;
                }
                if let Some((old, _)) = p.cache {
                    st.free_cache(old);
                }
                let range = st.cache_pool.allocate(&self.memory, count as u64)?;
                fills.push((range.address, range.count, p.initial_tile_color));
                if let Some(pl) = st.instances.get_mut(h)?.placement.as_mut() {
                    pl.cache = Some((range, id));
                }
            }
            st.caches_dirty = false;
        }
        for h in clears {
            if let Some(Placement { cache: Some((r, _)), initial_tile_color, .. }) = st.instances.get(h)?.placement {
                fills.push((r.address, r.count, initial_tile_color));
            }
        }
        let ws = &mut st.working_sets[ws_index];
        let tlas = ws.tlas.accel.as_ref().map(|a| a.accel).unwrap_or_default();
        let mut r =
            Recording { device, cmd, ring: &mut ws.ring, hazards, tlas, seed: serial as u32, instance_table: 0, floor: false };
        let ops = st.cache_ops.as_ref().expect("created in new");
        for (address, count, color) in fills {
            ops.fill(&mut r, address, count, color);
        }
        Ok(())
    }

    /// Bytes the instance table of this recording needs in the ring.
    pub(super) fn instance_table_bytes(st: &State) -> u64 {
        (st.instances.slot_count().max(1) * std::mem::size_of::<InstanceGpu>()) as u64 + 16
    }

    /// Writes the instance table (one record per instance slot) into the ring.
    pub(super) fn push_instance_table(&self, st: &mut State, ws_index: usize) -> u64 {
        let mut table = vec![InstanceGpu::default(); st.instances.slot_count().max(1)];
        for (h, rec) in st.instances.iter() {
            let (Some(p), Ok(i)) = (rec.placement, st.instances.index_of(h)) else { continue };
            let Ok(g) = st.geometries.get(p.geometry) else { continue };
            let surfel = g.surfel.as_ref();
            let c = p.initial_tile_color;
            let m = p.transform.matrix3;
            let tr = p.transform.translation;
            let copy = g.copy.as_ref().map_or(0, |b| b.address);
            table[i as usize] = InstanceGpu {
                object_to_world: [
                    [m.x_axis.x, m.y_axis.x, m.z_axis.x, tr.x],
                    [m.x_axis.y, m.y_axis.y, m.z_axis.y, tr.y],
                    [m.x_axis.z, m.y_axis.z, m.z_axis.z, tr.z],
                ],
                vertex_addr: copy,
                index_addr: g.layout.filter(|l| l.index_type.is_some()).map_or(0, |l| copy + l.index_offset),
                vertex_stride: g.layout.map_or(12, |l| l.vertex_stride as u32),
                index_size: g.layout.map_or(0, |l| l.index_size() as u32),
                max_resolution: surfel.map_or(1, |s| s.max_resolution),
                pad: 0,
                layout_addr: surfel.map_or(0, |s| s.buffer.address),
                cache_addr: p.cache.map_or(0, |(r, _)| r.address),
                initial_color: [c[0], c[1], c[2], 0.0],
                surfel_type: surfel.map_or(0, |s| s.surfel_type as u32),
                triangle_count: g.layout.map_or(0, |l| l.primitive_count),
                flags: if p.cache.is_some() && surfel.is_some() { HAS_CACHE } else { 0 },
                sample_count: surfel.map_or(0, |s| s.sample_count),
            };
        }
        st.working_sets[ws_index].ring.push(bytemuck::cast_slice(&table), 16).address
    }
}

/// Injection, then the resolve of every cache page in use.
pub(super) fn record_injection(
    r: &mut Recording<'_>,
    inject: &InjectPass,
    ops: &CacheOps,
    pool: &CachePool,
    task: &DirectLightingInjectionTask,
) {
    inject.record(r, task);
    for (address, count) in pool.spans() {
        ops.resolve(r, address, count, task.average_window);
    }
}

/// The launch of a transfer, or None when either instance has no cache yet.
pub(super) fn transfer_job(st: &State, t: &DirectLightTransferTask) -> Option<crate::passes::transfer::TransferJob> {
    let placed = |h: InstanceHandle| -> Option<(u32, Placement)> {
        let p = st.instances.get(h).ok()?.placement?;
        p.cache?;
        Some((st.instances.index_of(h).ok()?, p))
    };
    let (source_index, _) = placed(t.source)?;
    let (target_index, target) = placed(t.target)?;
    let g = st.geometries.get(target.geometry).ok()?;
    let surfel = g.surfel.as_ref()?;
    let r = surfel.max_resolution;
    let samples_per_triangle = match surfel.surfel_type {
        SurfelType::Tiles => r * r,
        SurfelType::MeshColors => (r + 1) * (r + 2) / 2,
    };
    Some(crate::passes::transfer::TransferJob {
        source_index,
        target_index,
        target_triangles: g.layout?.primitive_count,
        samples_per_triangle,
        distance: t.max_distance,
        bilinear: t.enable_bilinear_sampling,
    })
}
