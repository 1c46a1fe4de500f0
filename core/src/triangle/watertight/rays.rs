//! The watertight family's cull across rays: each stored triangle against [`RAY_LANES`] rays
//! at once, the rays side by side (Embree's packet kernels put rays in lanes the same way),
//! with the same bits as each ray's own cull ([`super::WatertightRay::certain_misses`]).
//!
//! Portable code over lane arrays: every lane is the scalar formula's IEEE operations in its
//! order (never fused), the axis picks are selects, not indexing, so the compiler turns the
//! lane loops into vector instructions of whatever level the caller is compiled for, and a
//! lane's bits cannot depend on the level.

use crate::ray::Ray;
use crate::triangle::{LANES, TriangleLanes};

/// Rays side by side in a [`ShearedRays`].
pub const RAY_LANES: usize = 8;

/// [`RAY_LANES`] rays prepared for the watertight cull, lane by lane: each ray's axis
/// permutation and shear as [`super::WatertightRay::of_valid`] computes them, and its origin in the
/// permuted order. For a ray that is not valid ([`Ray::is_valid`]) a lane's contents are
/// meaningless (never undefined): the caller ignores its bits.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRays {
    /// The axes `kx`, `ky`, `kz` of each lane (each 0, 1 or 2).
    k: [[u32; RAY_LANES]; 3],
    /// The origin's components `o_kx`, `o_ky`, `o_kz` of each lane.
    origin: [[f32; RAY_LANES]; 3],
    /// The shear `d_kx/d_kz`, `d_ky/d_kz` of each lane.
    shear: [[f32; RAY_LANES]; 2],
}

/// `c[k]` for `k` in `0..3` (`c[2]` for any larger `k`), as a select.
#[inline(always)]
fn pick(k: u32, c: [f32; 3]) -> f32 {
    if k == 0 {
        c[0]
    } else if k == 1 {
        c[1]
    } else {
        c[2]
    }
}

impl ShearedRays {
    /// Prepares the first [`RAY_LANES`] rays of `rays`, lane `i` from `rays[i]` (the lanes of
    /// a shorter slice beyond its end are meaningless): the axes of
    /// [`crate::triangle::projection_axes`] (the dominant direction component `kz`, ties to
    /// the lower axis; `kx`, `ky` the next two cyclically, swapped when `d_kz < 0`) and the
    /// shear `(d_kx/d_kz, d_ky/d_kz)` of [`super::WatertightRay::of_valid`], the same comparisons
    /// and the same divisions, lane by lane. (Written out over the lanes rather than calling
    /// `of_valid` per ray, which the compiler does not vectorise: +16 % instructions for a
    /// root leaf's batch of camera rays, callgrind.)
    #[inline(always)]
    #[must_use]
    pub fn new(rays: &[Ray]) -> Self {
        // The rays' components side by side first, then every step lane by lane.
        let (mut d, mut o) = ([[0.0f32; RAY_LANES]; 3], [[0.0f32; RAY_LANES]; 3]);
        for (i, ray) in rays.iter().enumerate().take(RAY_LANES) {
            let l = i & (RAY_LANES - 1);
            for axis in 0..3 {
                d[axis][l] = ray.direction[axis];
                o[axis][l] = ray.origin[axis];
            }
        }
        let mut s = Self {
            k: [[0; RAY_LANES]; 3],
            origin: [[0.0; RAY_LANES]; 3],
            shear: [[0.0; RAY_LANES]; 2],
        };
        for l in 0..RAY_LANES {
            let (dl, ol) = ([d[0][l], d[1][l], d[2][l]], [o[0][l], o[1][l], o[2][l]]);
            let a = [dl[0].abs(), dl[1].abs(), dl[2].abs()];
            let larger = if a[1] > a[0] { a[1] } else { a[0] };
            let kz = if a[2] > larger {
                2
            } else {
                u32::from(a[1] > a[0])
            };
            let (kx, ky) = (
                if kz == 2 { 0 } else { kz + 1 },
                if kz == 0 { 2 } else { kz - 1 },
            );
            let dz = pick(kz, dl);
            let (kx, ky) = if dz < 0.0 { (ky, kx) } else { (kx, ky) };
            s.k[0][l] = kx;
            s.k[1][l] = ky;
            s.k[2][l] = kz;
            s.origin[0][l] = pick(kx, ol);
            s.origin[1][l] = pick(ky, ol);
            s.origin[2][l] = pick(kz, ol);
            s.shear[0][l] = pick(kx, dl) / dz;
            s.shear[1][l] = pick(ky, dl) / dz;
        }
        s
    }

    /// For each ray, the lanes of `lanes` its watertight cull reports
    /// ([`super::WatertightRay::certain_misses`] of that ray, bit for bit: bit `j` for triangle lane
    /// `j`, set when two of the triangle's three `f32` edge functions have certain, opposite
    /// signs; never for a NaN lane).
    #[inline(always)]
    #[must_use]
    pub fn certain_misses(&self, lanes: &TriangleLanes) -> [u32; RAY_LANES] {
        let mut out = [0u32; RAY_LANES];
        for j in 0..LANES {
            let p = |c: &[[f32; LANES]; 3]| [c[0][j], c[1][j], c[2][j]];
            let [v0, v1, v2] = &lanes.v;
            let (p0, p1, p2) = (p(v0), p(v1), p(v2));
            let mut missed = [false; RAY_LANES];
            for (i, m) in missed.iter_mut().enumerate() {
                let [kx, ky, kz] = [self.k[0][i], self.k[1][i], self.k[2][i]];
                let [ox, oy, oz] = [self.origin[0][i], self.origin[1][i], self.origin[2][i]];
                let [sx, sy] = [self.shear[0][i], self.shear[1][i]];
                // As `WatertightRay::certain_misses`: (p_kx − o_kx) − s_x·(p_kz − o_kz), …
                let project = |c: [f32; 3]| {
                    let z = pick(kz, c) - oz;
                    ((pick(kx, c) - ox) - sx * z, (pick(ky, c) - oy) - sy * z)
                };
                let ((ax, ay), (bx, by), (cx, cy)) = (project(p0), project(p1), project(p2));
                let e = [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax];
                let neg = (e[0] < 0.0) | (e[1] < 0.0) | (e[2] < 0.0);
                let pos = (e[0] > 0.0) | (e[1] > 0.0) | (e[2] > 0.0);
                *m = neg & pos;
            }
            for (o, &m) in out.iter_mut().zip(&missed) {
                *o |= u32::from(m) << j;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests;
