//! The SIMD level a query runs at, chosen by the caller at run time: [`Portable`] (the
//! baseline of the target, every CPU) or, on x86-64, [`Avx2Fma`], a token that proves the CPU
//! has AVX2 and FMA. A `no_std` core cannot ask the CPU (`is_x86_feature_detected!` is in
//! `std`), so the caller asks and hands in the token; the kernels behind it are
//! `#[target_feature]` functions, which the compiler inlines into a caller compiled for the
//! same features (the frontend's dispatched query functions) and calls otherwise.
//!
//! Every level computes **bit-identical** results: the same IEEE operations in the same order
//! lane by lane, never a fused multiply-add (the padding arguments of the box test count plain
//! roundings). Only the speed differs.

/// A SIMD level for the 8-wide node test. Sealed: [`Portable`] and, on x86-64, [`Avx2Fma`].
pub trait SimdLevel: Copy + sealed::Sealed {
    /// The slab test of eight boxes at once ([`Slab8`]: the boxes, the ray and the interval),
    /// or `None` when this level has no kernel for it (the caller then runs the portable lane
    /// loop, which gives the same result). Returns the entry distances and the hit mask.
    fn slab8(self, q: &Slab8<'_>) -> Option<([f32; 8], u32)>;

    /// The eight [`order_key`]s of `dist` and the hit lanes `mask`, sorted ascending, or
    /// `None` when this level has no kernel for it (the caller then sorts the same keys,
    /// with the same result: the keys of hit lanes are distinct).
    fn sort_keys8(self, dist: &[f32; 8], mask: u32) -> Option<[u32; 8]>;
}

/// The inputs of [`SimdLevel::slab8`]: eight boxes and a padded ray.
///
/// `lo[axis]`/`hi[axis]` are the near/far bounds of the eight boxes along `axis` (already
/// swapped for a negative direction), `origin_near`/`origin_far` the ray origin shifted by
/// the box padding, `inv_dir` the reciprocal direction and `far_scale` the factor of the far
/// distances. Per lane: `t_enter = max((lo − on)·inv, …, t_min)`,
/// `t_exit = min((hi − of)·inv·far_scale, …, t_max)` with `max(a, b) = a > b ? a : b` (a NaN
/// `a` keeps `b`), and bit `i` of the mask set when `t_enter ≤ t_exit` (false for NaN).
#[derive(Clone, Copy, Debug)]
pub struct Slab8<'a> {
    /// Near bounds per axis (world units).
    pub lo: [&'a [f32; 8]; 3],
    /// Far bounds per axis (world units).
    pub hi: [&'a [f32; 8]; 3],
    /// Origin shifted by the padding toward the near bounds.
    pub origin_near: [f32; 3],
    /// Origin shifted by the padding toward the far bounds.
    pub origin_far: [f32; 3],
    /// Reciprocal direction per axis.
    pub inv_dir: [f32; 3],
    /// Factor applied to every far distance (unitless, ≥ 1).
    pub far_scale: f32,
    /// Start of the interval (ray parameter).
    pub t_min: f32,
    /// End of the interval (ray parameter).
    pub t_max: f32,
}

/// The sort key of child slot `lane` (`< 8`) entered at distance `dist`: `dist`'s bits made
/// monotone (an order-preserving map of `f32` to `u32`: a negative value has all bits
/// flipped, any other its sign bit set), with the low three bits replaced by the slot, so
/// that keys are distinct, ties go to the earlier slot and `key & 7` is the slot; `u32::MAX`
/// for a lane the ray misses (`hit` false). Distances differing only in those three bits
/// may be ordered by slot: only a traversal's visiting order, never an answer, depends on it.
#[inline(always)]
#[must_use]
pub fn order_key(dist: f32, lane: usize, hit: bool) -> u32 {
    let b = dist.to_bits();
    let monotone = b ^ ((((b as i32) >> 31) as u32) | 0x8000_0000);
    if hit {
        (monotone & !7) | (lane as u32 & 7)
    } else {
        u32::MAX
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Portable {}
    #[cfg(target_arch = "x86_64")]
    impl Sealed for super::Avx2Fma {}
}

/// The baseline of the target: the portable lane loops, which the compiler vectorises for
/// the target features of the calling function (SSE2 on plain x86-64).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Portable;

impl SimdLevel for Portable {
    #[inline(always)]
    fn sort_keys8(self, _: &[f32; 8], _: u32) -> Option<[u32; 8]> {
        None
    }

    #[inline(always)]
    fn slab8(self, _: &Slab8<'_>) -> Option<([f32; 8], u32)> {
        None
    }
}

/// Proof that the CPU running the program has AVX2 and FMA: eight-lane node tests in one
/// 256-bit register per plane. Only [`Avx2Fma::new_unchecked`] makes one.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avx2Fma(());

#[cfg(target_arch = "x86_64")]
impl Avx2Fma {
    /// The token.
    ///
    /// # Safety
    /// Every CPU that runs code holding the token must support AVX2 and FMA (in `std`:
    /// `is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")`); the kernels
    /// execute those instructions unconditionally.
    #[must_use]
    pub const unsafe fn new_unchecked() -> Self {
        Self(())
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
impl Avx2Fma {
    /// The token when this CPU has AVX2 and FMA (tests run with `std`).
    pub(crate) fn detect() -> Option<Self> {
        let yes = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma");
        // SAFETY: made only after the run-time check above.
        yes.then(|| unsafe { Self::new_unchecked() })
    }
}

#[cfg(target_arch = "x86_64")]
impl SimdLevel for Avx2Fma {
    #[inline(always)]
    fn sort_keys8(self, dist: &[f32; 8], mask: u32) -> Option<[u32; 8]> {
        // SAFETY: as in `slab8`: the token proves AVX2 and FMA.
        Some(unsafe { sort_keys8_avx2(dist, mask) })
    }

    #[inline(always)]
    fn slab8(self, q: &Slab8<'_>) -> Option<([f32; 8], u32)> {
        // SAFETY: the token exists, so the CPU supports AVX2 and FMA (the contract of
        // `Avx2Fma::new_unchecked`), the only requirement of calling a function compiled for
        // them.
        Some(unsafe {
            slab8_avx2(
                q.lo,
                q.hi,
                q.origin_near,
                q.origin_far,
                q.inv_dir,
                q.far_scale,
                q.t_min,
                q.t_max,
            )
        })
    }
}

/// [`SimdLevel::sort_keys8`] in one 256-bit register: the keys of [`order_key`] lane by lane,
/// then a bitonic sorting network of six compare-exchange steps (unsigned min and max, the
/// partner lane by a shuffle, the larger kept where the network says).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn sort_keys8_avx2(dist: &[f32; 8], mask: u32) -> [u32; 8] {
    use core::arch::x86_64::{
        __m256i, _mm256_and_si256, _mm256_andnot_si256, _mm256_blend_epi32, _mm256_castps_si256,
        _mm256_cmpeq_epi32, _mm256_loadu_ps, _mm256_max_epu32, _mm256_min_epu32, _mm256_or_si256,
        _mm256_permute4x64_epi64, _mm256_set1_epi32, _mm256_setr_epi32, _mm256_shuffle_epi32,
        _mm256_srai_epi32, _mm256_storeu_si256, _mm256_xor_si256,
    };
    // SAFETY: `dist` is eight `f32`: the unaligned 32-byte load reads exactly them.
    let b = _mm256_castps_si256(unsafe { _mm256_loadu_ps(dist.as_ptr()) });
    let sign = _mm256_set1_epi32(i32::MIN);
    let monotone = _mm256_xor_si256(b, _mm256_or_si256(_mm256_srai_epi32::<31>(b), sign));
    let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let keys = _mm256_or_si256(_mm256_and_si256(monotone, _mm256_set1_epi32(!7)), lanes);
    let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let hit = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask as i32), bits), bits);
    // Missed lanes: all ones.
    let mut v = _mm256_or_si256(keys, _mm256_andnot_si256(hit, _mm256_set1_epi32(-1)));
    // Lane i and its partner i ^ d: the smaller to the lanes of `MAX_LANES` clear.
    macro_rules! step {
        ($partner:expr, $max_lanes:literal) => {{
            let p: __m256i = $partner;
            let (lo, hi) = (_mm256_min_epu32(v, p), _mm256_max_epu32(v, p));
            v = _mm256_blend_epi32::<$max_lanes>(lo, hi);
        }};
    }
    // Bitonic: sorted pairs (alternating), sorted quadruples (alternating), then the merge.
    step!(_mm256_shuffle_epi32::<0xB1>(v), 0x66);
    step!(_mm256_shuffle_epi32::<0x4E>(v), 0x3C);
    step!(_mm256_shuffle_epi32::<0xB1>(v), 0x5A);
    step!(_mm256_permute4x64_epi64::<0x4E>(v), 0xF0);
    step!(_mm256_shuffle_epi32::<0x4E>(v), 0xCC);
    step!(_mm256_shuffle_epi32::<0xB1>(v), 0xAA);
    let mut out = [0u32; 8];
    // SAFETY: `out` is eight `u32`: the unaligned 32-byte store writes exactly them.
    unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), v) };
    out
}

