//! The rules every structure's walk shares, so that all of them give the same answer: the
//! tie rule of the closest hit ([`improves`], [`take_if_better`]), the bound up to which a
//! box or cell is still visited ([`cull_bound`], [`CULL_REL_SLACK`]), the outward padding of
//! the boxes a ray is tested against ([`PadFrame`], [`pad_to_root`], [`extent_of`]),
//! and the loop over a run of primitives of the closure-based walks ([`test_run`]).

use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;

/// Relative slack on the closest hit's `t` when culling boxes: a box whose entry distance is
/// at most `t·(1 + CULL_REL_SLACK)` is still visited. The slab test's entry distance is rounded
/// (up to `gamma(3)` relative) and so is the primitive's `t` (a few ulps for well-conditioned
/// hits), so a box holding a primitive that reports the same — or a one-ulp-smaller — `t` as
/// the current hit could otherwise be culled, and the tie rule would depend on the tree. 64
/// ulps (`64·2⁻²³`, [`crate::tolerance::T_REL_TOLERANCE_WELL_CONDITIONED`]) covers both; it
/// costs a handful of extra box tests per ray. Unitless.
pub const CULL_REL_SLACK: f32 = crate::tolerance::T_REL_TOLERANCE_WELL_CONDITIONED;

/// Where a structure's points lie, as its box padding needs it ([`PadFrame::pad`]): a centre
/// `c` of its root box, whether its boxes are stored in world coordinates or relative to `c`
/// ([`Aabb::relative_to`]), and the per-structure part of the padding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PadFrame {
    centre: Vec3,
    /// [`BVH_PROJECTION_PAD`]`·h`, plus [`PAD_ORIGIN_SHIFT_REL`]`·max|c|` for boxes in world
    /// coordinates (`h` below), or `+∞` for a root box that is not finite and ordered.
    ///
    /// [`BVH_PROJECTION_PAD`]: crate::tolerance::BVH_PROJECTION_PAD
    /// [`PAD_ORIGIN_SHIFT_REL`]: crate::tolerance::PAD_ORIGIN_SHIFT_REL
    offset: f32,
}

impl PadFrame {
    /// The frame of a structure whose points all lie in `root` and whose boxes are in world
    /// coordinates (the kd-tree's split planes): `c` its rounded centre, `h` at least
    /// `max_i max(|lo_i − c_i|, |hi_i − c_i|)` (the largest `f32` difference times `1 + 4u`,
    /// which covers its rounding and the product's). A root that is not finite and ordered
    /// (an empty tree's) pads every box by `+∞`.
    pub(crate) fn of(root: &Aabb) -> Self {
        Self::around(root, true)
    }

    /// [`PadFrame::of`] for a structure whose boxes are stored relative to the frame's centre
    /// ([`PadFrame::centre`], [`Aabb::relative_to`]) and tested from the ray's origin in that
    /// frame ([`PadFrame::local`]): no term grows with the coordinates' magnitude.
    pub(crate) fn relative(root: &Aabb) -> Self {
        Self::around(root, false)
    }

    fn around(root: &Aabb, world: bool) -> Self {
        use crate::float::F32_UNIT_ROUNDOFF as U;
        use crate::tolerance::{BVH_PROJECTION_PAD, PAD_ORIGIN_SHIFT_REL};
        if !(root.is_finite() && root.is_valid()) {
            return Self {
                centre: Vec3::ZERO,
                offset: f32::INFINITY,
            };
        }
        let centre = root.center();
        let h = (centre - root.min).max(root.max - centre).max_element() * (1.0 + 4.0 * U);
        let shift = if world {
            PAD_ORIGIN_SHIFT_REL * centre.abs().max_element()
        } else {
            0.0
        };
        let offset = BVH_PROJECTION_PAD * h + shift;
        Self {
            centre,
            offset: if offset <= f32::MAX {
                offset
            } else {
                f32::INFINITY
            },
        }
    }

    /// The centre `c` the frame measures from (the origin of a structure's relative boxes).
    #[inline]
    pub(crate) fn centre(&self) -> Vec3 {
        self.centre
    }

