//! Exact orientation predicates on `f32` points and directions: a fast `f64` evaluation
//! accepted when it clears a forward error bound ([`ORIENT3D_FILTER_REL`],
//! [`ORIENT2D_FILTER_REL`]), and an exact evaluation with Shewchuk's expansions (the private
//! `expansion` module) otherwise. The returned sign is the **exact** sign of the determinant
//! of the `f32` inputs, for every finite input.

mod expansion;

use crate::float::gamma_f64;
#[cfg(test)]
pub(crate) use expansion::two_product;
pub(crate) use expansion::{Expansion, diff};
use glam::Vec3;

/// Relative error bound of the `f64` evaluation of the 3×3 orientation determinant
/// `det[a − c, b − c, x − c]` of `f32` points, relative to its permanent (the same sum with
/// every product replaced by its absolute value, evaluated in `f64`). Unitless.
///
/// Why: each of the six terms `±u_i·v_j·w_k` passes through eight roundings (three
/// differences, the product `v_j·w_k`, the 2×2 difference, the product by `u_i`, two sums),
/// so the computed determinant is within `γ₈` of the exact permanent; the computed permanent
/// is itself within `γ₈` of the exact one (no underflow or overflow is possible for values
/// derived from `f32`). `γ₁₂` covers both and the rounding of the bound's own product. When
/// `|det| > γ₁₂·permanent` the computed sign is exact; otherwise the exact path decides.
pub const ORIENT3D_FILTER_REL: f64 = gamma_f64(12);

/// Relative error bound of the `f64` evaluation of the 2×2 determinant
/// `(a − c) × (b − c)` of `f32` coordinates, relative to its permanent. Unitless. Each term
/// passes through four roundings (two differences, one product, the difference); the
/// permanent through four as well; `γ₈` covers both.
pub const ORIENT2D_FILTER_REL: f64 = gamma_f64(8);

/// The sign (`1`, `−1`, `0`) of `det[a − c, b − c, x − c]`, exactly: positive when `x` lies on
/// the side of the plane through `a, b, c` that the normal `(a − c) × (b − c)` points to,
/// zero when the four points are coplanar (always, when `a, b, c` are collinear). `0` for a
/// non-finite input (callers reject those first).
#[must_use]
pub fn orient3d(a: Vec3, b: Vec3, c: Vec3, x: Vec3) -> i32 {
    let d = |p: Vec3| (p.as_dvec3() - c.as_dvec3()).to_array();
    det3_filtered([d(a), d(b), d(x)]).unwrap_or_else(|| orient3d_exact(a, b, c, x))
}

/// The sign (`1`, `−1`, `0`) of `det[a − c, b − c, dir] = dir · ((a − c) × (b − c))`, exactly:
/// positive when the direction `dir` points to the side of the plane through `a, b, c` that
/// the normal `(a − c) × (b − c)` points to, zero when `dir` is parallel to that plane (always,
/// when `a, b, c` are collinear). `0` for a non-finite input. Used by the triangle tests to
/// decide "degenerate triangle, or ray in its plane" exactly, where an `f64` cross product of
/// `f32` vertices spanning more than `2²⁹` in one coordinate can cancel to zero.
#[must_use]
pub fn orient_direction(a: Vec3, b: Vec3, c: Vec3, dir: Vec3) -> i32 {
    let d = |p: Vec3| (p.as_dvec3() - c.as_dvec3()).to_array();
    det3_filtered([d(a), d(b), dir.as_dvec3().to_array()]).unwrap_or_else(|| {
        let w = dir.to_array().map(|x| diff(f64::from(x), 0.0));
        det3_exact([differences(a, c), differences(b, c), w])
    })
}