/// [`SimdLevel::slab8`] in 256-bit registers, on the fields of a [`Slab8`] (passed one by one:
/// a reference to the record cost ~50 instructions per ray, measured with cachegrind).
#[cfg(target_arch = "x86_64")]
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn slab8_avx2(
    lo: [&[f32; 8]; 3],
    hi: [&[f32; 8]; 3],
    origin_near: [f32; 3],
    origin_far: [f32; 3],
    inv_dir: [f32; 3],
    far_scale: f32,
    t_min: f32,
    t_max: f32,
) -> ([f32; 8], u32) {
    use core::arch::x86_64::{
        _CMP_LE_OQ, _mm256_cmp_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps,
        _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_storeu_ps, _mm256_sub_ps,
    };
    let scale = _mm256_set1_ps(far_scale);
    let mut t_enter = _mm256_set1_ps(t_min);
    let mut t_exit = _mm256_set1_ps(t_max);
    for axis in 0..3 {
        // SAFETY: `lo[axis]` and `hi[axis]` are arrays of eight `f32`: each unaligned 32-byte
        // load reads exactly their elements.
        let (l, h) = unsafe {
            (
                _mm256_loadu_ps(lo[axis].as_ptr()),
                _mm256_loadu_ps(hi[axis].as_ptr()),
            )
        };
        let inv = _mm256_set1_ps(inv_dir[axis]);
        let t_near = _mm256_mul_ps(_mm256_sub_ps(l, _mm256_set1_ps(origin_near[axis])), inv);
        let t_far = _mm256_mul_ps(
            _mm256_mul_ps(_mm256_sub_ps(h, _mm256_set1_ps(origin_far[axis])), inv),
            scale,
        );
        // `maxps(a, b)` is `a > b ? a : b` and `minps(a, b)` is `a < b ? a : b`: the
        // portable loop's selects, NaN handling included.
        t_enter = _mm256_max_ps(t_near, t_enter);
        t_exit = _mm256_min_ps(t_far, t_exit);
    }
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_enter, t_exit)) as u32;
    let mut out = [0.0f32; 8];
    // SAFETY: `out` is eight `f32`: the unaligned 32-byte store writes exactly them.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), t_enter) };
    (out, mask)
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::test_util::{lcg, special_f32};

    /// The AVX2 kernel against the documented lane formula, bit for bit, on values with NaN,
    /// `±∞`, `±0` and subnormals mixed in. Runs where the CPU has AVX2 and FMA (every CI
    /// machine here); elsewhere there is no AVX2 code to run and the test says so.
    /// The AVX2 sort against the keys sorted in scalar code, on every hit mask and on
    /// distances with ties, `±0`, negatives, infinities and values that differ only in the
    /// bits the key drops.
    #[test]
    fn avx2_key_sort_equals_a_scalar_sort() {
        let Some(level) = Avx2Fma::detect() else {
            std::eprintln!("no AVX2+FMA on this CPU: the AVX2 kernel cannot run here");
            return;
        };
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            1.0,
            -2.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            3.5e-41,
        ];
        let mut s = 11u64;
        for case in 0..20_000u32 {
            let dist: [f32; 8] = core::array::from_fn(|i| {
                let r = lcg(&mut s);
                if r < 0.3 {
                    specials[(lcg(&mut s) * 8.0) as usize % 8]
                } else if r < 0.4 {
                    f32::from_bits(1.0f32.to_bits() + i as u32 % 3)
                } else {
                    (lcg(&mut s) - 0.3) * 100.0
                }
            });
            let mask = case % 256;
            let mut want: [u32; 8] =
                core::array::from_fn(|i| order_key(dist[i], i, mask >> i & 1 == 1));
            want.sort_unstable();
            assert_eq!(
                level.sort_keys8(&dist, mask),
                Some(want),
                "{dist:?} {mask:#x}"
            );
            // Hit lanes first, nearest first, each slot once.
            let n = mask.count_ones() as usize;
            let mut seen = 0u32;
            for w in want.windows(2).take(n.saturating_sub(1)) {
                let (a, b) = ((w[0] & 7) as usize, (w[1] & 7) as usize);
                assert!(dist[a] <= dist[b] || (dist[a] - dist[b]).abs() <= dist[a].abs() * 1e-6);
            }
            for k in &want[..n] {
                seen |= 1 << (k & 7);
            }
            assert_eq!(seen, mask);
        }
        assert_eq!(Portable.sort_keys8(&[0.0; 8], 0xFF), None);
    }

    #[test]
    fn avx2_slab_equals_the_lane_formula() {
        let Some(level) = Avx2Fma::detect() else {
            std::eprintln!("no AVX2+FMA on this CPU: the AVX2 kernel cannot run here");
            return;
        };
        let mut s = 7u64;
        let value = |s: &mut u64| {
            let r = lcg(s);
            if r < 0.08 {
                special_f32(s)
            } else {
                (lcg(s) - 0.5) * 20.0
            }
        };
        let mut hits = 0;
        for _ in 0..20_000 {
            let mut planes = [[0.0f32; 8]; 6];
            for p in &mut planes {
                for x in p.iter_mut() {
                    *x = value(&mut s);
                }
            }
            let on: [f32; 3] = core::array::from_fn(|_| value(&mut s));
            let of: [f32; 3] = core::array::from_fn(|_| value(&mut s));
            let inv: [f32; 3] = core::array::from_fn(|_| value(&mut s));
            let (t_min, t_max) = (value(&mut s).abs(), value(&mut s).abs() * 3.0);
            let scale = 1.0 + 1e-6;
            let lo = [&planes[0], &planes[1], &planes[2]];
            let hi = [&planes[3], &planes[4], &planes[5]];
            let q = Slab8 {
                lo,
                hi,
                origin_near: on,
                origin_far: of,
                inv_dir: inv,
                far_scale: scale,
                t_min,
                t_max,
            };
            let (dist, mask) = level.slab8(&q).unwrap();
            for i in 0..8 {
                let (mut enter, mut exit) = (t_min, t_max);
                for a in 0..3 {
                    let near = (lo[a][i] - on[a]) * inv[a];
                    let far = (hi[a][i] - of[a]) * inv[a] * scale;
                    enter = if near > enter { near } else { enter };
                    exit = if far < exit { far } else { exit };
                }
                assert_eq!(dist[i].to_bits(), enter.to_bits(), "lane {i}");
                let hit = enter <= exit;
                assert_eq!(mask >> i & 1 == 1, hit, "lane {i}");
                hits += usize::from(hit);
            }
        }
        assert!(
            (1000..150_000).contains(&hits),
            "both outcomes must occur: {hits} hits of 160000"
        );
        let zero = [0.0; 8];
        let q = Slab8 {
            lo: [&zero; 3],
            hi: [&zero; 3],
            origin_near: [0.0; 3],
            origin_far: [0.0; 3],
            inv_dir: [0.0; 3],
            far_scale: 1.0,
            t_min: 0.0,
            t_max: 1.0,
        };
        assert_eq!(Portable.slab8(&q), None);
    }
}