    /// The outward padding, in world units, of every box tested for a ray from `origin`:
    /// `(`[`BVH_PROJECTION_PAD`]` + 2·`[`PAD_ORIGIN_SHIFT_REL`]`)·m + offset`, `m =
    /// max_i |o_i − c_i|` (rounded). For boxes in world coordinates it meets
    /// [`BVH_PROJECTION_PAD`]'s requirement with `R ≤ m/(1 − u) + h` (every point lies within
    /// `h` of `c` per axis) and `max|o| ≤ m/(1 − u) + max|c|`; the margins of `γ₁₆` over `γ₈`
    /// absorb the roundings. For relative boxes see [`PadFrame::local`]. One subtraction per
    /// axis more than `γ₁₆·(max|o| + extent)`. `+∞` when it overflows (every box is then hit:
    /// slower, still exact).
    ///
    /// [`BVH_PROJECTION_PAD`]: crate::tolerance::BVH_PROJECTION_PAD
    /// [`PAD_ORIGIN_SHIFT_REL`]: crate::tolerance::PAD_ORIGIN_SHIFT_REL
    #[inline(always)]
    pub(crate) fn pad(&self, origin: Vec3) -> f32 {
        self.local(origin).1
    }

    /// The ray's origin in the frame, `o' = o − c` rounded to `f32`, and the padding
    /// [`PadFrame::pad`] (`m = max|o'|`). For boxes stored relative to `c`, tested from `o'`,
    /// the padding meets [`BVH_PROJECTION_PAD`]'s requirement in the frame: the exact ray
    /// from `o − c` passes within `γ₈·R` of a triangle the watertight test hits; `o'` moves it
    /// by at most `u·m` per axis, and the shifted origins `o' ± pad` round by at most
    /// `u·(m + pad)`: `3u·m` in all, under the `4u·m` of `2·`[`PAD_ORIGIN_SHIFT_REL`]`·m`,
    /// and no term grows with `max|c|`. A small mesh far from the coordinate origin is
    /// therefore padded by its own reach from the ray's origin alone.
    ///
    /// [`BVH_PROJECTION_PAD`]: crate::tolerance::BVH_PROJECTION_PAD
    /// [`PAD_ORIGIN_SHIFT_REL`]: crate::tolerance::PAD_ORIGIN_SHIFT_REL
    #[inline(always)]
    pub(crate) fn local(&self, origin: Vec3) -> (Vec3, f32) {
        use crate::tolerance::{BVH_PROJECTION_PAD, PAD_ORIGIN_SHIFT_REL};
        let o = origin - self.centre;
        let d = o.abs().to_array();
        // Plain comparisons: `d` is finite (a valid ray's origin, a finite centre).
        let m01 = if d[0] > d[1] { d[0] } else { d[1] };
        let m = if m01 > d[2] { m01 } else { d[2] };
        (
            o,
            (BVH_PROJECTION_PAD + 2.0 * PAD_ORIGIN_SHIFT_REL) * m + self.offset,
        )
    }
}

/// The box padding of a structure that keeps no frame (the binary [`crate::bvh::Bvh`], whose
/// microcontroller image has no room for one), for a ray from `origin` in a structure whose
/// points all lie in `root`: [`BVH_PROJECTION_PAD`]`·r + `[`PAD_ORIGIN_SHIFT_REL`]`·max|o|`,
/// `r` the largest of `|lo_i − o_i|`, `|hi_i − o_i|` over the axes, each rounded once.
///
/// It meets [`BVH_PROJECTION_PAD`]'s requirement: every point's `R = max_i |p_i − o_i|` is at
/// most `r/(1 − u)`; `γ₁₆·r` exceeds the `γ₈·R` of the watertight rounding and the slab's
/// `u·(R + pad)` by `6u·R`, and `2u·max|o|` the shifted origins' `u·(|o_i| + pad)` (the
/// `u·pad` part, of order `u²`, within the `6u·R`). Like [`PadFrame::pad`] in world
/// coordinates, nothing grows with the coordinates' magnitude but the origin's own two ulps:
/// a small mesh far from the coordinate origin is padded by its reach from the ray's origin.
/// One pass over the six bounds with plain comparisons (compact on small targets); `+∞` when
/// it overflows (every box is then hit: slower, still exact).
///
/// [`BVH_PROJECTION_PAD`]: crate::tolerance::BVH_PROJECTION_PAD
/// [`PAD_ORIGIN_SHIFT_REL`]: crate::tolerance::PAD_ORIGIN_SHIFT_REL
#[inline(always)]
pub(crate) fn pad_to_root(root: &Aabb, origin: Vec3) -> f32 {
    use crate::tolerance::{BVH_PROJECTION_PAD, PAD_ORIGIN_SHIFT_REL};
    let (lo, hi, o) = (root.min.to_array(), root.max.to_array(), origin.to_array());
    let (mut r, mut o_max) = (0.0f32, 0.0f32);
    for ((l, h), o) in lo.into_iter().zip(hi).zip(o) {
        let (below, above) = ((l - o).abs(), (h - o).abs());
        let far = if below > above { below } else { above };
        r = if far > r { far } else { r };
        o_max = if o.abs() > o_max { o.abs() } else { o_max };
    }
    BVH_PROJECTION_PAD * r + PAD_ORIGIN_SHIFT_REL * o_max
}

