//! Reading the arguments of a C call and writing its results: pointers (NULL is
//! `HRT_ERROR_NULL_POINTER`), arrays, enum values that arrive as integers (an out-of-range
//! value is `HRT_ERROR_INVALID_INPUT`, never undefined behaviour) and strings.
use crate::status::{null, Failure, HrtStatus};
use std::ffi::{c_char, CStr};

pub(crate) fn get<'a, T>(p: *const T, what: &str) -> Result<&'a T, Failure> {
    // SAFETY: the caller passes a valid pointer or NULL (checked).
    unsafe { p.as_ref() }.ok_or_else(|| null(what))
}

pub(crate) fn get_mut<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Failure> {
    // SAFETY: as for `get`.
    unsafe { p.as_mut() }.ok_or_else(|| null(what))
}

/// `n` elements at `p` (NULL is fine when `n` is 0).
pub(crate) fn slice<'a, T>(p: *const T, n: u32, what: &str) -> Result<&'a [T], Failure> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(null(what));
    }
    // SAFETY: the caller promises `n` readable elements.
    Ok(unsafe { std::slice::from_raw_parts(p, n as usize) })
}

/// The SDK enum value of the C integer `v`: `table[v]`.
pub(crate) fn pick<T: Copy>(what: &str, v: u32, table: &[T]) -> Result<T, Failure> {
    table
        .get(v as usize)
        .copied()
        .ok_or_else(|| Failure(HrtStatus::HRT_ERROR_INVALID_INPUT, format!("invalid {what}: {v} is not a valid enum value")))
}

/// A NUL-terminated UTF-8 string argument (lossy: invalid bytes become U+FFFD).
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string.
pub(crate) unsafe fn string_arg(p: *const c_char, what: &str) -> Result<String, Failure> {
    if p.is_null() {
        return Err(null(what));
    }
    Ok(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

/// Writes `s` to `buffer` NUL-terminated, truncated to `capacity` bytes with the NUL (nothing
/// when `buffer` is NULL or `capacity` 0). Returns the full length of `s` in bytes.
///
/// # Safety
/// `buffer` is NULL or has `capacity` writable bytes.
pub(crate) unsafe fn write_string(s: &str, buffer: *mut c_char, capacity: u32) -> u32 {
    if !buffer.is_null() && capacity > 0 {
        let n = s.len().min(capacity as usize - 1);
        unsafe {
            std::ptr::copy_nonoverlapping(s.as_ptr() as *const c_char, buffer, n);
            *buffer.add(n) = 0;
        }
    }
    s.len() as u32
}

/// Writes up to `capacity` of `values` to `out` (when not NULL) and their total number to
/// `count` (required).
///
/// # Safety
/// `out` is NULL or has `capacity` writable elements.
pub(crate) unsafe fn write_list<T: Copy>(values: &[T], out: *mut T, capacity: u32, count: *mut u32) -> Result<(), Failure> {
    *get_mut(count, "count")? = values.len() as u32;
    if !out.is_null() {
        for (i, v) in values.iter().take(capacity as usize).enumerate() {
            unsafe { *out.add(i) = *v };
        }
    }
    Ok(())
}
