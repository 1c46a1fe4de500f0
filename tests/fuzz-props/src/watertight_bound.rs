//! The error bound of the watertight test (the oracle of `ray_triangle` and `bvh`): the
//! projection's rounding, the domain where it holds, and where the `f64` reference may
//! decide a hit or a miss.

use super::*;

/// Relative error of one sheared `f32` coordinate of the watertight test,
/// `x' = fl(fl(p − o)_kx − fl(fl(d_kx/d_kz) · fl(p − o)_kz))`, with respect to the magnitude
/// `X = |(p − o)_kx| + |(d_kx/d_kz)·(p − o)_kz|`: the first term carries two roundings (the
/// subtraction `p − o` and the final subtraction), the second four (`p − o`, the shear
/// division, the product, the final subtraction), so `|x' − x| ≤ gamma(4)·X` (standard model,
/// no underflow; see [`UNDERFLOW_ABS`]). Same for `y'`.
pub const PROJ_REL: f64 = gamma(4) as f64;

/// Relative error of the scaled depth `z' = fl(fl(1/d_kz) · fl(p − o)_kz)`: three roundings,
/// relative to `Z = |(p − o)_kz / d_kz|`.
pub const DEPTH_REL: f64 = gamma(3) as f64;

/// Absolute error allowance per `f32` coordinate for gradual underflow: an operation whose
/// result is subnormal has an absolute error of at most `2⁻¹⁵⁰` instead of a relative one;
/// the four operations of a projection contribute at most `4·2⁻¹⁵⁰ < 2⁻¹⁴⁶` (the later
/// roundings scale it by at most `1 + gamma(4)`).
pub const UNDERFLOW_ABS: f64 = f32::MIN_POSITIVE as f64 / 1_048_576.0; // 2^-146

/// Absolute error of one rounding to `f32` below the normal range: at most half the spacing
/// `2⁻¹⁴⁹` of the subnormals; the whole spacing (the smallest positive `f32`) is allowed, so
/// the rounding of the bound's own evaluation is covered. Unit: that of the rounded value
/// (`t`, or a unitless barycentric).
pub const F32_SUBNORMAL_ROUNDING_ABS: f64 = 1.401_298_464_324_817e-45; // 2^-149

/// Relative allowance for the reference's own error (and this file's `f64` recomputation of
/// the same edge functions): the `f64` shear, products and sums carry a few roundings of
/// `2⁻⁵³ ≈ 1.1·10⁻¹⁶` each; `10⁻¹³` is a thousand times that.
pub const REF_REL: f64 = 1e-13;

/// Factor applied on top of the first-order bounds: covers the second-order terms dropped in
/// the derivations and the rounding of the bound's own `f64` evaluation.
pub const BOUND_SAFETY: f64 = 2.0;

/// Domain of the agreement check: every sheared magnitude `X`, `Y`, `Z` (see [`PROJ_REL`]) is
/// at most `2⁶⁰`, so no `f32` product of two of them (`watertight-f32` edge functions) and no
/// projection overflows. Beyond it (about 10¹⁸ from the ray origin) only the contract is
/// checked.
pub const DOMAIN_MAX: f64 = 1_152_921_504_606_846_976.0; // 2^60

/// Domain of the agreement check: the dominant direction component satisfies
/// `|d_kz| ≥ 2⁻¹⁰⁰`, so the `f32` shear `1/d_kz` is finite and normal.
pub const DOMAIN_MIN_DOMINANT_DIRECTION: f64 = 7.888_609_052_210_118e-31; // 2^-100

/// How a variant evaluates its edge functions from the sheared `f32` coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeEval {
    /// `watertight`: `f64` difference of exact `f64` products (one rounding, `2⁻⁵³` of the
    /// products), `det`, `t` and barycentrics in `f64`, rounded once to `f32`.
    ExactF64,
    /// `watertight-f32`: `f32` products and difference (`gamma(2)` of the products; signs are
    /// still exact by monotone rounding, zeros recomputed exactly), `det`, `t` and the
    /// barycentrics in `f32` (a further `gamma(3)`–`gamma(5)`).
    F32,
}

