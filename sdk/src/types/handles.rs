//! Generational handles. A handle packs (context id, generation, slot index); a destroyed,
//! reused or foreign handle is detected and refused, never dereferenced.
use crate::error::{Error, HandleProblem, Result};

macro_rules! handle_type {
    ($(#[$m:meta])* $name:ident, $kind:literal) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
        #[repr(transparent)]
        pub struct $name(pub u64);

        impl $name {
            /// The null handle: never a live one.
            pub const NULL: $name = $name(0);
            #[allow(dead_code)]
            pub(crate) const KIND: &'static str = $kind;
            /// Whether this is the null handle.
            pub fn is_null(self) -> bool { self.0 == 0 }
        }
        impl RawHandle for $name {
            const KIND: &'static str = $kind;
            fn raw(self) -> u64 { self.0 }
            fn from_raw(raw: u64) -> Self { $name(raw) }
        }
    };
}

handle_type!(
    /// A mesh registered with the SDK: its vertex/index copy and its BLAS.
    GeometryHandle, "geometry");
handle_type!(
    /// A placed geometry: a TLAS entry (and, later, its direct-lighting cache).
    InstanceHandle, "instance");
handle_type!(
    /// A denoiser's state: its history images and the previous camera.
    DenoisingContextHandle, "denoising context");
handle_type!(
    /// A many-lights context: the light list and one view's resampling history.
    ManyLightsContextHandle, "many-lights context");

pub(crate) trait RawHandle: Copy {
    const KIND: &'static str;
    fn raw(self) -> u64;
    fn from_raw(raw: u64) -> Self;
}

const INDEX_BITS: u32 = 32;
const GEN_BITS: u32 = 16;

fn pack(ctx: u16, generation: u16, index: u32) -> u64 {
    ((ctx as u64) << (INDEX_BITS + GEN_BITS)) | ((generation as u64) << INDEX_BITS) | index as u64
}

/// The context a raw handle was made by.
pub(crate) fn context_of(raw: u64) -> u16 {
    unpack(raw).0
}

fn unpack(raw: u64) -> (u16, u16, u32) {
    ((raw >> (INDEX_BITS + GEN_BITS)) as u16, (raw >> INDEX_BITS) as u16, raw as u32)
}

struct Slot<T> {
    generation: u16,
    value: Option<T>,
}

/// A generational slot map owned by one context. Generation 0 is never issued, so no live
/// handle is ever 0 (the null handle).
pub(crate) struct Registry<H: RawHandle, T> {
    ctx: u16,
    slots: Vec<Slot<T>>,
    free: Vec<u32>,
    len: usize,
    _h: std::marker::PhantomData<H>,
}

impl<H: RawHandle, T> Registry<H, T> {
    pub fn new(ctx: u16) -> Self {
        Registry { ctx, slots: Vec::new(), free: Vec::new(), len: 0, _h: Default::default() }
    }

    pub fn insert(&mut self, value: T) -> H {
        self.len += 1;
        if let Some(index) = self.free.pop() {
            let slot = &mut self.slots[index as usize];
            slot.value = Some(value);
            return H::from_raw(pack(self.ctx, slot.generation, index));
        }
        let index = self.slots.len() as u32;
        self.slots.push(Slot { generation: 1, value: Some(value) });
        H::from_raw(pack(self.ctx, 1, index))
    }

    /// Classifies a handle without touching it.
    pub fn check(&self, h: H) -> Result<u32> {
        let raw = h.raw();
        let problem = |problem| Error::InvalidHandle { field: "", kind: H::KIND, raw, problem, name: None };
        if raw == 0 {
            return Err(problem(HandleProblem::Null));
        }
        let (ctx, generation, index) = unpack(raw);
        if ctx != self.ctx {
            return Err(problem(HandleProblem::Foreign));
        }
        match self.slots.get(index as usize) {
            Some(slot) if slot.generation == generation && slot.value.is_some() => Ok(index),
            Some(_) => Err(problem(HandleProblem::Destroyed)),
            None => Err(problem(HandleProblem::Foreign)),
        }
    }

    fn stale(h: H) -> Error {
        Error::InvalidHandle { field: "", kind: H::KIND, raw: h.raw(), problem: HandleProblem::Destroyed, name: None }
    }

    pub fn get(&self, h: H) -> Result<&T> {
        let i = self.check(h)?;
        self.slots[i as usize].value.as_ref().ok_or_else(|| Self::stale(h))
    }

    pub fn get_mut(&mut self, h: H) -> Result<&mut T> {
        let i = self.check(h)?;
        self.slots[i as usize].value.as_mut().ok_or_else(|| Self::stale(h))
    }

    pub fn remove(&mut self, h: H) -> Result<T> {
        let i = self.check(h)?;
        let slot = &mut self.slots[i as usize];
        let value = slot.value.take().ok_or_else(|| Self::stale(h))?;
        self.len -= 1;
        // A slot whose 16-bit generation is spent is retired, never reused: a wrapped
        // generation would make a long-dead handle equal a live one.
        if slot.generation < u16::MAX {
            slot.generation += 1;
            self.free.push(i);
        }
        Ok(value)
    }

    /// Number of slots ever used (an upper bound of live slot indices).
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn iter(&self) -> impl Iterator<Item = (H, &T)> {
        self.slots
            .iter()
            .enumerate()
            .filter_map(move |(i, s)| s.value.as_ref().map(|v| (H::from_raw(pack(self.ctx, s.generation, i as u32)), v)))
    }

    /// Slot index of a live handle (the instance's custom index in the TLAS).
    pub fn index_of(&self, h: H) -> Result<u32> {
        self.check(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// After 65,535 reuses a slot retires instead of wrapping its generation: no stale handle
    /// ever becomes valid again.
    #[test]
    fn a_spent_slot_is_retired_not_wrapped() {
        let mut r: Registry<crate::types::GeometryHandle, u32> = Registry::new(1);
        let first = r.insert(0);
        r.remove(first).unwrap();
        let mut last = first;
        for k in 1..u16::MAX as u32 {
            last = r.insert(k);
            assert_eq!(r.index_of(last).unwrap(), 0, "slot 0 is reused while its generation lasts");
            r.remove(last).unwrap();
        }
        let fresh = r.insert(7);
        assert_eq!(r.index_of(fresh).unwrap(), 1, "the spent slot 0 is not reused");
        assert!(r.get(first).is_err() && r.get(last).is_err(), "no old handle of slot 0 is valid");
        assert_eq!(r.slot_count(), 2);
    }

    #[test]
    fn stale_foreign_and_null_handles_are_refused() {
        let mut a: Registry<GeometryHandle, u32> = Registry::new(1);
        let b: Registry<GeometryHandle, u32> = Registry::new(2);
        let h = a.insert(7);
        assert_eq!(*a.get(h).unwrap(), 7);
        assert!(matches!(b.check(h), Err(Error::InvalidHandle { problem: HandleProblem::Foreign, .. })));
        a.remove(h).unwrap();
        let h2 = a.insert(8);
        assert_ne!(h, h2, "a reused slot gets a new generation");
        assert!(matches!(a.check(h), Err(Error::InvalidHandle { problem: HandleProblem::Destroyed, .. })));
        assert!(matches!(a.check(GeometryHandle::NULL), Err(Error::InvalidHandle { problem: HandleProblem::Null, .. })));
        assert_eq!(*a.get(h2).unwrap(), 8);
    }
}
