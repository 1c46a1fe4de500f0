//! The crate's only use of x86-64 intrinsics, with portable fallbacks elsewhere: cache
//! prefetch hints ([`lines`]), the bit mask of a lane comparison ([`mask_le`]) and a
//! four-lane `f32` vector ([`F32x4`]) for the triangle tests' lane culls. All use SSE, part
//! of the baseline x86-64 target, so no run-time check is needed; the unsafe blocks only call
//! intrinsics on their documented inputs. Plain IEEE operations lane by lane (never fused):
//! every target computes bit-identical lanes.
//!
//! A wide tree over a large mesh does not fit in the cache, and a traversal that waits for
//! each node and leaf on first use spends most of its time in those misses. When a node test
//! finds its hit children, [`lines`] asks for all of their memory at once, so the misses
//! overlap instead of following one another. On x86-64 this is `prefetcht0` (SSE, part of the
//! baseline target, and a safe intrinsic: it never faults, whatever the address); elsewhere it
//! does nothing.

/// Bytes per cache line assumed by the hints (x86-64 and the common Arm cores).
#[cfg(target_arch = "x86_64")]
const LINE: usize = 64;

/// Hints that the `size_of::<T>()` bytes at `item` will be read soon: one `prefetcht0` per
/// cache line on x86-64, nothing elsewhere. The address need not be valid (nothing is read).
#[inline(always)]
pub(crate) fn lines<T>(item: *const T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let start = item.cast::<i8>();
        let mut offset = 0;
        while offset < core::mem::size_of::<T>() {
            // SAFETY: `prefetcht0` needs SSE, which every x86-64 CPU has (baseline of the
            // target), and it never faults or reads into the program, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(offset)) };
            offset += LINE;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = item;
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

/// The first three lanes of `v`, each already in `[0, 2²⁴]` (clamped by the caller), truncated
/// to integers: one `cvttps2dq` on x86-64 (SSE2, baseline), `as` per lane elsewhere. Equal to
/// `v[i] as u32` on that domain.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn truncate3(v: glam::Vec4) -> [usize; 3] {
    use core::arch::x86_64::{__m128, _mm_cvttps_epi32, _mm_storeu_si128};
    let mut out = [0i32; 4];
    // SAFETY: both intrinsics are SSE2, part of the x86-64 baseline; `out` is 16 writable
    // bytes (four `i32`), which is all the unaligned store writes.
    unsafe { _mm_storeu_si128(out.as_mut_ptr().cast(), _mm_cvttps_epi32(__m128::from(v))) };
    [out[0] as usize, out[1] as usize, out[2] as usize]
}

pub mod level;

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
    (@ +, $a:expr, $b:expr) => { $a + $b };
    (@ -, $a:expr, $b:expr) => { $a - $b };
    (@ *, $a:expr, $b:expr) => { $a * $b };
    (@ /, $a:expr, $b:expr) => { $a / $b };
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

    /// Lane `i` (`i < 4`; tests read results through it).
    #[cfg(test)]
    pub(crate) fn lane(self, i: usize) -> f32 {
        #[cfg(target_arch = "x86_64")]
        {
            let mut out = [0.0f32; 4];
            // SAFETY: `out` is four `f32`: the unaligned 16-byte store writes exactly them.
            unsafe { arch::_mm_storeu_ps(out.as_mut_ptr(), self.0) };
            out[i]
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.0[i]
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

    lanewise!(add, _mm_add_ps, +);
    lanewise!(sub, _mm_sub_ps, -);
    lanewise!(mul, _mm_mul_ps, *);
    lanewise!(div, _mm_div_ps, /);

    /// `|x|` lane by lane (the sign bit cleared, as `f32::abs`).
    #[inline(always)]
    pub(crate) fn abs(self) -> Self {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an SSE bitwise and-not with a broadcast constant; no memory access.
        return Self(unsafe { arch::_mm_andnot_ps(arch::_mm_set1_ps(-0.0), self.0) });
        #[cfg(not(target_arch = "x86_64"))]
        return Self(self.0.map(f32::abs));
    }

    /// Bit `i` set when lane `i` of `self` is `>` that of `o` (false when either is NaN).
    #[inline(always)]
    pub(crate) fn gt_bits(self, o: Self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an SSE compare and sign mask of registers; no memory access.
        return unsafe { arch::_mm_movemask_ps(arch::_mm_cmpgt_ps(self.0, o.0)) as u32 };
        #[cfg(not(target_arch = "x86_64"))]
        return (0..4).fold(0u32, |m, i| m | u32::from(self.0[i] > o.0[i]) << i);
    }

    /// Bit `i` set when lane `i` of `self` is `>=` that of `o` (false when either is NaN).
    #[inline(always)]
    pub(crate) fn ge_bits(self, o: Self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an SSE compare and sign mask of registers; no memory access.
        return unsafe { arch::_mm_movemask_ps(arch::_mm_cmpge_ps(self.0, o.0)) as u32 };
        #[cfg(not(target_arch = "x86_64"))]
        return (0..4).fold(0u32, |m, i| m | u32::from(self.0[i] >= o.0[i]) << i);
    }

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

/// Four 3-vectors, one [`F32x4`] per axis, with glam's `Vec3` formulas operation for
/// operation (same order, never fused), so every lane equals the scalar `Vec3` result bit for
/// bit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct V3x4 {
    pub(crate) x: F32x4,
    pub(crate) y: F32x4,
    pub(crate) z: F32x4,
}

impl V3x4 {
    /// Lanes from `[axis][lane]` arrays.
    #[inline(always)]
    pub(crate) fn load(p: &[[f32; 4]; 3]) -> Self {
        Self {
            x: F32x4::load(&p[0]),
            y: F32x4::load(&p[1]),
            z: F32x4::load(&p[2]),
        }
    }

    /// The same vector in every lane.
    #[inline(always)]
    pub(crate) fn splat(v: glam::Vec3) -> Self {
        Self {
            x: F32x4::splat(v.x),
            y: F32x4::splat(v.y),
            z: F32x4::splat(v.z),
        }
    }

    /// `self − o`.
    #[inline(always)]
    pub(crate) fn sub(self, o: Self) -> Self {
        Self {
            x: self.x.sub(o.x),
            y: self.y.sub(o.y),
            z: self.z.sub(o.z),
        }
    }

    /// `Vec3::dot`: `(x·x') + (y·y') + (z·z')`.
    #[inline(always)]
    pub(crate) fn dot(self, o: Self) -> F32x4 {
        self.x.mul(o.x).add(self.y.mul(o.y)).add(self.z.mul(o.z))
    }

    /// `Vec3::cross`: `(y·z' − y'·z, z·x' − z'·x, x·y' − x'·y)`.
    #[inline(always)]
    pub(crate) fn cross(self, o: Self) -> Self {
        Self {
            x: self.y.mul(o.z).sub(o.y.mul(self.z)),
            y: self.z.mul(o.x).sub(o.z.mul(self.x)),
            z: self.x.mul(o.y).sub(o.x.mul(self.y)),
        }
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
                let q = va.div(vb).add(va.abs());
                let want_q: [f32; 4] = core::array::from_fn(|i| a4[i] / b4[i] + a4[i].abs());
                let (gt, ge) = (q.gt_bits(va), q.ge_bits(va));
                for i in 0..4 {
                    assert_eq!(gt >> i & 1 == 1, want_q[i] > a4[i], "{a4:?} {b4:?} gt {i}");
                    assert_eq!(ge >> i & 1 == 1, want_q[i] >= a4[i], "{a4:?} {b4:?} ge {i}");
                }
                for (i, &e) in expect.iter().enumerate() {
                    assert_eq!(bits >> i & 1 == 1, e < 0.0, "{a4:?} {b4:?} lane {i}");
                    assert_eq!(bits >> (4 + i) & 1 == 1, e > 0.0, "{a4:?} {b4:?} lane {i}");
                }
            }
        }
    }

    /// `V3x4::dot` and `cross` equal glam's scalar `Vec3` methods bit for bit.
    #[test]
    fn v3x4_matches_glam_bit_for_bit() {
        use glam::Vec3;
        let mut state = 0x1234_5678_u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            f32::from_bits((state >> 32) as u32 & 0x7fff_ffff) * 1e-30 - 3.0
        };
        for _ in 0..500 {
            let a: [Vec3; 4] = core::array::from_fn(|_| Vec3::new(next(), next(), next()));
            let b: [Vec3; 4] = core::array::from_fn(|_| Vec3::new(next(), next(), next()));
            let lanes =
                |v: &[Vec3; 4]| V3x4::load(&[v.map(|p| p.x), v.map(|p| p.y), v.map(|p| p.z)]);
            let (va, vb) = (lanes(&a), lanes(&b));
            let c = va.cross(vb);
            let d = va.sub(vb).dot(c);
            for i in 0..4 {
                let want_c = a[i].cross(b[i]);
                let want_d = (a[i] - b[i]).dot(want_c);
                assert_eq!(c.x.lane(i).to_bits(), want_c.x.to_bits());
                assert_eq!(c.y.lane(i).to_bits(), want_c.y.to_bits());
                assert_eq!(c.z.lane(i).to_bits(), want_c.z.to_bits());
                assert_eq!(d.lane(i).to_bits(), want_d.to_bits());
            }
        }
    }
}
