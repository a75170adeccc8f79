//! The cache budget (`InitSettings::cache_budget_bytes`): which instances hold a
//! direct-lighting cache when not all of them fit.
//!
//! Kickstart RT gives every instance a cache for as long as it lives; a streaming open world
//! then holds the lighting of every surface it ever loaded. Here, with a budget, the caches
//! of the instances unused for longest make room — the policy of a texture streamer: "used"
//! means a camera's injection, a GI or reflection ray or a debug view reached the instance in
//! a ticket that came back (shaders set a per-instance flag, `hrt_mark_used`; the ticket's
//! copy is read when it is handed back, with no wait). An evicted instance reads as its
//! initial colour until it is used again, then gets a new cache at the next build (its
//! lighting comes back through injection and relighting). A cache is only evicted for one
//! used more recently than it, so a working set larger than the budget does not thrash.
use super::journal::Journal;
use super::State;
use crate::cache::pool::SAMPLE_BYTES;
use crate::types::InstanceHandle;

/// What `ExecuteContext::cache_report` says.
pub(super) struct Residency {
    pub resident_bytes: u64,
    pub waiting: u32,
}

impl State {
    /// A ticket (`serial`) came back with these per-slot usage flags: the used instances are
    /// the most recent, and any that lacks a cache gets one at the next build.
    pub(super) fn mark_used(&mut self, used: &[bool], serial: u64) {
        let handles: Vec<InstanceHandle> = self
            .scene
            .instances
            .iter()
            .filter(|(h, _)| self.scene.instances.index_of(*h).is_ok_and(|i| used.get(i as usize).copied().unwrap_or(false)))
            .map(|(h, _)| h)
            .collect();
        for h in handles {
            if let Ok(rec) = self.scene.instances.get_mut(h) {
                rec.last_used = rec.last_used.max(serial);
                if rec.placement.is_some_and(|p| p.cache.is_none()) {
                    self.scene.caches_dirty = true;
                }
            }
        }
    }

    /// Bytes of the caches held now, and instances that wait for room.
    pub(super) fn residency(&self) -> Residency {
        let mut r = Residency { resident_bytes: 0, waiting: 0 };
        for (_, rec) in self.scene.instances.iter() {
            let Some(p) = rec.placement else { continue };
            match p.cache {
                Some((range, _)) => r.resident_bytes += range.count * SAMPLE_BYTES,
                None => {
                    let has_layout = self.scene.geometries.get(p.geometry).ok().and_then(|g| g.surfel.as_ref()).is_some();
                    r.waiting += has_layout as u32;
                }
            }
        }
        r
    }
}

/// An instance that needs a cache this build: its samples, the layout id, and when it was
/// last used.
pub(super) struct Candidate {
    pub handle: InstanceHandle,
    pub samples: u64,
    pub layout_id: u64,
    pub last_used: u64,
}

/// Orders `candidates` (most recently used first) and makes room for each within the budget
/// by evicting caches used less recently; returns the candidates that fit, in order. Without
/// a budget every candidate fits.
pub(super) fn admit(st: &mut State, journal: &mut Journal, mut candidates: Vec<Candidate>) -> Vec<Candidate> {
    if st.cache_budget == 0 {
        return candidates;
    }
    candidates.sort_by_key(|c| std::cmp::Reverse(c.last_used));
    // Resident caches (of current layouts) that may be evicted, oldest first.
    let mut residents: Vec<(InstanceHandle, u64, u64)> = st
        .scene
        .instances
        .iter()
        .filter_map(|(h, rec)| {
            let p = rec.placement?;
            let (range, _) = p.cache?;
            Some((h, range.count * SAMPLE_BYTES, rec.last_used))
        })
        .filter(|(h, _, _)| !candidates.iter().any(|c| c.handle == *h))
        .collect();
    residents.sort_by_key(|r| r.2);
    let mut resident: u64 = residents.iter().map(|r| r.1).sum();
    let mut admitted = Vec::new();
    let mut next_victim = 0;
    for c in candidates {
        let need = c.samples.max(1) * SAMPLE_BYTES;
        while resident + need > st.cache_budget && next_victim < residents.len() && residents[next_victim].2 < c.last_used {
            let (victim, bytes, _) = residents[next_victim];
            next_victim += 1;
            if evict(st, journal, victim) {
                resident -= bytes;
            }
        }
        if resident + need <= st.cache_budget {
            resident += need;
            admitted.push(c);
        }
    }
    admitted
}

/// Takes `h`'s cache (freed once the tickets in flight are done with it).
fn evict(st: &mut State, journal: &mut Journal, h: InstanceHandle) -> bool {
    let Ok(rec) = st.scene.instances.get_mut(h) else { return false };
    let Some(p) = rec.placement.as_mut() else { return false };
    let Some((range, _)) = p.cache else { return false };
    journal.touch_instance(h, Some(*p));
    p.cache = None;
    p.evicted = true;
    let serial = st.next_serial;
    st.cache_pool.free_after(serial, range);
    st.scene.cache_stats.evictions += 1;
    st.scene.cache_stats.evicted_bytes += range.count * SAMPLE_BYTES;
    true
}
