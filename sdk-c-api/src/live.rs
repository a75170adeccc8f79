//! The opaque objects alive right now. A context or container pointer is checked against this
//! registry on every call, so a destroyed (or never created, or wrong-kind) pointer is
//! `HRT_ERROR_INVALID_HANDLE` instead of a use-after-free: destroying twice, or calling after
//! destroy, is an error the caller can see. (A destroy racing another thread's call on the
//! same object is still the caller's bug: the check and the use are not one step.)
use crate::status::{Failure, HrtStatus};
use std::collections::HashMap;
use std::sync::Mutex;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Kind {
    Context,
    Container,
}

static LIVE: Mutex<Option<HashMap<usize, Kind>>> = Mutex::new(None);

fn with<R>(f: impl FnOnce(&mut HashMap<usize, Kind>) -> R) -> R {
    let mut guard = LIVE.lock().unwrap_or_else(|p| p.into_inner());
    f(guard.get_or_insert_with(HashMap::new))
}

/// A new object of `kind` lives at `p`.
pub(crate) fn register<T>(p: *mut T, kind: Kind) {
    with(|m| m.insert(p as usize, kind));
}

/// `p` is a live object of `kind` (checked, not removed).
pub(crate) fn check<T>(p: *const T, kind: Kind, what: &str) -> Result<(), Failure> {
    if p.is_null() {
        return Err(crate::status::null(what));
    }
    match with(|m| m.get(&(p as usize)).copied()) {
        Some(k) if k == kind => Ok(()),
        Some(k) => Err(Failure(HrtStatus::HRT_ERROR_INVALID_HANDLE, format!("{what} is a {k:?}, not a {kind:?}"))),
        None => Err(Failure(HrtStatus::HRT_ERROR_INVALID_HANDLE, format!("{what} was destroyed or never created"))),
    }
}

/// Takes `p` out of the registry (it is being destroyed); an error if it was not live.
pub(crate) fn unregister<T>(p: *mut T, kind: Kind, what: &str) -> Result<(), Failure> {
    check(p, kind, what)?;
    with(|m| m.remove(&(p as usize)));
    Ok(())
}
