//! Handing tickets back: the per-task GPU timings (with their labels) and the per-pass ones,
//! and the tickets still in flight.
use super::{context, HrtContext, HrtTicket};
use crate::args::write_list;
use crate::status::{guard, HrtStatus};
use hybrid_rt as rt;
use std::ffi::c_char;

/// What an HrtTaskTiming measured: one of the HRT_TASK_* values.
pub type HrtTaskKind = u32;

/// Bytes of HrtTaskTiming.label, its NUL included.
pub const HRT_TASK_LABEL_CAPACITY: u32 = 64;

/// One timed task of a ticket (hrt_mark_gpu_task_completed).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtTaskTiming {
    pub kind: HrtTaskKind,
    pub task_index: u32,
    pub gpu_ms: f64,
    /// The label the task was given (hrt_task_container_set_task_label); for HRT_TASK_BVH the
    /// first BVH task's, none for the intervals nested in it (HRT_TASK_BLAS_BUILD,
    /// HRT_TASK_TLAS_BUILD) and HRT_TASK_CACHE_UPDATE, so labelled times add up. NUL-terminated, cut to at most HRT_TASK_LABEL_CAPACITY - 1 bytes
    /// at a UTF-8 character boundary; all zero when the task has no label.
    pub label: [c_char; HRT_TASK_LABEL_CAPACITY as usize],
}

/// Bytes of HrtPassTiming.pass, its NUL included.
pub const HRT_PASS_NAME_CAPACITY: u32 = 32;

/// One timed pass of a task of a ticket (HrtInitSettings.time_passes): its time is part of
/// the task's HrtTaskTiming, so do not add the two.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HrtPassTiming {
    /// The kind of the task the pass belongs to.
    pub kind: HrtTaskKind,
    /// That task's position in its container.
    pub task_index: u32,
    pub gpu_ms: f64,
    /// The pass's name ("temporal", "blur_1", "shadow_blur", ...; the integration guide lists
    /// them), NUL-terminated.
    pub pass: [c_char; HRT_PASS_NAME_CAPACITY as usize],
}

/// `text` NUL-terminated in a fixed array, cut at a UTF-8 character boundary (all zero for
/// none).
fn fixed_c<const N: usize>(text: Option<&str>) -> [c_char; N] {
    let mut out = [0; N];
    let s = text.unwrap_or_default();
    let mut n = s.len().min(N - 1);
    while !s.is_char_boundary(n) {
        n -= 1;
    }
    for (o, b) in out.iter_mut().zip(&s.as_bytes()[..n]) {
        *o = *b as c_char;
    }
    out
}

/// Hands a ticket back after the GPU finished its command buffer. Writes up to `capacity`
/// per-task timings and their total number to `timing_count` (both optional). A ticket
/// returned twice or never issued is HRT_ERROR_UNKNOWN_TICKET.
#[no_mangle]
pub unsafe extern "C" fn hrt_mark_gpu_task_completed(
    ctx: *mut HrtContext,
    ticket: HrtTicket,
    timings: *mut HrtTaskTiming,
    capacity: u32,
    timing_count: *mut u32,
) -> HrtStatus {
    hrt_mark_gpu_task_completed_with_passes(
        ctx,
        ticket,
        timings,
        capacity,
        timing_count,
        std::ptr::null_mut(),
        0,
        std::ptr::null_mut(),
    )
}

