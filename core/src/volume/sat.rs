//! The OBB–OBB separating-axis test with its rounding bounds.
//!
//! Notation: box `A` has centre `c_a`, axes `aᵢ` (rows of `A`), half-extents `e_a`; box `B`
//! likewise; `Δ = c_b − c_a`, `tᵢ = aᵢ·Δ`, `uⱼ = bⱼ·Δ`, `Rᵢⱼ = aᵢ·bⱼ`, all in `f32` after
//! [`super::rescale::rescale_factor`]. `τ =` [`super::OBB_ORTHONORMAL_TOL`] bounds the axes'
//! deviation from orthonormal.
//!
//! **Exact geometry.** An [`Obb`] is the intersection of three slabs `|aᵢ·(x − c)| ≤ eᵢ`; its
//! edges run along the dual basis `αᵢ` (the columns of `A⁻¹`, `αᵢ·aⱼ = δᵢⱼ`), and with the
//! Gram matrix within `τ` of the identity, `|αᵢ − aᵢ| ≤ 4τ(1 + τ)`. Its support along `L` is
//! `Σᵢ e_aᵢ|αᵢ·L|`. The test declares "apart" only when, along one axis `L` of the 15, the
//! centres' separation `|Δ·L|` exceeds an **upper bound** of the two supports plus the
//! rounding of `Δ·L`: that is a proof of separation whatever the axes' deviation.
//!
//! **Bounds.** With `S = Σ|Δₖ| + Σe_a + Σe_b` (computed once):
//! * `|Rᵢⱼ|` is within `γ₃(1 + τ)²` of `|aᵢ·bⱼ|`, and `|aᵢ·bⱼ|` within `4τ(1 + τ)` of the
//!   dual-basis products `|αᵢ·bⱼ|`, `|aᵢ·βⱼ|` the face supports need; for the edge axes
//!   `L = aᵢ × bⱼ` the terms `|αₖ·L|` are within `8τ(1 + τ)²` of the `|R|` entries the formula
//!   uses (`aᵢ₊₁ × aᵢ₊₂` is within `4τ` of `±aᵢ`). [`OBB_ABS_R_EPSILON`] covers the largest,
//!   `8τ + γ₃ + O(τ²) = 67u + O(u²)`.
//! * The centres' projections: `tᵢ`, `uⱼ` take `γ₄` of `Σ|Δₖ|`; the edge-axis form
//!   `t_{i+2}R_{i+1,j} − t_{i+1}R_{i+2,j}` equals `(aᵢ₊₂ × aᵢ₊₁)·(Δ × bⱼ)` (Binet–Cauchy),
//!   within `4τ(1 + τ)|Δ|` of `±(aᵢ × bⱼ)·Δ`, plus `γ₉` of `Σ|Δₖ|` of rounding. The dual
//!   term `αᵢ·(aᵢ × bⱼ)` the formula omits is at most `4τ(1 + τ)` per unit of `e_aᵢ`.
//!   Together with the `γ₆` rounding of the right-hand sums these are below `80u·S`;
//!   [`OBB_SAT_PAD_REL`] `= γ₁₂₈` of `S` covers them.
//!
//! Near-parallel edges make `aᵢ × bⱼ` short and both sides of its comparison nearly zero:
//! the `ε` on `|R|` and the padding then keep the comparison from declaring a separation
//! that rounding invented (Ericson's classic robustness fix), and the face axes decide.

use super::Obb;
use super::rescale::{UNDERFLOW_PAD_ABS, max_abs, rescale_factor};
use crate::float::gamma;

/// `ε` added to every `|Rᵢⱼ| = |aᵢ·bⱼ|` of the OBB–OBB test (the "absolute rotation matrix"),
/// unitless: `gamma(80)` ≈ 4.8e-6.
///
/// Covers the rounding of `Rᵢⱼ` (`γ₃`) and the difference between the `f32` axes and the
/// exact boxes' edge directions and face normals (`8τ` with `τ =`
/// [`super::OBB_ORTHONORMAL_TOL`] `= 8u`): `67u` at most, see the module docs. For
/// near-parallel edges it is what keeps the degenerate cross-product axes from separating.
pub const OBB_ABS_R_EPSILON: f32 = gamma(80);