/// The error bound of the watertight test against the exact result, for one ray and triangle.
///
/// Derivation. With `(xᵢ, yᵢ, zᵢ)` the exact sheared coordinates of vertex `i` and
/// `(Xᵢ, Yᵢ, Zᵢ)` their magnitudes ([`PROJ_REL`], [`DEPTH_REL`]), the `f32` coordinates are
/// within `dXᵢ = PROJ_REL·Xᵢ + UNDERFLOW_ABS` (same for `y`, `z` with `DEPTH_REL`). An edge
/// function `e = x_p·y_q − y_p·x_q` evaluated on perturbed coordinates moves by at most
/// `D = (X_p + dX_p)·dY_q + Y_q·dX_p + (Y_p + dY_p)·dX_q + X_q·dY_p`; its evaluation adds
/// `eval·P` with `P = (X_p + dX_p)(Y_q + dY_q) + (Y_p + dY_p)(X_q + dX_q)`, and the reference
/// `REF_REL·P`. So `errᵢ = BOUND_SAFETY·(D + (eval + REF_REL)·P)`.
///
/// * If every exact `|eᵢ| > errᵢ`, the variant's edge signs equal the exact ones, so it is
///   inside exactly when the reference is (reference barycentric `|bᵢ| = |eᵢ/det|` farther
///   than `errᵢ/|det|` from an edge; `det = Σ eᵢ`).
/// * Then `t = Σ eᵢzᵢ / Σ eᵢ` moves by at most
///   `(Σ |eᵢ|·dZᵢ + Σ errᵢ·(|zᵢ| + dZᵢ) + |t|·Σ errᵢ) / (|det| − Σ errᵢ)`, plus the
///   evaluation of `t` and its rounding to `f32`; a barycentric `bᵢ = eᵢ/det` by at most
///   `(errᵢ + |bᵢ|·Σ errᵢ) / (|det| − Σ errᵢ)` plus its rounding.
///
/// Domain ([`WatertightBound::new`] returns `None` outside it): valid ray, finite vertices,
/// every `X, Y, Z ≤` [`DOMAIN_MAX`], `|d_kz| ≥` [`DOMAIN_MIN_DOMINANT_DIRECTION`]; for
/// `watertight-f32` also `2⁻¹⁰⁰ ≤ |det|`, `Σ |eᵢ·zᵢ| ≤ 2¹²⁰` (its `f32` `det`, `1/det` and
/// `t` neither underflow nor overflow), and for both `|t| ≤ 2¹²⁰`.
#[derive(Clone, Copy, Debug)]
pub struct WatertightBound {
    /// Exact-ish (`f64`) sheared coordinates `x, y, z` per vertex.
    pub x: [f64; 3],
    /// `y` per vertex.
    pub y: [f64; 3],
    /// `z` per vertex.
    pub z: [f64; 3],
    /// Magnitudes `X` per vertex.
    pub mx: [f64; 3],
    /// Magnitudes `Y` per vertex.
    pub my: [f64; 3],
    /// Magnitudes `Z` per vertex.
    pub mz: [f64; 3],
}

/// `true` when a quantity of the watertight projection of `v` (`p − o`, the shear products
/// `s·(p − o)_kz`, the sheared `x'`, `y'`) is a non-zero subnormal, or the shear `d_i/d_kz`
/// itself underflows: its rounding is then absolute, not relative, and the projected ray is no
/// longer the exact one up to `f32` rounding; or when one of them exceeds `f32::MAX`, so that
/// it overflows in `f32` (regression `crash-aa8baa4e…`: `p − o` of `±1.7e38` coordinates).
/// Both are outside the `Watertight` docs' domain ("a normal number or zero").
pub fn projection_underflows(ray: &Ray, v: &[Vec3; 3]) -> bool {
    let d = ray.direction;
    let a = d.abs();
    let kz = a.max_position();
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    // Each quantity in f64 from the f32 values the test actually rounds: below the f32 normal
    // range (and not exactly zero), its f32 rounding is absolute, or it vanishes.
    let sub = |x: f64| {
        x != 0.0 && x.abs() < f64::from(f32::MIN_POSITIVE) || x.abs() > f64::from(f32::MAX)
    };
    let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    let dk = f64::from(d[kz]);
    sub(f64::from(d[kx]) / dk)
        || sub(f64::from(d[ky]) / dk)
        || v.iter().any(|p| {
            let q = *p - ray.origin;
            let q64 = p.as_dvec3() - ray.origin.as_dvec3();
            let qz = f64::from(q[kz]);
            let (px, py, pz) = (f64::from(sx) * qz, f64::from(sy) * qz, f64::from(sz) * qz);
            let (px32, py32) = (sx * q[kz], sy * q[kz]);
            [
                q64.x,
                q64.y,
                q64.z,
                px,
                py,
                pz,
                f64::from(q[kx]) - f64::from(px32),
                f64::from(q[ky]) - f64::from(py32),
            ]
            .into_iter()
            .any(sub)
        })
}

/// Smallest `|det|` (sum of the sheared edge functions) inside the `f32` variant's domain:
/// 2^-100 (7.889e-31) rounded up, so within the domain, where its `f32` products stay clear
/// of the subnormal range.
pub const F32_DET_MIN: f64 = 7.9e-31;

