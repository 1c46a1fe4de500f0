//! The traversal's two uses of x86-64 intrinsics, with portable fallbacks elsewhere: cache
//! prefetch hints ([`slice`]) and the bit mask of a lane comparison ([`mask_le`]). Both use
//! SSE, part of the baseline x86-64 target, so no run-time check is needed; the unsafe blocks
//! only call intrinsics on their documented inputs.
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

/// Bit `i` set when `a[i] <= b[i]` (false for NaN), for `W` a multiple of 4 (a lane
/// comparison and its sign mask, `cmpleps` + `movmskps` per four lanes), or lane by lane
/// otherwise.
#[inline(always)]
pub(super) fn mask_le<const W: usize>(a: &[f32; W], b: &[f32; W]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if W.is_multiple_of(4) {
        use core::arch::x86_64::{_mm_cmple_ps, _mm_loadu_ps, _mm_movemask_ps};
        let mut mask = 0u32;
        for (i, (qa, qb)) in a.chunks_exact(4).zip(b.chunks_exact(4)).enumerate() {
            // SAFETY: `qa` and `qb` are slices of exactly four `f32`, so each unaligned
            // 16-byte load reads only their elements; the compare and the mask are SSE, which
            // every x86-64 CPU has.
            let bits = unsafe {
                _mm_movemask_ps(_mm_cmple_ps(
                    _mm_loadu_ps(qa.as_ptr()),
                    _mm_loadu_ps(qb.as_ptr()),
                ))
            };
            mask |= (bits as u32) << (4 * i);
        }
        return mask;
    }
    let mut mask = 0u32;
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        mask |= u32::from(x <= y) << i;
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_le_matches_lane_comparisons() {
        let a = [1.0, f32::NAN, -0.0, 3.0, f32::INFINITY, 2.0, -1.0, 5.0];
        let b = [1.0, 0.0, 0.0, 2.0, f32::INFINITY, f32::NAN, 0.0, 4.0];
        let expect = (0..8).fold(0u32, |m, i| m | u32::from(a[i] <= b[i]) << i);
        assert_eq!(expect, 0b0101_0101);
        assert_eq!(mask_le(&a, &b), expect);
        let (a4, b4) = ([0.0f32, 1.0, 2.0, 3.0], [3.0f32, 2.0, 1.0, 0.0]);
        assert_eq!(mask_le(&a4, &b4), 0b0011);
        assert_eq!(mask_le(&[1.0f32; 3], &[1.0f32, 0.0, 2.0]), 0b101);
    }
}
