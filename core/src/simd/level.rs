//! The SIMD level a query runs at, chosen by the caller at run time: [`Portable`] (the
//! baseline of the target, every CPU) or, on x86-64, [`Avx2Fma`], a token that proves the CPU
//! has AVX2 and FMA. The caller asks the CPU once and hands in the token
//! ([`Avx2Fma::detect`] without `std`; with it, `is_x86_feature_detected!` and
//! [`Avx2Fma::new_unchecked`]); the kernels behind it are
//! `#[target_feature]` functions, which the compiler inlines into a caller compiled for the
//! same features (the frontend's dispatched query functions) and calls otherwise.
//!
//! Every level computes **bit-identical** results: the same IEEE operations in the same order
//! lane by lane, never a fused multiply-add (the padding arguments of the box test count plain
//! roundings). Only the speed differs.

/// A SIMD level for the 8-wide node test and child sort and the watertight test's lane cull.
/// Sealed: [`Portable`] and, on x86-64, [`Avx2Fma`] (whose token other modules with AVX2
/// kernels of their own also take, such as the watertight test's hit path).
pub trait SimdLevel: Copy + sealed::Sealed {
    /// The slab test of eight boxes at once ([`Slab8`]: the boxes, the ray and the interval),
    /// or `None` when this level has no kernel for it (the caller then runs the portable lane
    /// loop, which gives the same result). Returns the entry distances and the hit mask.
    fn slab8(self, q: &Slab8<'_>) -> Option<([f32; 8], u32)>;

    /// The eight [`order_key`]s of `dist` and the hit lanes `mask`, sorted ascending, or
    /// `None` when this level has no kernel for it (the caller then sorts the same keys,
    /// with the same result: the keys of hit lanes are distinct).
    fn sort_keys8(self, dist: &[f32; 8], mask: u32) -> Option<[u32; 8]>;

    /// The watertight test's four-lane cull ([`crate::triangle::WatertightRay::certain_misses`])
    /// of two groups at once ([`Sheared8`]): bit `i` for lane `i` of the first group, bit
    /// `4 + i` for lane `i` of the second, set when two of the lane's `f32` edge functions
    /// have certain, opposite signs. `None` when this level has no kernel for it (the caller
    /// then culls each group alone, with the same result).
    fn certain_misses8(self, q: &Sheared8<'_>) -> Option<u32>;

    /// The watertight test's "crossed behind the origin" cull of two groups at once
    /// ([`Behind8`]; [`crate::triangle::WatertightRay::behind_misses2`]): bit `i` for lane
    /// `i` of the first group, bit `4 + i` for lane `i` of the second, set when the lane
    /// formula of [`Behind8`] refuses the lane; bit `8 + i`, `12 + i` set when the lane is
    /// *near* (its formula's `|wn|` does not clear `bound_w`: the origin within the `f32`
    /// bound of the plane, or NaN). `None` when this level has no kernel for it (the caller
    /// then evaluates the formula lane by lane, with the same bits).
    fn behind_misses8(self, q: &Behind8<'_>) -> Option<u32>;
}

/// The inputs of [`SimdLevel::behind_misses8`]: two groups of four triangles and a ray, in
/// world axes (the groups as stored: no permutation, which would change the signs of both
/// determinants below alike).
///
/// Per lane, with the vertices `p0, p1, p2`, the origin `o` and the direction `d`, all `f32`
/// and in plain `f32` operations (never fused; sums `(x + y) + z`; `|·|` clears the sign bit;
/// `max(a, b) = a > b ? a : b`):
/// - `a = p0 − o`, `e1 = p1 − p0`, `e2 = p2 − p0`;
/// - the six products `yz = e1_y·e2_z`, `zy = e1_z·e2_y`, `zx = e1_z·e2_x`, `xz = e1_x·e2_z`,
///   `xy = e1_x·e2_y`, `yx = e1_y·e2_x`; the normal `n = (yz − zy, zx − xz, xy − yx)` and its
///   permanent `N = (|yz| + |zy|, |zx| + |xz|, |xy| + |yx|)`;
/// - `wn = a·n`, `w_nn = |a|·N`, `dn = d·n`, `d_nn = |d|·N`;
/// - `m = max(max(s_x, s_y), s_z)` with `s = |e1| + |e2|`, `margin = F·(m·m) + T` and
///   `a1 = (|a_x| + |a_y|) + |a_z|`;
/// - `bound_w = (R·w_nn + margin·a1) + T`, `bound_d = (R·d_nn + margin·dir_l1) + T`, with
///   `R`, `F`, `T` the constants `BEHIND_REL`, `BEHIND_F64_MARGIN`, `BEHIND_TINY` of
///   `crate::tolerance`, derived in `triangle/watertight/behind.rs`;
///
/// and the lane's bit is set when `|wn| > bound_w`, `|dn| > bound_d` and `wn`, `dn` have
/// opposite signs (a NaN anywhere leaves it clear); its *near* bit when `|wn| > bound_w`
/// fails (NaN included).
#[derive(Clone, Copy, Debug)]
pub struct Behind8<'a> {
    /// The first group (bits 0–3; world units).
    pub first: &'a crate::triangle::TriangleLanes,
    /// The second group (bits 4–7).
    pub second: &'a crate::triangle::TriangleLanes,
    /// The ray origin (world units).
    pub origin: [f32; 3],
    /// The ray direction (world units per unit of `t`).
    pub dir: [f32; 3],
    /// `(|d_0| + |d_1|) + |d_2|` of `dir`, in that order (world units per unit of `t`).
    pub dir_l1: f32,
}

/// The inputs of [`SimdLevel::certain_misses8`]: two groups of four triangles and a ray in the
/// watertight test's permuted axes.
///
/// `first[vertex][j]`/`second[vertex][j]` are the four lanes of each group's coordinate along
/// the permuted axis `k_j` (`k_x`, `k_y`, `k_z`). Per lane, vertex by vertex:
/// `z = p_kz − o_kz`, `x = (p_kx − o_kx) − s_x·z`, `y = (p_ky − o_ky) − s_y·z` (never fused),
/// then the edge functions `c_x·b_y − c_y·b_x`, `a_x·c_y − a_y·c_x`, `b_x·a_y − b_y·a_x`
/// of the vertices `a, b, c`; a lane's bit is set when one of them is `< 0` and another
/// `> 0` (zero and NaN count as neither).
#[derive(Clone, Copy, Debug)]
pub struct Sheared8<'a> {
    /// The first group's rows, vertex by vertex, in the permuted axis order (world units).
    pub first: [[&'a [f32; 4]; 3]; 3],
    /// The second group's rows, likewise.
    pub second: [[&'a [f32; 4]; 3]; 3],
    /// The ray origin in the permuted axis order `(o_kx, o_ky, o_kz)` (world units).
    pub origin: [f32; 3],
    /// The shear `(s_x, s_y) = (d_kx/d_kz, d_ky/d_kz)` (unitless).
    pub shear: [f32; 2],
}

/// The inputs of [`SimdLevel::slab8`]: eight boxes and a padded ray.
///
/// `lo[axis]`/`hi[axis]` are the near/far bounds of the eight boxes along `axis` (already
/// swapped for a negative direction), `origin_near`/`origin_far` the ray origin shifted by
/// the box padding, `inv_dir` the reciprocal direction and `inv_far` the reciprocal the far
/// distances use (padded). Per lane: `t_enter = max((lo − on)·inv_dir, …, t_min)`,
/// `t_exit = min((hi − of)·inv_far, …, t_max)` with `max(a, b) = a > b ? a : b` (a NaN
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
    /// Reciprocal direction per axis for the far distances (`inv_dir` scaled outward).
    pub inv_far: [f32; 3],
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
    /// What the crate's own modules ask of a level (not part of the public interface).
    pub trait Sealed: Copy {
        /// This level as the AVX2 + FMA token when it is that level, `None` otherwise: a
        /// module with its own AVX2 kernels (the triangle hit path's end,
        /// `triangle/watertight/avx2.rs`) picks them per level with it, decided at compile
        /// time (each level returns a constant).
        #[cfg(target_arch = "x86_64")]
        fn avx2(self) -> Option<super::Avx2Fma>;
    }
}

/// The baseline of the target: the portable lane loops, which the compiler vectorises for
/// the target features of the calling function (SSE2 on plain x86-64).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Portable;

impl sealed::Sealed for Portable {
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self) -> Option<Avx2Fma> {
        None
    }
}

impl SimdLevel for Portable {
    #[inline(always)]
    fn sort_keys8(self, _: &[f32; 8], _: u32) -> Option<[u32; 8]> {
        None
    }

    #[inline(always)]
    fn slab8(self, _: &Slab8<'_>) -> Option<([f32; 8], u32)> {
        None
    }

    #[inline(always)]
    fn certain_misses8(self, _: &Sheared8<'_>) -> Option<u32> {
        None
    }

    #[inline(always)]
    fn behind_misses8(self, _: &Behind8<'_>) -> Option<u32> {
        None
    }
}

/// Proof that the CPU running the program has AVX2 and FMA: eight-lane node tests in one
/// 256-bit register per plane. Only [`Avx2Fma::detect`] (which asks the CPU) and
/// [`Avx2Fma::new_unchecked`] make one.
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

#[cfg(all(target_arch = "x86_64", not(target_env = "sgx")))]
impl Avx2Fma {
    /// The token when the CPU running this code has AVX2 and FMA and the operating system
    /// saves the 256-bit registers across context switches; `None` otherwise. Asked without
    /// `std`: `cpuid` leaves 0, 1 and 7 and the `XCR0` register (`xgetbv`), the checks
    /// `is_x86_feature_detected!("avx2")` and `("fma")` make. Every call executes `cpuid`,
    /// which serialises the core and, in a virtual machine, traps to the hypervisor (about a
    /// microsecond): ask once and keep the token (`std`'s macro caches its answer).
    #[must_use]
    pub fn detect() -> Option<Self> {
        /// `cpuid` leaf 1, `ecx`: FMA, XSAVE, OSXSAVE (the OS enabled `xsave`/`xgetbv`), AVX.
        const LEAF1_ECX: u32 = (1 << 12) | (1 << 26) | (1 << 27) | (1 << 28);
        /// `cpuid` leaf 7 sub-leaf 0, `ebx`: AVX2.
        const LEAF7_EBX_AVX2: u32 = 1 << 5;
        /// `XCR0`: the OS saves the SSE (bit 1) and AVX (bit 2) register state.
        const XCR0_SSE_AVX: u64 = 0b110;
        if cpuid(0).eax < 7 || cpuid(1).ecx & LEAF1_ECX != LEAF1_ECX {
            return None;
        }
        // SAFETY: `cpuid` leaf 1 reported XSAVE and OSXSAVE just above: the CPU has `xgetbv`
        // (the `xsave` feature `xcr0` is compiled for) and the OS has enabled it, so reading
        // `XCR0` does not fault at any privilege level.
        let xcr0 = unsafe { xcr0() };
        if xcr0 & XCR0_SSE_AVX != XCR0_SSE_AVX || cpuid(7).ebx & LEAF7_EBX_AVX2 == 0 {
            return None;
        }
        // SAFETY: the CPU has AVX2 and FMA and the OS saves their registers (checked above),
        // the token's one requirement.
        Some(unsafe { Self::new_unchecked() })
    }
}

/// `cpuid` leaf `leaf`, sub-leaf 0.
#[cfg(all(target_arch = "x86_64", not(target_env = "sgx")))]
// A safe intrinsic in newer Rust; `unsafe` in the MSRV's.
#[allow(unused_unsafe)]
fn cpuid(leaf: u32) -> core::arch::x86_64::CpuidResult {
    // SAFETY: every x86-64 CPU has `cpuid` (it is in the baseline); it reads no memory, and a
    // leaf above the CPU's highest (leaf 0's `eax`) answers with the highest leaf's values.
    unsafe { core::arch::x86_64::__cpuid_count(leaf, 0) }
}

/// `XCR0`, the register whose bits say which register state the OS saves.
#[cfg(all(target_arch = "x86_64", not(target_env = "sgx")))]
#[target_feature(enable = "xsave")]
fn xcr0() -> u64 {
    // SAFETY: `xgetbv` with `ecx = 0` reads `XCR0`; this function is compiled for (and only
    // called on a CPU with) `xsave`, whose instruction it is.
    unsafe { core::arch::x86_64::_xgetbv(0) }
}

#[cfg(target_arch = "x86_64")]
impl sealed::Sealed for Avx2Fma {
    #[inline(always)]
    fn avx2(self) -> Option<Avx2Fma> {
        Some(self)
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
    fn certain_misses8(self, q: &Sheared8<'_>) -> Option<u32> {
        // SAFETY: as in `slab8`: the token proves AVX2 and FMA.
        Some(unsafe { certain_misses8_avx2(q.first, q.second, q.origin, q.shear) })
    }

    #[inline(always)]
    fn behind_misses8(self, q: &Behind8<'_>) -> Option<u32> {
        // SAFETY: as in `slab8`: the token proves AVX2 and FMA.
        Some(unsafe { behind_misses8_avx2(q) })
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
                q.inv_far,
                q.t_min,
                q.t_max,
            )
        })
    }
}

/// [`SimdLevel::certain_misses8`] in 256-bit registers: the first group's lanes in the low
/// half, the second's in the high half, the operations of [`Sheared8`] lane by lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn certain_misses8_avx2(
    first: [[&[f32; 4]; 3]; 3],
    second: [[&[f32; 4]; 3]; 3],
    origin: [f32; 3],
    shear: [f32; 2],
) -> u32 {
    use core::arch::x86_64::{
        __m256, _CMP_GT_OQ, _CMP_LT_OQ, _mm256_cmp_ps, _mm256_movemask_ps, _mm256_mul_ps,
        _mm256_or_ps, _mm256_set1_ps, _mm256_setzero_ps, _mm256_sub_ps,
    };
    let row = |lo: &[f32; 4], hi: &[f32; 4]| -> __m256 { row8(lo, hi) };
    let o = [
        _mm256_set1_ps(origin[0]),
        _mm256_set1_ps(origin[1]),
        _mm256_set1_ps(origin[2]),
    ];
    let (sx, sy) = (_mm256_set1_ps(shear[0]), _mm256_set1_ps(shear[1]));
    let project = |v: usize| {
        let z = _mm256_sub_ps(row(first[v][2], second[v][2]), o[2]);
        (
            _mm256_sub_ps(
                _mm256_sub_ps(row(first[v][0], second[v][0]), o[0]),
                _mm256_mul_ps(sx, z),
            ),
            _mm256_sub_ps(
                _mm256_sub_ps(row(first[v][1], second[v][1]), o[1]),
                _mm256_mul_ps(sy, z),
            ),
        )
    };
    let ((ax, ay), (bx, by), (cx, cy)) = (project(0), project(1), project(2));
    let edge = |p: __m256, q: __m256, r: __m256, s: __m256| {
        _mm256_sub_ps(_mm256_mul_ps(p, q), _mm256_mul_ps(r, s))
    };
    let e = [
        edge(cx, by, cy, bx),
        edge(ax, cy, ay, cx),
        edge(bx, ay, by, ax),
    ];
    let zero = _mm256_setzero_ps();
    let (mut neg, mut pos) = (zero, zero);
    for x in e {
        // Ordered compares: a NaN edge is neither negative nor positive.
        neg = _mm256_or_ps(neg, _mm256_cmp_ps::<_CMP_LT_OQ>(x, zero));
        pos = _mm256_or_ps(pos, _mm256_cmp_ps::<_CMP_GT_OQ>(x, zero));
    }
    (_mm256_movemask_ps(neg) & _mm256_movemask_ps(pos)) as u32
}