/// The largest coordinate magnitude of `b` (0 for an empty or non-finite box, whose
/// children are never hit).
#[inline]
pub(crate) fn extent_of(b: &Aabb) -> f32 {
    // One pass over the six bounds (compact on small targets): finite, ordered per axis.
    let (lo, hi) = (b.min.to_array(), b.max.to_array());
    let mut usable = true;
    let mut m = 0.0f32;
    for (l, h) in lo.into_iter().zip(hi) {
        usable &= l.is_finite() & h.is_finite() & (l <= h);
        let a = if l.abs() > h.abs() { l.abs() } else { h.abs() };
        m = if a > m { a } else { m };
    }
    if usable { m } else { 0.0 }
}

/// `t` padded by [`CULL_REL_SLACK`] for box culling (infinities are kept as they are).
#[inline(always)]
pub(crate) fn cull_bound(t: f32) -> f32 {
    if t.is_finite() {
        t + t.abs() * CULL_REL_SLACK
    } else {
        t
    }
}

/// Whether a hit of primitive `prim` at `t` replaces the current best (`best_prim`, at
/// `ray.t_max`, or none yet): `t` in `(t_min, t_max]`, and of equal `t` the smaller primitive
/// index (the tie rule of [`crate::query`]). Shared by every traversal.
#[inline(always)]
pub(crate) fn improves(ray: &Ray, t: f32, prim: u32, best_prim: Option<u32>) -> bool {
    match best_prim {
        None => ray.contains(t),
        Some(bp) => t > ray.t_min && (t < ray.t_max || (t == ray.t_max && prim < bp)),
    }
}

/// Offers the hit `(t, h)` of primitive `prim` to a closest-hit search whose current best is
/// `best` (at `cur.t_max`): when it [`improves`] on it, it becomes `best`, `cur.t_max`
/// shrinks to `t`, and the result is `true`; otherwise nothing changes. Shared by every
/// traversal (binary and wide BVH, kd-tree, grid).
#[inline(always)]
pub(crate) fn take_if_better<H>(
    cur: &mut Ray,
    best: &mut Option<(u32, H)>,
    prim: u32,
    t: f32,
    h: H,
) -> bool {
    if improves(cur, t, prim, best.as_ref().map(|b| b.0)) {
        cur.t_max = t;
        *best = Some((prim, h));
        true
    } else {
        false
    }
}

/// Tests the primitives of `run` in order with `intersect(prim, cur)`, adding one to
/// `*tested` per primitive tested, and offers each hit to the search ([`take_if_better`]).
/// Returns `true` when `any` and a hit was taken: the any-hit query is done and the rest of
/// `run` is left untested. The leaf (or cell) loop of the closure-based queries of
/// [`crate::kdtree::KdTree`] and [`crate::grid::Grid`]. ([`crate::bvh::Bvh`] keeps its own loop: through
/// this one the Cortex-M4F query image of `examples/mcu` grew from 8 168 to 8 208 bytes, past
/// its 8 KiB budget.)
#[inline(always)]
pub(crate) fn test_run<H>(
    run: &[u32],
    intersect: &mut impl FnMut(u32, &Ray) -> Option<(f32, H)>,
    cur: &mut Ray,
    best: &mut Option<(u32, H)>,
    tested: &mut u64,
    any: bool,
) -> bool {
    for &prim in run {
        *tested += 1;
        let Some((t, h)) = intersect(prim, cur) else {
            continue;
        };
        if take_if_better(cur, best, prim, t, h) && any {
            return true;
        }
    }
    false
}
