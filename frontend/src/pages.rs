//! Owned arrays for the acceleration structures, backed by 2 MiB pages where the OS gives them.
//!
//! A ray's walk through a BVH touches a few nodes and triangle groups scattered over many
//! megabytes; with 4 KiB pages most of those reads also miss the TLB. Embree asks Linux for
//! transparent huge pages (`madvise(MADV_HUGEPAGE)`) on its large allocations, and on a
//! machine whose THP mode is `madvise` (the common default) it gets them while a plain `Vec`
//! does not. [`PageArray`] does the same for the frontend's trees: the array starts on a
//! 2 MiB boundary and the whole 2 MiB-aligned span of its buffer is advised before any element
//! is written (advice given after the first touch does not change pages already mapped).
//! The advice is a hint: where the OS declines it, or on another OS, the array is an
//! ordinary heap array with the same contents.

use std::ops::{Deref, DerefMut};

/// The huge page size advised for: 2 MiB (x86-64 and aarch64 Linux). Bytes.
pub const HUGE_PAGE: usize = 2 << 20;

/// Arrays smaller than this many bytes are not advised: a quarter of a huge page, below
/// which a 2 MiB page would mostly hold nothing (and few TLB entries are at stake). Bytes.
pub const ADVISE_MIN_BYTES: usize = HUGE_PAGE / 4;

/// `len` copies of a value in one heap buffer whose elements start within one element of a
/// [`HUGE_PAGE`] boundary, advised for huge pages (module docs). Dereferences to `[T]`.
#[derive(Clone)]
pub struct PageArray<T> {
    buf: Vec<T>,
    start: usize,
}

impl<T: Copy> PageArray<T> {
    /// `len` copies of `value`. Arrays of at least [`ADVISE_MIN_BYTES`] over-allocate by two
    /// huge pages of address space, never written: one to start on a boundary, one so that
    /// the advised span reaches past the last element.
    #[must_use]
    pub fn filled(value: T, len: usize) -> Self {
        let size = size_of::<T>().max(1);
        if len.saturating_mul(size) < ADVISE_MIN_BYTES {
            return Self {
                buf: vec![value; len],
                start: 0,
            };
        }
        let pad = (2 * HUGE_PAGE).div_ceil(size);
        let mut buf: Vec<T> = Vec::with_capacity(len + pad);
        let base = buf.as_ptr() as usize;
        let start = (base.next_multiple_of(HUGE_PAGE) - base).div_ceil(size);
        advise_huge(&buf);
        buf.resize(start + len, value);
        Self { buf, start }
    }
}

impl<T> Deref for PageArray<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        self.buf.get(self.start..).unwrap_or(&[])
    }
}

impl<T> DerefMut for PageArray<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        self.buf.get_mut(self.start..).unwrap_or(&mut [])
    }
}

impl<T> AsRef<[T]> for PageArray<T> {
    fn as_ref(&self) -> &[T] {
        self
    }
}

impl<T> AsMut<[T]> for PageArray<T> {
    fn as_mut(&mut self) -> &mut [T] {
        self
    }
}

impl<T: std::fmt::Debug> std::fmt::Debug for PageArray<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// The 2 MiB-aligned span `[lo, hi)` inside `bytes` bytes at address `base`, if any.
fn advised_span(base: usize, bytes: usize) -> Option<(usize, usize)> {
    let end = base + bytes;
    let (lo, hi) = (base.next_multiple_of(HUGE_PAGE), end - end % HUGE_PAGE);
    (hi > lo).then_some((lo, hi))
}

/// Advises the [`advised_span`] of `buf`'s allocated capacity for transparent huge pages.
/// Best effort: the results of the calls are ignored (declined advice leaves 4 KiB pages).
#[cfg(target_os = "linux")]
fn advise_huge<T>(buf: &Vec<T>) {
    debug_assert!(buf.is_empty());
    if let Some((lo, hi)) = advised_span(buf.as_ptr() as usize, buf.capacity() * size_of::<T>()) {
        // SAFETY: `[lo, hi)` lies inside `buf`'s live allocation, in its capacity past every
        // element (`buf` is empty): memory that holds no Rust value. MADV_HUGEPAGE only
        // changes which page size backs the range. MADV_DONTNEED drops the range's current
        // pages (a reused heap block may already be mapped with small pages, which the advice
        // would not change); the next write maps fresh zeroed ones, huge where the kernel
        // can. No value is lost: the elements are written afterwards.
        unsafe {
            let p = lo as *mut libc::c_void;
            libc::madvise(p, hi - lo, libc::MADV_HUGEPAGE);
            libc::madvise(p, hi - lo, libc::MADV_DONTNEED);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge<T>(_: &Vec<T>) {}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every element of a large array lies in the span that was advised (recomputed from the
    /// array's own allocation), and the span starts on a huge page boundary at most one
    /// element before the first element.
    #[test]
    fn large_arrays_lie_in_the_advised_span_and_hold_the_value() {
        for n in [
            ADVISE_MIN_BYTES / 224 + 1,
            HUGE_PAGE / 224 + 1,
            3 * HUGE_PAGE / 224 + 17,
        ] {
            let a = PageArray::filled([7u32; 56], n);
            assert_eq!(a.len(), n);
            assert!(a.iter().all(|x| *x == [7u32; 56]));
            let bytes = a.buf.capacity() * 224;
            let (lo, hi) = advised_span(a.buf.as_ptr() as usize, bytes).expect("a span");
            let (first, end) = (a.as_ptr() as usize, a.as_ptr() as usize + n * 224);
            assert!(
                lo <= first && first < lo + 224,
                "{n}: starts {} past",
                first - lo
            );
            assert!(end <= hi, "{n}: ends {end:#x} past the span's end {hi:#x}");
        }
        assert_eq!(advised_span(HUGE_PAGE + 1, HUGE_PAGE), None);
        assert_eq!(advised_span(0, 2 * HUGE_PAGE + 5), Some((0, 2 * HUGE_PAGE)));
    }

    #[test]
    fn small_and_empty_arrays_are_plain() {
        let a = PageArray::filled(1.5f32, 10);
        assert_eq!(&a[..], &[1.5; 10]);
        let mut e = PageArray::filled(0u8, 0);
        assert!(e.is_empty() && e.as_mut().is_empty());
        let mut b = a.clone();
        b[3] = 2.0;
        assert_eq!((a[3], b[3]), (1.5, 2.0));
    }
}