/// The sign of `det[u, v, w]` from its `f64` evaluation when that clears
/// [`ORIENT3D_FILTER_REL`] times its permanent (then exact); `Some(0)` for a non-finite
/// evaluation; `None` when the exact evaluation must decide. Valid for rows that are `f32`
/// values or `f64` differences of two `f32` values (the bound counts a rounding per
/// difference; rows without one only have fewer).
#[inline]
fn det3_filtered([u, v, w]: [[f64; 3]; 3]) -> Option<i32> {
    let m = [
        v[1] * w[2] - v[2] * w[1],
        v[2] * w[0] - v[0] * w[2],
        v[0] * w[1] - v[1] * w[0],
    ];
    let det = u[0] * m[0] + u[1] * m[1] + u[2] * m[2];
    let perm = u[0].abs() * ((v[1] * w[2]).abs() + (v[2] * w[1]).abs())
        + u[1].abs() * ((v[2] * w[0]).abs() + (v[0] * w[2]).abs())
        + u[2].abs() * ((v[0] * w[1]).abs() + (v[1] * w[0]).abs());
    if !det.is_finite() || !perm.is_finite() {
        return Some(0);
    }
    (det.abs() > ORIENT3D_FILTER_REL * perm).then_some(if det > 0.0 { 1 } else { -1 })
}

/// [`orient3d`] by expansions only (no filter).
pub(crate) fn orient3d_exact(a: Vec3, b: Vec3, c: Vec3, x: Vec3) -> i32 {
    det3_exact([differences(a, c), differences(b, c), differences(x, c)])
}

/// `p − c` per coordinate, each as an exact two-component expansion.
fn differences(p: Vec3, c: Vec3) -> [Expansion<2>; 3] {
    let (p, c) = (p.to_array(), c.to_array());
    core::array::from_fn(|i| diff(f64::from(p[i]), f64::from(c[i])))
}

/// The exact sign of `det[u, v, w]` for rows of exact two-component expansions (differences
/// of two `f32` values, or one `f32` value); `0` if a capacity were exceeded (it cannot be:
/// the capacities below are the proven maxima).
fn det3_exact([u, v, w]: [[Expansion<2>; 3]; 3]) -> i32 {
    // Each 2×2 minor: two products of 2-component expansions, 8 components each: ≤ 16.
    let minor = |i: usize, j: usize| {
        let mut m = Expansion::<16>::ZERO;
        if let (Some(vi), Some(wj), Some(vj), Some(wi)) = (v.get(i), w.get(j), v.get(j), w.get(i)) {
            m.add_product(vi.components(), wj.components(), 1.0);
            m.add_product(vj.components(), wi.components(), -1.0);
        }
        m
    };
    let minors = [minor(1, 2), minor(2, 0), minor(0, 1)];
    // Three products of a 16-component minor by a 2-component difference: ≤ 3·64 = 192.
    let mut det = Expansion::<192>::ZERO;
    for (ui, mi) in u.iter().zip(&minors) {
        det.add_product(ui.components(), mi.components(), 1.0);
    }
    if det.overflowed() || minors.iter().any(Expansion::overflowed) {
        return 0;
    }
    det.sign()
}

/// The sign of the 2×2 determinant `(a − c) × (b − c)` of the projections of `a, b, c` onto
/// the coordinate axes `i` and `j` (`0..3`), exactly: positive when `(a, b, c)` turn
/// counter-clockwise in the `(i, j)` plane. `0` for a non-finite input.
#[must_use]
pub fn orient2d(a: Vec3, b: Vec3, c: Vec3, i: usize, j: usize) -> i32 {
    let g = |p: Vec3, k: usize| p.to_array().get(k).map_or(f64::NAN, |&v| f64::from(v));
    let (ai, aj, bi, bj, ci, cj) = (g(a, i), g(a, j), g(b, i), g(b, j), g(c, i), g(c, j));
    let (l, r) = ((ai - ci) * (bj - cj), (aj - cj) * (bi - ci));
    let det = l - r;
    let perm = l.abs() + r.abs();
    if !det.is_finite() || !perm.is_finite() {
        return 0;
    }
    if det.abs() > ORIENT2D_FILTER_REL * perm {
        return if det > 0.0 { 1 } else { -1 };
    }
    let mut e = Expansion::<16>::ZERO;
    e.add_product(diff(ai, ci).components(), diff(bj, cj).components(), 1.0);
    e.add_product(diff(aj, cj).components(), diff(bi, ci).components(), -1.0);
    if e.overflowed() { 0 } else { e.sign() }
}

#[cfg(test)]
mod tests;