/// Four lanes of one group (`lo`) and four of another (`hi`) in one 256-bit register.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn row8(lo: &[f32; 4], hi: &[f32; 4]) -> core::arch::x86_64::__m256 {
    use core::arch::x86_64::{_mm_loadu_ps, _mm256_castps128_ps256, _mm256_insertf128_ps};
    // SAFETY: `lo` and `hi` are four `f32` each: each unaligned 16-byte load reads exactly
    // them (AVX, which the function's target features enable).
    unsafe {
        _mm256_insertf128_ps::<1>(
            _mm256_castps128_ps256(_mm_loadu_ps(lo.as_ptr())),
            _mm_loadu_ps(hi.as_ptr()),
        )
    }
}

/// [`SimdLevel::behind_misses8`] in 256-bit registers: the first group's lanes in the low
/// half, the second's in the high half, the operations of [`Behind8`] lane by lane (`|·|` an
/// `andnot` of the sign bit, `max` as `maxps`, the opposite signs as the sign bit of
/// `wn ^ dn`, which equals the comparison of signs wherever both magnitudes cleared their
/// bounds: then neither is zero or NaN).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn behind_misses8_avx2(q: &Behind8<'_>) -> u32 {
    use crate::tolerance::{BEHIND_F64_MARGIN, BEHIND_REL, BEHIND_TINY};
    use core::arch::x86_64::{
        __m256, _CMP_GT_OQ, _mm256_add_ps, _mm256_and_ps, _mm256_andnot_ps, _mm256_cmp_ps,
        _mm256_max_ps, _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_sub_ps,
        _mm256_xor_ps,
    };
    let sign = _mm256_set1_ps(-0.0);
    let abs = |x: __m256| _mm256_andnot_ps(sign, x);
    let add = |x: __m256, y: __m256| _mm256_add_ps(x, y);
    let sub = |x: __m256, y: __m256| _mm256_sub_ps(x, y);
    let mul = |x: __m256, y: __m256| _mm256_mul_ps(x, y);
    // Written out (no `array::map`/`from_fn`, which are not always inlined).
    let vertex = |v: usize| {
        [
            row8(&q.first.v[v][0], &q.second.v[v][0]),
            row8(&q.first.v[v][1], &q.second.v[v][1]),
            row8(&q.first.v[v][2], &q.second.v[v][2]),
        ]
    };
    let (p0, p1, p2) = (vertex(0), vertex(1), vertex(2));
    let splat3 = |x: [f32; 3]| {
        [
            _mm256_set1_ps(x[0]),
            _mm256_set1_ps(x[1]),
            _mm256_set1_ps(x[2]),
        ]
    };
    let (o, d) = (splat3(q.origin), splat3(q.dir));
    let diff3 =
        |u: [__m256; 3], v: [__m256; 3]| [sub(u[0], v[0]), sub(u[1], v[1]), sub(u[2], v[2])];
    let (a, e1, e2) = (diff3(p0, o), diff3(p1, p0), diff3(p2, p0));
    // The edges' own terms first (the margin, from `|e1| + |e2|`), so that the edges are dead
    // once the normal's products are taken: fewer live registers, the same operations.
    let s = [
        add(abs(e1[0]), abs(e2[0])),
        add(abs(e1[1]), abs(e2[1])),
        add(abs(e1[2]), abs(e2[2])),
    ];
    let m = _mm256_max_ps(_mm256_max_ps(s[0], s[1]), s[2]);
    let tiny = _mm256_set1_ps(BEHIND_TINY);
    let margin = add(mul(_mm256_set1_ps(BEHIND_F64_MARGIN), mul(m, m)), tiny);
    let (yz, zy) = (mul(e1[1], e2[2]), mul(e1[2], e2[1]));
    let (zx, xz) = (mul(e1[2], e2[0]), mul(e1[0], e2[2]));
    let (xy, yx) = (mul(e1[0], e2[1]), mul(e1[1], e2[0]));
    let n = [sub(yz, zy), sub(zx, xz), sub(xy, yx)];
    let nn = [
        add(abs(yz), abs(zy)),
        add(abs(zx), abs(xz)),
        add(abs(xy), abs(yx)),
    ];
    let dot = |u: [__m256; 3], v: [__m256; 3]| {
        add(add(mul(u[0], v[0]), mul(u[1], v[1])), mul(u[2], v[2]))
    };
    let abs3 = |u: [__m256; 3]| [abs(u[0]), abs(u[1]), abs(u[2])];
    let rel = _mm256_set1_ps(BEHIND_REL);
    let bound_d = add(
        add(
            mul(rel, dot(abs3(d), nn)),
            mul(margin, _mm256_set1_ps(q.dir_l1)),
        ),
        tiny,
    );
    let dn = dot(d, n);
    let aa = abs3(a);
    let a1 = add(add(aa[0], aa[1]), aa[2]);
    let (wn, w_nn) = (dot(a, n), dot(aa, nn));
    let bound_w = add(add(mul(rel, w_nn), mul(margin, a1)), tiny);
    let side = _mm256_cmp_ps::<_CMP_GT_OQ>(abs(wn), bound_w);
    let certain = _mm256_and_ps(side, _mm256_cmp_ps::<_CMP_GT_OQ>(abs(dn), bound_d));
    let refused = _mm256_movemask_ps(_mm256_and_ps(certain, _mm256_xor_ps(wn, dn))) as u32;
    let near = !(_mm256_movemask_ps(side) as u32) & 0xFF;
    refused | near << 8
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

