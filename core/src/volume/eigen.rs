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
    if finite {
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
    }
    ([m[0][0], m[1][1], m[2][2]], v)
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
