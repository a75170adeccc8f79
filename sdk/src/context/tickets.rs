//! Tickets: `build_gpu_task` records a container into the engine's command buffer and hands
//! out a ticket; `mark_gpu_task_completed` takes it back once the GPU is done, returns the
//! working set to the pool and reports per-task GPU times.
use super::container::TaskContainer;
use super::journal::Journal;
use super::record::Recorder;
use super::{scene, ExecuteContext};
use crate::error::{Error, Result};
use crate::gpu::commands::Commands;
use crate::gpu::sync::Hazards;
use crate::types::{CompletedTask, GpuTicket, MAX_CACHE_SAMPLES};
use ash::vk;
use std::sync::Arc;

impl ExecuteContext {
    /// Records every task of `container` into `cmd`, which the engine has begun and will end,
    /// submit and wait for itself. On success the container is emptied and a ticket returned.
    ///
    /// On error nothing was recorded into `cmd` and no state changed: a build that fails
    /// halfway (out of memory, say) is undone — registries, queues, caches and GPU objects are
    /// as before — and the container keeps its tasks, so the same build can be tried again.
    /// Whatever the engine recorded into `cmd` before or after the failed call stays valid:
    /// the engine can go on recording, end and submit it as if the call had not been made.
    ///
    /// # Safety
    /// - `cmd` is a command buffer of the context's device, in the recording state, outside a
    ///   render pass, from a pool whose queue family supports compute (and the families of
    ///   `InitSettings::queue_family_indices` where several are given);
    /// - every image, view and buffer the container's tasks name is a live object of that
    ///   device, created with the usage flags the task declares, and in the declared layout
    ///   when the commands execute, with the engine's writes to them made visible by its own
    ///   barriers (the integration guide's barriers section); each stays alive until this
    ///   ticket has come back.
    ///
    /// Every other property of the inputs — formats, sizes, ranges, handles the SDK issued —
    /// is checked, and refused with an error; the handles of Vulkan objects cannot be.
    pub unsafe fn build_gpu_task(&self, container: &mut TaskContainer, cmd: vk::CommandBuffer) -> Result<GpuTicket> {
        if !std::ptr::eq(container.shared.as_ptr(), Arc::as_ptr(&self.shared)) {
            return Err(Error::ForeignContainer);
        }
        if cmd == vk::CommandBuffer::null() {
            return Err(Error::invalid("build_gpu_task command buffer", "is null"));
        }
        let shared = &*self.shared;
        let mut guard = shared.state.lock();
        let st = &mut *guard;
        let ws = st
            .working_sets
            .iter()
            .position(|w| w.in_flight.is_none())
            .ok_or(Error::WorkingSetsExhausted { in_flight: st.working_sets.len() as u32 })?;
        scene::validate_handles(st, &container.tasks, &shared.device.limits)?;
        st.collect_garbage(&shared.device, &shared.memory);

        let serial = st.next_serial;
        let journal = Journal::begin(st, ws);
        // The build records into a list first and into `cmd` only once it has succeeded, so a
        // failure leaves the engine's buffer as it was (see `gpu::commands`).
        let commands = Commands::default();
        let mut recorder = Recorder {
            device: &shared.device,
            memory: &shared.memory,
            st,
            ws,
            serial,
            // Low 32 bits: the shaders' sequences and the checkerboard parity use them.
            seed: container.frame_index.unwrap_or(serial) as u32,
            cmd: &commands,
            hazards: Hazards::after_earlier_submissions(),
            warned_inline: &shared.warned_inline,
            journal,
        };
        let recorded = recorder.record(&container.tasks, &container.labels);
        let Recorder { journal, .. } = recorder;
        if let Err(e) = recorded {
            // Nothing of this build stays: the context is as it was, the container keeps its
            // tasks, and `cmd` never saw a command of it.
            journal.roll_back(st, ws, &shared.device, &shared.memory);
            return Err(e);
        }
        // SAFETY: `cmd` is the engine's, begun and outside a render pass (the function's
        // contract); every object the list names is alive — the build succeeded and keeps what
        // it replaced until this ticket comes back.
        unsafe { commands.replay(&shared.device, cmd) };
        journal.commit(st, serial);
        st.next_serial += 1;
        st.working_sets[ws].in_flight = Some(serial);
        st.working_sets[ws].labels = std::mem::take(&mut container.labels);
        container.tasks.clear();
        container.frame_index = None;
        Ok(GpuTicket { ctx: shared.id, serial })
    }

