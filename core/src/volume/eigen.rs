//! Eigen-decomposition of a symmetric 3×3 matrix by the cyclic Jacobi method, in `f64`.
//!
//! Each rotation zeroes one off-diagonal entry; a sweep visits the three. Convergence is
//! quadratic once the off-diagonal part is small, so a few sweeps reach `f64` precision; the
//! loop stops after [`JACOBI_MAX_SWEEPS`] whatever happens (no input can make it run longer
//! or panic). The eigenvectors are the columns of the accumulated rotation: orthonormal up to
//! a few `f64` roundings per sweep.

// Index loops mirror the matrix formulas (rows, columns, rotation planes).
#![allow(clippy::needless_range_loop)]

/// Largest number of Jacobi sweeps. Unitless. Symmetric 3×3 matrices converge to `f64`
/// precision in about 5 sweeps; 32 is a guard against a non-converging input (NaN), not a
/// tuning parameter: the result is then whatever rotation was reached, still orthonormal.
pub const JACOBI_MAX_SWEEPS: usize = 32;

/// Eigenvalues (unsorted) and eigenvectors (the columns of the returned matrix, `v[row][col]`)
/// of the symmetric matrix `a` (only its upper triangle is read). A zero or non-finite matrix
/// returns its diagonal and the identity.
///
/// Any finite matrix is solved, up to entries near `f64::MAX`: the rotations run on `a` scaled
/// by a power of two that brings its largest entry into `[1, 2)` (exact, except that entries
/// below `2⁻¹⁰²²` of the largest lose bits they could not contribute anyway), and the
/// eigenvalues are scaled back. An eigenvalue beyond `f64::MAX` (`|λ| ≤ 3·max|aᵢⱼ|`) comes
/// back infinite.
#[must_use]
pub fn symmetric_eigen(a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut m = a;
    for i in 0..3 {
        for j in 0..i {
            m[i][j] = m[j][i];
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let finite = m.iter().flatten().all(|x| x.is_finite());
    let largest = m.iter().flatten().fold(0.0f64, |acc, x| acc.max(x.abs()));
    if finite && largest > 0.0 {
        // Without this a difference of two diagonal entries near ±f64::MAX overflows and
        // every rotation is skipped.
        let exponent = largest_exponent(largest);
        for x in m.iter_mut().flatten() {
            *x = scale_by_pow2(*x, -exponent);
        }
        for _ in 0..JACOBI_MAX_SWEEPS {
            let off = m[0][1].abs() + m[0][2].abs() + m[1][2].abs();
            let diag = m[0][0].abs() + m[1][1].abs() + m[2][2].abs();
            if !(off > diag * crate::float::F64_UNIT_ROUNDOFF) {
                break;
            }
            for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
                rotate(&mut m, &mut v, p, q);
            }
        }
        let back = |x: f64| scale_by_pow2(x, exponent);
        return ([back(m[0][0]), back(m[1][1]), back(m[2][2])], v);
    }
    ([m[0][0], m[1][1], m[2][2]], v)
}

/// The unbiased binary exponent of a positive finite `x`, in `[-1022, 1023]` (a subnormal
/// reads −1022).
fn largest_exponent(x: f64) -> i32 {
    let biased = ((x.to_bits() >> 52) & 0x7ff) as i32;
    (biased - 1023).max(-1022)
}

/// `x · 2ᵏ` for `k` in `[-1023, 1023]`, in two steps whose factors are normal: exact unless
/// the result is subnormal (then rounded once per step) or overflows.
fn scale_by_pow2(x: f64, k: i32) -> f64 {
    let first = k.clamp(-1022, 1023);
    x * pow2(first) * pow2(k - first)
}

/// `2ᵏ` for `k` in `[-1022, 1023]`, exact (built from its bits).
fn pow2(k: i32) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// One Jacobi rotation in the `(p, q)` plane that zeroes `m[p][q]` (Golub & Van Loan,
/// Algorithm 8.4.1, the stable choice of `tan θ` of smaller magnitude).
fn rotate(m: &mut [[f64; 3]; 3], v: &mut [[f64; 3]; 3], p: usize, q: usize) {
    let apq = m[p][q];
    if apq == 0.0 {
        return;
    }
    let tau = (m[q][q] - m[p][p]) / (2.0 * apq);
    let t = if tau.is_finite() {
        tau.signum() / (tau.abs() + libm::sqrt(1.0 + tau * tau).max(tau.abs()))
    } else {
        0.0
    };
    if t == 0.0 || !t.is_finite() {
        return;
    }
    let c = 1.0 / libm::sqrt(1.0 + t * t);
    let s = t * c;
    // m ← Jᵀ m J with J the rotation in the (p, q) plane.
    for k in 0..3 {
        let (mkp, mkq) = (m[k][p], m[k][q]);
        m[k][p] = c * mkp - s * mkq;
        m[k][q] = s * mkp + c * mkq;
    }
    for k in 0..3 {
        let (mpk, mqk) = (m[p][k], m[q][k]);
        m[p][k] = c * mpk - s * mqk;
        m[q][k] = s * mpk + c * mqk;
    }
    m[p][q] = 0.0;
    m[q][p] = 0.0;
    for row in v.iter_mut() {
        let (vp, vq) = (row[p], row[q]);
        row[p] = c * vp - s * vq;
        row[q] = s * vp + c * vq;
    }
}
