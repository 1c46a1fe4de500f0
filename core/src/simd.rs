//! The crate's only use of x86-64 intrinsics, with portable fallbacks elsewhere: cache
//! prefetch hints ([`slice`]), the bit mask of a lane comparison ([`mask_le`]) and a
//! four-lane `f32` vector ([`F32x4`]) for the triangle tests' lane culls. All use SSE, part
//! of the baseline x86-64 target, so no run-time check is needed; the unsafe blocks only call
//! intrinsics on their documented inputs. Plain IEEE operations lane by lane (never fused):
//! every target computes bit-identical lanes.
//!
//! A wide tree over a large mesh does not fit in the cache, and a traversal that waits for
//! each node and leaf on first use spends most of its time in those misses. When a node test
//! finds its hit children, [`slice`] asks for all of their memory at once, so the misses
//! overlap instead of following one another. On x86-64 this is `prefetcht0` (SSE, part of the
//! baseline target, and a safe intrinsic: it never faults, whatever the address); elsewhere it
//! does nothing.

/// Bytes per cache line assumed by the hints (x86-64 and the common Arm cores).
#[cfg(target_arch = "x86_64")]
const LINE: usize = 64;

/// Hints that every cache line of `items` will be read soon.
#[inline(always)]
pub(crate) fn slice<T>(items: &[T]) {
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
pub(crate) fn mask_le<const W: usize>(a: &[f32; W], b: &[f32; W]) -> u32 {
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

#[cfg(target_arch = "x86_64")]
use core::arch::x86_64 as arch;

/// Four `f32` lanes: an SSE register on x86-64, an array elsewhere.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F32x4(
    #[cfg(target_arch = "x86_64")] arch::__m128,
    #[cfg(not(target_arch = "x86_64"))] [f32; 4],
);

/// Applies `$op` (an SSE intrinsic on x86-64, else the lane operator `$lane`) to two vectors.
macro_rules! lanewise {
    ($name:ident, $op:ident, $lane:tt) => {
        #[inline(always)]
        pub(crate) fn $name(self, o: Self) -> Self {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an SSE arithmetic or bitwise intrinsic on two registers; SSE is part of
            // the x86-64 baseline.
            return Self(unsafe { arch::$op(self.0, o.0) });
            #[cfg(not(target_arch = "x86_64"))]
            return Self(core::array::from_fn(|i| lanewise!(@ $lane, self.0[i], o.0[i])));
        }
    };
    (@ -, $a:expr, $b:expr) => { $a - $b };
    (@ *, $a:expr, $b:expr) => { $a * $b };
}

impl F32x4 {
    /// The lanes of `a`.
    #[inline(always)]
    pub(crate) fn load(a: &[f32; 4]) -> Self {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `a` is four `f32`: the unaligned 16-byte load reads exactly them (SSE).
        return Self(unsafe { arch::_mm_loadu_ps(a.as_ptr()) });
        #[cfg(not(target_arch = "x86_64"))]
        return Self(*a);
    }

    /// `x` in every lane.
    #[inline(always)]
    pub(crate) fn splat(x: f32) -> Self {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an SSE register broadcast; no memory access.
        return Self(unsafe { arch::_mm_set1_ps(x) });
        #[cfg(not(target_arch = "x86_64"))]
        return Self([x; 4]);
    }

    lanewise!(sub, _mm_sub_ps, -);
    lanewise!(mul, _mm_mul_ps, *);

    /// Bit `i` set when lane `i` is `< 0`, and bit `4 + i` when it is `> 0` (neither for
    /// zero or NaN).
    #[inline(always)]
    pub(crate) fn sign_bits(self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE compares against zero and sign masks of registers; no memory access.
        return unsafe {
            let zero = arch::_mm_setzero_ps();
            let neg = arch::_mm_movemask_ps(arch::_mm_cmplt_ps(self.0, zero));
            let pos = arch::_mm_movemask_ps(arch::_mm_cmpgt_ps(self.0, zero));
            (neg as u32) | ((pos as u32) << 4)
        };
        #[cfg(not(target_arch = "x86_64"))]
        return (0..4).fold(0u32, |m, i| {
            m | u32::from(self.0[i] < 0.0) << i | u32::from(self.0[i] > 0.0) << (4 + i)
        });
    }
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

    /// Every lane operation against the scalar operators, bit for bit (the oracle is plain
    /// `f32` arithmetic), on values that round, overflow, underflow and carry NaN.
    #[test]
    fn f32x4_lanes_equal_scalar_operations() {
        let xs = [
            1.1f32,
            -3.0e38,
            1.0e-40,
            f32::NAN,
            0.0,
            -0.0,
            7.0,
            f32::INFINITY,
        ];
        for a in xs.windows(4) {
            for b in xs.windows(4).rev() {
                let (a4, b4): ([f32; 4], [f32; 4]) = (a.try_into().unwrap(), b.try_into().unwrap());
                let (va, vb) = (F32x4::load(&a4), F32x4::load(&b4));
                let diff = va.sub(vb).mul(F32x4::splat(3.0)).sub(vb.mul(va));
                let expect: [f32; 4] =
                    core::array::from_fn(|i| (a4[i] - b4[i]) * 3.0 - b4[i] * a4[i]);
                let bits = diff.sign_bits();
                for (i, &e) in expect.iter().enumerate() {
                    assert_eq!(bits >> i & 1 == 1, e < 0.0, "{a4:?} {b4:?} lane {i}");
                    assert_eq!(bits >> (4 + i) & 1 == 1, e > 0.0, "{a4:?} {b4:?} lane {i}");
                }
            }
        }
    }
}