/// Padding of every comparison of the OBB–OBB test relative to
/// `S = Σ|c_b − c_a|ₖ + Σe_a + Σe_b`, unitless: `gamma(128)` ≈ 7.6e-6 (the centre terms'
/// rounding and frame deviation, below `80u·S`; see the module docs).
pub const OBB_SAT_PAD_REL: f32 = gamma(128);

/// False-positive band of the OBB–OBB test relative to `S`, unitless (`gamma(512)` ≈
/// 3.1e-5): boxes reported overlapping have, along **each** of the 15 axes `L` (`aᵢ`, `bⱼ`,
/// `aᵢ × bⱼ`, not normalised), a gap between their projections of at most
/// `OBB_OBB_BAND_REL·S +` [`super::rescale::BAND_ABS_PER_MAGNITUDE`]`·max(m, 1)`:
/// `OBB_SAT_PAD_REL`, twice `ε` per unit of `Σe`, the frame terms, and the sums' rounding.
/// Measured along the unit axis that is `1/|L|` times more: a pair separated only across two
/// nearly parallel edges (sin of their angle `≲ 1e-4`) may be reported overlapping at a
/// visible distance, the usual price of the `ε`.
pub const OBB_OBB_BAND_REL: f32 = gamma(512);

/// The bit patterns of a box's parameters: a total order that makes the test symmetric.
fn key(o: &Obb) -> [u32; 15] {
    let mut k = [0u32; 15];
    let [x, y, z] = o.axes();
    for (slot, v) in k.iter_mut().zip(
        [o.center(), x, y, z, o.half_extents()]
            .iter()
            .flat_map(|v| v.to_array()),
    ) {
        *slot = v.to_bits();
    }
    k
}

/// The test (see the module docs). The boxes are taken in a fixed order (by their bit
/// patterns): the formulas are not symmetric in rounding, the answer is.
pub(crate) fn obb_obb(a: &Obb, b: &Obb) -> bool {
    let (a, b) = if key(a) <= key(b) { (a, b) } else { (b, a) };
    let m = max_abs(a.center())
        .max(max_abs(b.center()))
        .max(max_abs(a.half_extents()))
        .max(max_abs(b.half_extents()));
    let k = rescale_factor(m);
    let delta = b.center() * k - a.center() * k;
    let ea = (a.half_extents() * k).to_array();
    let eb = (b.half_extents() * k).to_array();
    let (aa, ba) = (a.axes(), b.axes());
    let s = delta.abs().element_sum() + (ea.iter().sum::<f32>() + eb.iter().sum::<f32>());
    let pad = OBB_SAT_PAD_REL * s + UNDERFLOW_PAD_ABS;
    let t = aa.map(|x| x.dot(delta));
    let u = ba.map(|x| x.dot(delta));
    let mut r = [[0.0f32; 3]; 3];
    let mut abs_r = [[0.0f32; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = aa[i].dot(ba[j]);
            abs_r[i][j] = r[i][j].abs() + OBB_ABS_R_EPSILON;
        }
    }
    let separated = |lhs: f32, rhs: f32| lhs.abs() > rhs + pad;
    for i in 0..3 {
        let rb = eb[0] * abs_r[i][0] + eb[1] * abs_r[i][1] + eb[2] * abs_r[i][2];
        if separated(t[i], ea[i] + rb) {
            return false;
        }
    }
    for j in 0..3 {
        let ra = ea[0] * abs_r[0][j] + ea[1] * abs_r[1][j] + ea[2] * abs_r[2][j];
        if separated(u[j], ra + eb[j]) {
            return false;
        }
    }
    for i in 0..3 {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        for j in 0..3 {
            let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
            let lhs = t[i2] * r[i1][j] - t[i1] * r[i2][j];
            let ra = ea[i1] * abs_r[i2][j] + ea[i2] * abs_r[i1][j];
            let rb = eb[j1] * abs_r[i][j2] + eb[j2] * abs_r[i][j1];
            if separated(lhs, ra + rb) {
                return false;
            }
        }
    }
    true
}