/// [`SimdLevel::slab8`] in 256-bit registers, on the fields of a [`Slab8`], passed one by one
/// so that they arrive in registers rather than through a reference to the record.
///
/// Not a `#[target_feature]` function but `#[inline(always)]`: it is inlined wherever it is
/// called, so its intrinsics are compiled with the features of the caller it lands in (the
/// frontend's `#[target_feature(enable = "avx2,fma")]` query functions). A
/// `#[target_feature]` function can only be `#[inline]`, a hint the compiler dropped when the
/// walk around it grew (a second leaf path moved it out of line: ~60 instructions more per
/// node test, `docs/performance.md`).
///
/// # Safety
///
/// The CPU must support AVX2 and FMA (the [`Avx2Fma`] token proves it).
#[cfg(target_arch = "x86_64")]
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn slab8_avx2(
    lo: [&[f32; 8]; 3],
    hi: [&[f32; 8]; 3],
    origin_near: [f32; 3],
    origin_far: [f32; 3],
    inv_dir: [f32; 3],
    inv_far: [f32; 3],
    t_min: f32,
    t_max: f32,
) -> ([f32; 8], u32) {
    use core::arch::x86_64::{
        _CMP_LE_OQ, _mm256_cmp_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_min_ps,
        _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_storeu_ps, _mm256_sub_ps,
    };
    // SAFETY: the caller's CPU supports AVX2 and FMA (this function's contract), the only
    // requirement of the arithmetic intrinsics; `lo[axis]` and `hi[axis]` are arrays of eight
    // `f32`, so each unaligned 32-byte load reads exactly their elements, and `out` is eight
    // `f32`, so the unaligned 32-byte store writes exactly them.
    unsafe {
        let mut t_enter = _mm256_set1_ps(t_min);
        let mut t_exit = _mm256_set1_ps(t_max);
        for axis in 0..3 {
            let l = _mm256_loadu_ps(lo[axis].as_ptr());
            let h = _mm256_loadu_ps(hi[axis].as_ptr());
            let inv = _mm256_set1_ps(inv_dir[axis]);
            let t_near = _mm256_mul_ps(_mm256_sub_ps(l, _mm256_set1_ps(origin_near[axis])), inv);
            let t_far = _mm256_mul_ps(
                _mm256_sub_ps(h, _mm256_set1_ps(origin_far[axis])),
                _mm256_set1_ps(inv_far[axis]),
            );
            // `maxps(a, b)` is `a > b ? a : b` and `minps(a, b)` is `a < b ? a : b`: the
            // portable loop's selects, NaN handling included.
            t_enter = _mm256_max_ps(t_near, t_enter);
            t_exit = _mm256_min_ps(t_far, t_exit);
        }
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_enter, t_exit)) as u32;
        let mut out = [0.0f32; 8];
        _mm256_storeu_ps(out.as_mut_ptr(), t_enter);
        (out, mask)
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::test_util::{lcg, mixed_f32};

    /// The `no_std` detection answers as `std`'s (which also reads `cpuid` and `XCR0`, in
    /// code of its own) on the CPU running the tests.
    #[test]
    fn detection_without_std_agrees_with_std() {
        let std_says = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma");
        assert_eq!(Avx2Fma::detect().is_some(), std_says);
    }

    /// The AVX2 sort against the keys sorted in scalar code, on every hit mask and on
    /// distances with ties, `±0`, negatives, infinities and values that differ only in the
    /// bits the key drops.
    #[test]
    fn avx2_key_sort_equals_a_scalar_sort() {
        let Some(level) = crate::test_util::avx2_or_skip(
            "simd::level::tests::avx2_key_sort_equals_a_scalar_sort",
        ) else {
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

    /// The AVX2 two-group cull against [`Sheared8`]'s lane formula written out in scalar
    /// code, bit for bit, on coordinates with NaN, `±∞`, `±0` and subnormals mixed in; both
    /// outcomes must occur.
    #[test]
    fn avx2_two_group_cull_equals_the_lane_formula() {
        let Some(level) = crate::test_util::avx2_or_skip(
            "simd::level::tests::avx2_two_group_cull_equals_the_lane_formula",
        ) else {
            return;
        };
        let mut s = 23u64;
        let value = |s: &mut u64| mixed_f32(s, 0.05, 8.0);
        let mut culled = 0;
        for _ in 0..20_000 {
            // rows[group][vertex][axis]: the permuted axes already.
            let mut rows = [[[[0.0f32; 4]; 3]; 3]; 2];
            for x in rows.iter_mut().flatten().flatten().flatten() {
                *x = value(&mut s);
            }
            let origin: [f32; 3] = core::array::from_fn(|_| value(&mut s) * 0.1);
            let shear = [lcg(&mut s) * 2.0 - 1.0, lcg(&mut s) * 2.0 - 1.0];
            fn refs(g: &[[[f32; 4]; 3]; 3]) -> [[&[f32; 4]; 3]; 3] {
                [0, 1, 2].map(|v| [&g[v][0], &g[v][1], &g[v][2]])
            }
            let q = Sheared8 {
                first: refs(&rows[0]),
                second: refs(&rows[1]),
                origin,
                shear,
            };
            let got = level.certain_misses8(&q).unwrap();
            for lane in 0..8 {
                let g = &rows[lane / 4];
                let l = lane % 4;
                let p = |v: usize| {
                    let z = g[v][2][l] - origin[2];
                    (
                        (g[v][0][l] - origin[0]) - shear[0] * z,
                        (g[v][1][l] - origin[1]) - shear[1] * z,
                    )
                };
                let ((ax, ay), (bx, by), (cx, cy)) = (p(0), p(1), p(2));
                let e = [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax];
                let want = e.iter().any(|&x| x < 0.0) && e.iter().any(|&x| x > 0.0);
                assert_eq!(got >> lane & 1 == 1, want, "lane {lane}: {e:?}");
                culled += usize::from(want);
            }
        }
        assert!(
            (10_000..150_000).contains(&culled),
            "both outcomes must occur: {culled} culled of 160000"
        );
        let zero = [0.0f32; 4];
        let q = Sheared8 {
            first: [[&zero; 3]; 3],
            second: [[&zero; 3]; 3],
            origin: [0.0; 3],
            shear: [0.0; 2],
        };
        assert_eq!(Portable.certain_misses8(&q), None);
    }

    /// The AVX2 slab kernel against the documented lane formula, bit for bit, on values with
    /// NaN, `±∞`, `±0` and subnormals mixed in. Runs where the CPU has AVX2 and FMA (every CI
    /// machine here); elsewhere there is no AVX2 code to run and the test says so.
    #[test]
    fn avx2_slab_equals_the_lane_formula() {
        let Some(level) =
            crate::test_util::avx2_or_skip("simd::level::tests::avx2_slab_equals_the_lane_formula")
        else {
            return;
        };
        let mut s = 7u64;
        let value = |s: &mut u64| mixed_f32(s, 0.08, 20.0);
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
            let inv_far: [f32; 3] = core::array::from_fn(|_| value(&mut s));
            let lo = [&planes[0], &planes[1], &planes[2]];
            let hi = [&planes[3], &planes[4], &planes[5]];
            let q = Slab8 {
                lo,
                hi,
                origin_near: on,
                origin_far: of,
                inv_dir: inv,
                inv_far,
                t_min,
                t_max,
            };
            let (dist, mask) = level.slab8(&q).unwrap();
            for i in 0..8 {
                let (mut enter, mut exit) = (t_min, t_max);
                for a in 0..3 {
                    let near = (lo[a][i] - on[a]) * inv[a];
                    let far = (hi[a][i] - of[a]) * inv_far[a];
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
            inv_far: [0.0; 3],
            t_min: 0.0,
            t_max: 1.0,
        };
        assert_eq!(Portable.slab8(&q), None);
    }
}