/// Largest `Σ|eᵢ·zᵢ|` (and `|t|`) inside the `f32` variant's domain: 2^120 ≈ 1.33e36 rounded
/// down, so the scaled depth sum cannot overflow `f32` (max ≈ 2^128).
pub const F32_DEPTH_SUM_MAX: f64 = 1.3e36;

/// The edge functions in the watertight test's order: `e0 = e(v2, v1)`, `e1 = e(v0, v2)`,
/// `e2 = e(v1, v0)` with `e(p, q) = x_p·y_q − y_p·x_q`; `bᵢ = eᵢ / Σ e`.
const EDGE_PAIRS: [(usize, usize); 3] = [(2, 1), (0, 2), (1, 0)];

impl WatertightBound {
    /// The sheared coordinates (same axis permutation as the watertight test: `kz` is the
    /// largest `|dᵢ|`, ties to the lower index), or `None` outside the domain.
    pub fn new(ray: &Ray, v: &[Vec3; 3]) -> Option<Self> {
        if !ray.is_valid() || !v.iter().all(|p| p.is_finite()) {
            return None;
        }
        let d = ray.direction.as_dvec3();
        let o = ray.origin.as_dvec3();
        let a = d.abs();
        let kz = a.max_position();
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        if a[kz] < DOMAIN_MIN_DOMINANT_DIRECTION {
            return None;
        }
        let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
        let mut b = Self {
            x: [0.0; 3],
            y: [0.0; 3],
            z: [0.0; 3],
            mx: [0.0; 3],
            my: [0.0; 3],
            mz: [0.0; 3],
        };
        for (i, vi) in v.iter().enumerate() {
            let p = vi.as_dvec3() - o;
            b.x[i] = p[kx] - sx * p[kz];
            b.y[i] = p[ky] - sy * p[kz];
            b.z[i] = sz * p[kz];
            b.mx[i] = p[kx].abs() + (sx * p[kz]).abs();
            b.my[i] = p[ky].abs() + (sy * p[kz]).abs();
            b.mz[i] = b.z[i].abs();
        }
        let max =
            b.mx.iter()
                .chain(&b.my)
                .chain(&b.mz)
                .fold(0.0f64, |m, &x| m.max(x));
        (max <= DOMAIN_MAX).then_some(b)
    }

    /// Edge functions `eᵢ` (`f64`, error `≤ REF_REL·P`).
    pub fn edges(&self) -> [f64; 3] {
        EDGE_PAIRS.map(|(p, q)| self.x[p] * self.y[q] - self.y[p] * self.x[q])
    }

    /// Error bounds `errᵢ` of the variant's edge functions (see the type's docs).
    pub fn edge_errors(&self, eval: EdgeEval) -> [f64; 3] {
        let (eval_rel, eval_abs) = match eval {
            EdgeEval::ExactF64 => (F64_UNIT_ROUNDOFF, 0.0),
            EdgeEval::F32 => (f64::from(gamma(2)), 2.0 * UNDERFLOW_ABS),
        };
        let dx = self.mx.map(|m| PROJ_REL * m + UNDERFLOW_ABS);
        let dy = self.my.map(|m| PROJ_REL * m + UNDERFLOW_ABS);
        EDGE_PAIRS.map(|(p, q)| {
            let d = (self.mx[p] + dx[p]) * dy[q]
                + self.my[q] * dx[p]
                + (self.my[p] + dy[p]) * dx[q]
                + self.mx[q] * dy[p];
            let prod = (self.mx[p] + dx[p]) * (self.my[q] + dy[q])
                + (self.my[p] + dy[p]) * (self.mx[q] + dx[q]);
            BOUND_SAFETY * (d + (eval_rel + REF_REL) * prod + eval_abs)
        })
    }

    /// How far the variant's barycentric `bᵢ` can be from the exact `b_ref` (the reference's
    /// `eᵢ/det`), when every exact `|eᵢ|` exceeds its error bound (see the type's docs): the
    /// edge functions' errors over `|det| − Σ errᵢ`, the evaluation's relative rounding and
    /// one subnormal rounding ([`F32_SUBNORMAL_ROUNDING_ABS`]), times [`BOUND_SAFETY`].
    /// Unitless (absolute, on the barycentric).
    pub fn barycentric_error(&self, eval: EdgeEval, i: usize, b_ref: f64) -> f64 {
        let e = self.edges();
        let err = self.edge_errors(eval);
        let sum_err: f64 = err.iter().sum();
        let denom = e.iter().sum::<f64>().abs() - sum_err;
        let b_eval = match eval {
            EdgeEval::ExactF64 => F64_UNIT_ROUNDOFF,
            EdgeEval::F32 => f64::from(gamma(3)),
        };
        BOUND_SAFETY
            * ((err[i] + b_ref.abs() * sum_err) / denom
                + b_eval * b_ref.abs()
                + F32_SUBNORMAL_ROUNDING_ABS)
    }