/// hrt_mark_gpu_task_completed, and also writes up to `pass_capacity` per-pass timings of the
/// ticket's denoise tasks and their total number to `pass_count` (both optional; none unless
/// the context was created with HrtInitSettings.time_passes).
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn hrt_mark_gpu_task_completed_with_passes(
    ctx: *mut HrtContext,
    ticket: HrtTicket,
    timings: *mut HrtTaskTiming,
    capacity: u32,
    timing_count: *mut u32,
    passes: *mut HrtPassTiming,
    pass_capacity: u32,
    pass_count: *mut u32,
) -> HrtStatus {
    guard(|| {
        let c = context(ctx)?;
        let done = c.ctx.mark_gpu_task_completed(rt::GpuTicket::from_raw(ticket))?;
        if let Some(n) = timing_count.as_mut() {
            *n = done.timings.len() as u32;
        }
        if !timings.is_null() {
            for (i, t) in done.timings.iter().take(capacity as usize).enumerate() {
                *timings.add(i) = HrtTaskTiming {
                    kind: t.kind as u32,
                    task_index: t.task_index,
                    gpu_ms: t.gpu_ms,
                    label: fixed_c(done.label(t)),
                };
            }
        }
        if let Some(n) = pass_count.as_mut() {
            *n = done.pass_timings.len() as u32;
        }
        if !passes.is_null() {
            for (i, t) in done.pass_timings.iter().take(pass_capacity as usize).enumerate() {
                *passes.add(i) = HrtPassTiming {
                    kind: t.kind as u32,
                    task_index: t.task_index,
                    gpu_ms: t.gpu_ms,
                    pass: fixed_c(Some(t.pass)),
                };
            }
        }
        Ok(())
    })
}

/// Serials of the tickets built and not yet handed back: writes up to `capacity` and the total
/// to `count`.
#[no_mangle]
pub unsafe extern "C" fn hrt_tickets_in_flight(
    ctx: *const HrtContext,
    serials: *mut u64,
    capacity: u32,
    count: *mut u32,
) -> HrtStatus {
    guard(|| write_list(&context(ctx)?.ctx.tickets_in_flight(), serials, capacity, count))
}

/// Tickets in flight whose command buffers the GPU has not run to the end (what must finish
/// before hrt_context_destroy succeeds); same conventions as hrt_tickets_in_flight.
#[no_mangle]
pub unsafe extern "C" fn hrt_unfinished_tickets(
    ctx: *const HrtContext,
    serials: *mut u64,
    capacity: u32,
    count: *mut u32,
) -> HrtStatus {
    guard(|| write_list(&context(ctx)?.ctx.unfinished_tickets(), serials, capacity, count))
}

#[cfg(test)]
mod tests {
    use super::{fixed_c, HRT_TASK_LABEL_CAPACITY};
    use std::ffi::c_char;

    fn label_c(label: Option<&str>) -> [c_char; HRT_TASK_LABEL_CAPACITY as usize] {
        fixed_c(label)
    }

    fn text(l: &[std::ffi::c_char]) -> String {
        let bytes: Vec<u8> = l.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
        String::from_utf8(bytes).expect("a label is UTF-8")
    }

    /// Labels are NUL-terminated and cut at a character boundary; no label is all zero.
    #[test]
    fn labels_are_cut_to_the_capacity_at_a_character_boundary() {
        let max = HRT_TASK_LABEL_CAPACITY as usize - 1;
        assert!(label_c(None).iter().all(|&c| c == 0));
        assert!(label_c(Some("")).iter().all(|&c| c == 0));
        let short = label_c(Some("shadows: sun"));
        assert_eq!(text(&short), "shadows: sun");
        assert!(short[12..].iter().all(|&c| c == 0));
        assert_eq!(text(&label_c(Some(&"a".repeat(max)))), "a".repeat(max));
        assert_eq!(text(&label_c(Some(&"a".repeat(max + 10)))), "a".repeat(max));
        // 62 bytes and a 2-byte 'é' across the 63rd: the 'é' goes whole.
        let cut = label_c(Some(&format!("{}é", "a".repeat(max - 1))));
        assert_eq!(text(&cut), "a".repeat(max - 1));
        assert_eq!(cut[max - 1], 0);
        // 3-byte characters: 21 of them fill 63 bytes exactly, a 22nd is left out.
        assert_eq!(text(&label_c(Some(&"€".repeat(22)))), "€".repeat(21));
        assert_eq!(label_c(Some(&"x".repeat(200)))[max], 0);
    }
}
