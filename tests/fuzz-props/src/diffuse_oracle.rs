//! Uniform Laplacian smoothing ("diffuse") evaluated without the core: straight from a
//! triangle list, in `f64`. The oracle of the `halfedge_ops` property's `Diffuse` and
//! `DiffuseVertex` operations and of `tests/tests/halfedge_meshes.rs`.
//!
//! The rule (`Mesh::diffuse`'s contract): every vertex moves to `x + k·(m − x)`, with `m` the
//! mean of its neighbours' **old** positions (Jacobi); a vertex with no neighbour stays put,
//! and so does a boundary vertex under [`DiffuseBoundary::Fixed`]. Neighbours and boundary
//! are read off the triangle list here: `w` is a neighbour of `v` when some triangle has the
//! edge `v–w`, and `v` is a boundary vertex when one of its edges is in exactly one triangle.

use std::collections::{BTreeSet, HashMap};

use glam::{DVec3, Vec3};
use halfray_core::float::F32_UNIT_ROUNDOFF;
use halfray_core::halfedge::DiffuseBoundary;

/// Tolerance of [`diffuse_close`], in units of `f32` unit roundoff `u = 2⁻²⁴` times the
/// magnitude of the rule's terms `M = |x| + |k|·(Σ|xⱼ|/n + |x|)` ([`DiffusePoint::tol`]).
///
/// Derivation, for the evaluation `Mesh::diffuse` documents (`L = m − x` summed and divided
/// in `f64` and rounded to `f32` once, then `x + k·L` in `f32`): three `f32` roundings (`L`,
/// `k·L`, the sum), each at most `u` of a quantity at most `M` (to first order); the core's
/// `f64` sum, division and subtraction (`n + 1` roundings) and this oracle's (`n + 3`) err by
/// at most `(2n + 4)·2⁻⁵³` of `M`, at most `u/4` for a valence `n < 2²⁶` ([`MAX_VALENCE`]).
/// `3u + u/4` plus second-order terms (`O(u²)`): within `4u`.
pub const DIFFUSE_TOL_ROUNDINGS: f64 = 4.0;

/// Absolute slack of [`diffuse_close`], in units (of the coordinates) per unit of `1 + |k|`:
/// the smallest subnormal `f32`, `2⁻¹⁴⁹`. Each of the three `f32` roundings errs by up to
/// `2⁻¹⁵⁰` absolutely when its result is subnormal, and the first (of `L`) is then scaled by
/// `k`: `(|k| + 2)·2⁻¹⁵⁰ ≤ (1 + |k|)·2⁻¹⁴⁹`, an error no relative bound covers.
pub const DIFFUSE_TOL_SUBNORMAL: f64 = f32::from_bits(1) as f64;

/// The valence [`DIFFUSE_TOL_ROUNDINGS`]'s derivation admits vertices below (its `f64` part
/// then stays within `u/4`).
pub const MAX_VALENCE: usize = 1 << 26;

/// `f32::MAX` in `f64`: the largest finite coordinate an `f32` evaluation can produce.
const F32_MAX: f64 = f32::MAX as f64;

/// Whether the core's `f32` evaluation of a moved vertex (`L`, `k·L`, `x + k·L`) stays finite,
/// as far as rounding lets the `f64` values decide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum F32Fit {
    /// Every intermediate is below `f32::MAX` by more than its rounding error: the step must
    /// succeed.
    Finite,
    /// The new position is beyond `f32::MAX` by more than its tolerance on some axis: the
    /// step must be refused as non-finite.
    Overflows,
    /// Within rounding of `f32::MAX`: either answer is right.
    Unclear,
}

/// One vertex's new position under the rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusePoint {
    /// The new position, in `f64`.
    pub at: DVec3,
    /// Per axis, the largest error the `f32` evaluation may make: [`DIFFUSE_TOL_ROUNDINGS`]`·u`
    /// of the terms' magnitude `M` plus [`DIFFUSE_TOL_SUBNORMAL`]`·(1 + |k|)`. Zero magnitude
    /// for a vertex that stays put (the core copies it).
    pub tol: DVec3,
    /// The Laplacian `m − x` (zero for a vertex that stays put).
    pub laplacian: DVec3,
    /// Per axis, the magnitude of the Laplacian's terms `Σ|xⱼ|/n + |x|` (zero when it stays).
    pub laplacian_magnitude: DVec3,
    /// The step size `k`.
    pub k: f64,
}