    /// Property 2 of [`check_ray_triangle`] for one variant's result `got`.
    pub fn check_agreement(
        &self,
        name: &str,
        eval: EdgeEval,
        ray: &Ray,
        v: &[Vec3; 3],
        got: Option<TriangleHit>,
    ) {
        if projection_underflows(ray, v) {
            return; // outside the documented domain of the sheared test
        }
        let e = self.edges();
        let err = self.edge_errors(eval);
        if (0..3).any(|i| e[i].abs().partial_cmp(&err[i]) != Some(core::cmp::Ordering::Greater)) {
            return; // within the error bound of an edge (or det = 0): either answer is right
        }
        let inside = e.iter().all(|&x| x > 0.0) || e.iter().all(|&x| x < 0.0);
        let reference = F64Reference::solve(ray, v);
        let ctx = || {
            format!(
                "variant {name}: got {got:?}\n  reference {reference:?}\n  edges {e:?}\n  \
                 edge error bounds {err:?}\n{}",
                tri_context(ray, v)
            )
        };
        if !inside {
            reached();
            assert!(
                got.is_none(),
                "hit although the reference is outside by more than the bound\n{}",
                ctx()
            );
            return;
        }
        let Some((t_ref, b_ref)) = reference else {
            panic!(
                "F64Reference::solve reports no hit for a point clearly inside\n{}",
                ctx()
            );
        };
        let det: f64 = e.iter().sum();
        let sum_err: f64 = err.iter().sum();
        let denom = det.abs() - sum_err;
        let ez: f64 = (0..3).map(|i| (e[i] * self.z[i]).abs()).sum();
        if eval == EdgeEval::F32 && !(det.abs() >= F32_DET_MIN && ez <= F32_DEPTH_SUM_MAX) {
            return; // outside the f32 variant's domain (2^-100 ≤ |det|, Σ|e·z| ≤ 2^120)
        }
        if t_ref.is_nan() || t_ref.abs() > F32_DEPTH_SUM_MAX {
            return;
        }
        let dz = self.mz.map(|m| DEPTH_REL * m + UNDERFLOW_ABS);
        let mut dt = ((0..3)
            .map(|i| e[i].abs() * dz[i] + err[i] * (self.z[i].abs() + dz[i]))
            .sum::<f64>()
            + t_ref.abs() * sum_err)
            / denom;
        let t_eval = match eval {
            EdgeEval::ExactF64 => REF_REL,
            EdgeEval::F32 => f64::from(gamma(6)),
        };
        dt += t_eval * ez / det.abs();
        if eval == EdgeEval::F32 {
            // The f32 products eᵢ·zᵢ round absolutely (2⁻¹⁴⁹) when they are subnormal; and
            // `watertight-f32-exact` forms t as Σ (eᵢ/det)·zᵢ, where a barycentric below the
            // normal range rounds absolutely (2⁻¹⁵⁰), times its depth.
            dt += 3.0 * f64::from(f32::from_bits(1)) / det.abs();
            dt += f64::from(f32::from_bits(1)) / 2.0 * self.z.iter().map(|z| z.abs()).sum::<f64>();
        }
        dt += f64::from(F32_UNIT_ROUNDOFF) * t_ref.abs() + F32_SUBNORMAL_ROUNDING_ABS;
        dt *= BOUND_SAFETY;
        let (t_min, t_max) = (f64::from(ray.t_min), f64::from(ray.t_max));
        if !((t_ref - t_min).abs() > dt && (t_ref - t_max).abs() > dt) {
            return; // within the t bound of an interval end: either answer is right
        }
        let expect_hit = t_ref > t_min && t_ref <= t_max;
        reached();
        match got {
            None => assert!(
                !expect_hit,
                "missed: the reference hits at t = {t_ref:e} (bound {dt:e}) with every \
                 barycentric farther from an edge than the bound\n{}",
                ctx()
            ),
            Some(h) => {
                assert!(
                    expect_hit,
                    "hit although the reference t = {t_ref:e} is outside the interval by more \
                     than the bound {dt:e}\n{}",
                    ctx()
                );
                assert!(
                    (f64::from(h.t) - t_ref).abs() <= dt,
                    "t = {:e} differs from the reference {t_ref:e} by more than the bound \
                     {dt:e}\n{}",
                    h.t,
                    ctx()
                );
                for (i, b) in [(1, h.b1), (2, h.b2)] {
                    let db = self.barycentric_error(eval, i, b_ref[i]);
                    assert!(
                        (f64::from(b) - b_ref[i]).abs() <= db,
                        "b{i} = {b:e} differs from the reference {:e} by more than the bound \
                         {db:e}\n{}",
                        b_ref[i],
                        ctx()
                    );
                }
            }
        }
    }
}
