//! Caller-provided storage.

/// The first `len` elements of `storage`: the part a structure uses. The build checked
/// `len ≤ storage.len()`; should the caller's `AsRef` later return a shorter slice, the whole
/// slice (queries then see fewer entries, never an out-of-bounds index).
#[inline]
pub(crate) fn used<T>(storage: &[T], len: usize) -> &[T] {
    storage.get(..len).unwrap_or(storage)
}