impl DiffusePoint {
    /// Whether the `f32` evaluation of this point stays finite ([`F32Fit`]). `L` is clear of
    /// `f32::MAX` when `|L| + 2u·(Σ|xⱼ|/n + |x|)` is below it (its `f64` error and one `f32`
    /// rounding), `k·L` and `x + k·L` when their value plus [`Self::tol`] is.
    #[must_use]
    pub fn f32_fit(&self) -> F32Fit {
        let u = f64::from(F32_UNIT_ROUNDOFF);
        let l_bound = self.laplacian.abs() + self.laplacian_magnitude * (2.0 * u);
        let step_bound = (self.laplacian * self.k).abs() + self.tol;
        let at_bound = self.at.abs() + self.tol;
        if (self.at.abs() - self.tol).max_element() > F32_MAX {
            F32Fit::Overflows
        } else if l_bound.max(step_bound).max(at_bound).max_element() <= F32_MAX {
            F32Fit::Finite
        } else {
            F32Fit::Unclear
        }
    }
}

/// `true` when `got` (the core's `f32` result) is within [`DiffusePoint::tol`] of `want.at`
/// on every axis.
#[must_use]
pub fn diffuse_close(got: Vec3, want: &DiffusePoint) -> bool {
    (got.as_dvec3() - want.at).abs().cmple(want.tol).all()
}

/// Neighbours (sorted, no repeats) and boundary flags of every vertex of a triangle list.
fn adjacency(n: usize, t: &[[u32; 3]]) -> (Vec<BTreeSet<u32>>, Vec<bool>) {
    let mut uses: HashMap<(u32, u32), usize> = HashMap::new();
    for tri in t {
        for c in 0..3 {
            let (a, b) = (tri[c], tri[(c + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut nbrs = vec![BTreeSet::new(); n];
    let mut boundary = vec![false; n];
    for (&(a, b), &count) in &uses {
        nbrs[a as usize].insert(b);
        nbrs[b as usize].insert(a);
        if count == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    (nbrs, boundary)
}

/// One Jacobi step of the rule on the triangle list `p`, `t` (every index < `p.len()`): the
/// new position of every vertex, by index (an unreferenced vertex stays put).
///
/// # Panics
/// If a vertex has [`MAX_VALENCE`] neighbours or more (outside the tolerance's derivation).
#[must_use]
pub fn diffuse_reference(
    p: &[Vec3],
    t: &[[u32; 3]],
    k: f64,
    boundary: DiffuseBoundary,
) -> Vec<DiffusePoint> {
    let (nbrs, on_boundary) = adjacency(p.len(), t);
    let slack = DVec3::splat(DIFFUSE_TOL_SUBNORMAL * (1.0 + k.abs()));
    (0..p.len())
        .map(|v| {
            let x = p[v].as_dvec3();
            let nb = &nbrs[v];
            assert!(nb.len() < MAX_VALENCE, "vertex {v}: valence {}", nb.len());
            let stays = nb.is_empty() || (boundary == DiffuseBoundary::Fixed && on_boundary[v]);
            if stays {
                return DiffusePoint {
                    at: x,
                    tol: slack,
                    laplacian: DVec3::ZERO,
                    laplacian_magnitude: DVec3::ZERO,
                    k,
                };
            }
            let n = nb.len() as f64;
            let sum: DVec3 = nb.iter().map(|&w| p[w as usize].as_dvec3()).sum();
            let sum_abs: DVec3 = nb.iter().map(|&w| p[w as usize].as_dvec3().abs()).sum();
            let laplacian = sum / n - x;
            let laplacian_magnitude = sum_abs / n + x.abs();
            let magnitude = x.abs() + laplacian_magnitude * k.abs();
            DiffusePoint {
                at: x + laplacian * k,
                tol: magnitude * (DIFFUSE_TOL_ROUNDINGS * f64::from(F32_UNIT_ROUNDOFF)) + slack,
                laplacian,
                laplacian_magnitude,
                k,
            }
        })
        .collect()
}