    /// Hands a ticket back once the GPU has finished its command buffer: returns its working
    /// set to the pool, frees what only it still used, and reports per-task GPU times.
    ///
    /// A ticket whose commands have not run yet is refused and stays in flight:
    ///
    /// ```no_run
    /// # fn poll(ctx: &hybrid_rt::ExecuteContext, ticket: hybrid_rt::GpuTicket) -> hybrid_rt::Result<Option<hybrid_rt::GpuTicket>> {
    /// match ctx.mark_gpu_task_completed(ticket) {
    ///     Ok(done) => println!("{} task timings", done.timings.len()),
    ///     // Not submitted, or the fence was not waited for: keep it, try next frame.
    ///     Err(hybrid_rt::Error::TicketNotComplete { raw, .. }) => return Ok(Some(hybrid_rt::GpuTicket::from_raw(raw))),
    ///     Err(e) => return Err(e),
    /// }
    /// # Ok(None) }
    /// ```
    pub fn mark_gpu_task_completed(&self, ticket: GpuTicket) -> Result<CompletedTask> {
        let mut guard = self.shared.state.lock();
        let st = &mut *guard;
        let unknown = Error::UnknownTicket { serial: ticket.serial };
        if ticket.ctx != self.shared.id {
            return Err(unknown);
        }
        let ws_index = st.working_sets.iter().position(|w| w.in_flight == Some(ticket.serial)).ok_or(unknown)?;
        // Handed back before the GPU ran it (or before the engine waited for it): nothing is
        // recycled, the ticket stays in flight, and the engine can try again with `raw`.
        if !st.working_sets[ws_index].completed(ticket.serial) {
            return Err(Error::TicketNotComplete { serial: ticket.serial, raw: ticket.into_raw() });
        }
        let d = &self.shared.device;
        let ws = &mut st.working_sets[ws_index];
        let mut done = CompletedTask { serial: ticket.serial, labels: std::mem::take(&mut ws.labels), ..Default::default() };
        if let Some(period) = d.timestamp_period_ns {
            match ws.timer.read(&d.raw, period) {
                Ok((tasks, passes)) => (done.timings, done.pass_timings) = (tasks, passes),
                Err(e) => log::warn!("ticket {}: timestamps unavailable ({e:?}); was it really complete?", ticket.serial),
            }
        }
        if !ws.compactions.is_empty() {
            let mut sizes = vec![0u64; ws.compactions.len()];
            // SAFETY: the ticket's marker says its commands completed, so the compaction queries are written.
            let r = unsafe { d.raw.get_query_pool_results(ws.compaction_pool, 0, &mut sizes, vk::QueryResultFlags::TYPE_64) };
            let compactions = std::mem::take(&mut ws.compactions);
            if r.is_ok() {
                for ((h, build_id), size) in compactions.into_iter().zip(sizes) {
                    if let Ok(g) = st.scene.geometries.get_mut(h) {
                        if g.build_id == build_id && size > 0 {
                            g.compacted_size = Some(size);
                            st.scene.compaction_ready.push(h);
                        }
                    }
                }
            }
        }
        let ws = &mut st.working_sets[ws_index];
        let checks = std::mem::take(&mut ws.index_checks);
        if let Some(counters) = ws.index_counters.as_ref().and_then(|b| b.mapped_bytes()) {
            for (h, copy, slot) in checks {
                let at = slot as usize * 4;
                let Some(bytes) = counters.get(at..at + 4) else { continue };
                let bad = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                let Ok(g) = st.scene.geometries.get_mut(h) else { continue };
                if g.copy.as_ref().is_some_and(|c| c.raw == copy) {
                    if bad > 0 {
                        log::warn!(
                            "geometry {:#x}{}: {bad} triangle(s) index outside its parts' vertices; made degenerate",
                            h.0,
                            g.label()
                        );
                    }
                    g.invalid_triangles = bad;
                }
            }
        }
        // The usage flags of the cache budget.
        let ws = &mut st.working_sets[ws_index];
        let slots = std::mem::take(&mut ws.usage_slots) as usize;
        let used: Vec<bool> = match ws.usage_readback.as_ref().and_then(|b| b.mapped_bytes()) {
            Some(bytes) if slots > 0 => bytes.chunks_exact(4).take(slots).map(|w| w != [0; 4]).collect(),
            _ => Vec::new(),
        };
        if !used.is_empty() {
            st.mark_used(&used, ticket.serial);
        }
        // One cache must fit one buffer, and stay within MAX_CACHE_SAMPLES.
        let max_samples = MAX_CACHE_SAMPLES.min(d.limits.max_buffer_size / crate::cache::pool::SAMPLE_BYTES);
        st.finish_readbacks(&self.shared.memory, ws_index, max_samples);
        st.working_sets[ws_index].in_flight = None;
        st.collect_garbage(d, &self.shared.memory);
        Ok(done)
    }
}
