//! Cache-line prefetch hints for the traversal: a hint only, with no effect on any result.
//!
//! A wide tree over a large mesh does not fit in the cache, and a traversal that waits for
//! each node and leaf on first use spends most of its time in those misses. When a node test
//! finds its hit children, [`slice`] asks for all of their memory at once, so the misses
//! overlap instead of following one another. On x86-64 this is `prefetcht0` (SSE, part of the
//! baseline target, and a safe intrinsic: it never faults, whatever the address); elsewhere it
//! does nothing.

/// Bytes per cache line assumed by the hints (x86-64 and the common Arm cores).
const LINE: usize = 64;

/// Hints that every cache line of `items` will be read soon.
#[inline(always)]
pub(super) fn slice<T>(items: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let bytes = core::mem::size_of_val(items);
        let start = items.as_ptr().cast::<i8>();
        let mut offset = 0;
        while offset < bytes {
            // SAFETY: `prefetcht0` needs SSE, which every x86-64 CPU has (baseline of the
            // target), and it never faults or reads into the program, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(offset)) };
            offset += LINE;
        }
        // The last line, when the items do not start on a line boundary.
        if bytes > 0 {
            // SAFETY: as above.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(bytes - 1)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = items;
    }
}
