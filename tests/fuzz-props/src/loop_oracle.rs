//! Loop subdivision evaluated without the core: straight from a triangle list, in `f64`,
//! with β from the published formulas. The oracle of the `halfedge_ops` property's Loop
//! operation and of `tests/tests/halfedge_meshes.rs`.

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use halfray_core::halfedge::LoopWeights;

/// Tolerance of [`loop_close`], in units of `f32` unit roundoff `u = 2⁻²⁴` times the
/// magnitude of the rule's terms ([`LoopPoint::magnitude`]). Each Loop rule rounds at most
/// four times in `f32` (the odd interior rule: `a + b`, `·3/8`, `c + d`, the final sum; the
/// even interior rule rounds β to `f32` and its `f64` sum once): ≤ 4u of the terms'
/// magnitude, cancellation included. Twice that, for the order of the roundings.
pub const LOOP_TOL_ROUNDINGS: f64 = 8.0;

/// Absolute slack of [`loop_close`], in units (of the coordinates): eight of the smallest
/// subnormal `f32` (2⁻¹⁴⁹). A rounding among subnormals errs by up to half of one, an
/// absolute error no relative bound covers.
pub const LOOP_TOL_SUBNORMAL: f64 = 8.0 * 1.401_298_464_324_817e-45;

/// `f32` unit roundoff `2⁻²⁴`, unitless.
const U32: f64 = 1.0 / 16_777_216.0;

/// One subdivided position: its value and, per axis, the sum of its terms' magnitudes
/// `Σ |wᵢ·xᵢ|` (what bounds the rounding error of any evaluation order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopPoint {
    /// The position, in `f64`.
    pub at: DVec3,
    /// `Σ |wᵢ·xᵢ|` per axis.
    pub magnitude: DVec3,
}

/// `true` when `got` (the core's `f32` result) is within [`LOOP_TOL_ROUNDINGS`]`·u` of the
/// terms' magnitude (plus [`LOOP_TOL_SUBNORMAL`]) of `want`, on every axis.
#[must_use]
pub fn loop_close(got: Vec3, want: &LoopPoint) -> bool {
    let err = (got.as_dvec3() - want.at).abs();
    let tol = want.magnitude * (LOOP_TOL_ROUNDINGS * U32) + DVec3::splat(LOOP_TOL_SUBNORMAL);
    err.cmple(tol).all()
}

/// β of an interior vertex of valence `n`, from the published formulas in `f64` (not the
/// core's `loop_beta`): Loop (1987) `(5/8 − (3/8 + cos(2π/n)/4)²)/n`; Warren (1995) `3/16`
/// for `n = 3`, else `3/(8n)`.
#[must_use]
pub fn reference_beta(n: usize, weights: LoopWeights) -> f64 {
    let nf = n as f64;
    match weights {
        LoopWeights::Loop => {
            let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / nf).cos();
            (0.625 - c * c) / nf
        }
        LoopWeights::Warren if n == 3 => 3.0 / 16.0,
        LoopWeights::Warren => 3.0 / (8.0 * nf),
    }
}

/// One level of Loop subdivision of the manifold triangle list `p`, `t` (every vertex on at
/// most one boundary loop, no repeated edge; every vertex index < `p.len()`): the new
/// position of every old vertex (by index; an unreferenced vertex keeps its position), and
/// of the new vertex on every edge (keyed by its endpoints, smaller first).
///
/// Rules: interior vertex of valence `n`, `(1 − nβ(n))·x + β(n)·Σ neighbours`; boundary
/// vertex, `3/4·x + 1/8·(b₀ + b₁)` over its two neighbours along boundary edges; interior edge
/// `a–b` with opposite vertices `c`, `d`, `3/8·(a + b) + 1/8·(c + d)`; boundary edge, its
/// midpoint.
///
/// # Panics
/// If a boundary vertex has other than two boundary neighbours (a non-manifold input).
#[must_use]
pub fn loop_reference(
    p: &[Vec3],
    t: &[[u32; 3]],
    beta: impl Fn(usize) -> f64,
) -> (Vec<LoopPoint>, HashMap<(u32, u32), LoopPoint>) {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut opp: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for tri in t {
        for k in 0..3 {
            opp.entry(key(tri[k], tri[(k + 1) % 3]))
                .or_default()
                .push(tri[(k + 2) % 3]);
        }
    }
    let mut nbrs: Vec<Vec<u32>> = vec![Vec::new(); p.len()];
    let mut bnbrs: Vec<Vec<u32>> = vec![Vec::new(); p.len()];
    for (&(a, b), o) in &opp {
        nbrs[a as usize].push(b);
        nbrs[b as usize].push(a);
        if o.len() == 1 {
            bnbrs[a as usize].push(b);
            bnbrs[b as usize].push(a);
        }
    }
    let d = |i: u32| p[i as usize].as_dvec3();
    // Σ wᵢ·xᵢ and Σ |wᵢ·xᵢ| of (weight, vertex) terms.
    let combine = |terms: &[(f64, u32)]| LoopPoint {
        at: terms.iter().map(|&(w, i)| w * d(i)).sum(),
        magnitude: terms.iter().map(|&(w, i)| (w * d(i)).abs()).sum(),
    };
    let even = (0..p.len() as u32)
        .map(|v| {
            let (nb, bn) = (&nbrs[v as usize], &bnbrs[v as usize]);
            if !bn.is_empty() {
                assert_eq!(bn.len(), 2, "vertex {v} has boundary neighbours {bn:?}");
                combine(&[(0.75, v), (0.125, bn[0]), (0.125, bn[1])])
            } else {
                let n = nb.len();
                let b = if n == 0 { 0.0 } else { beta(n) };
                let mut terms = vec![(1.0 - n as f64 * b, v)];
                terms.extend(nb.iter().map(|&w| (b, w)));
                combine(&terms)
            }
        })
        .collect();
    let odd = opp
        .iter()
        .map(|(&(a, b), o)| {
            let q = if o.len() == 1 {
                combine(&[(0.5, a), (0.5, b)])
            } else {
                combine(&[(0.375, a), (0.375, b), (0.125, o[0]), (0.125, o[1])])
            };
            ((a, b), q)
        })
        .collect();
    (even, odd)
}
