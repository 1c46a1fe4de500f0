//! [`WatertightRay`]: the per-ray data of the watertight family (the axis permutation and the
//! shear that map the ray to the `+z` axis through the origin), the projection of a triangle's
//! vertices with it, the family's lane cull on their `f32` edge functions
//! ([`WatertightRay::certain_misses`], [`WatertightRay::certain_misses2`]) and the half-open
//! crossing rule ([`WatertightRay::crossing_sign`]).

use super::edges::exact_edges;
use crate::ray::Ray;
use crate::simd::F32x4;
use crate::simd::level::{Sheared8, SimdLevel};
use crate::triangle::{LANES, TriangleLanes};
use glam::Vec3;

/// Per-ray data of the watertight test: the axis permutation that makes the largest direction
/// component `z`, and the shear that maps the ray to the `+z` axis through the origin.
///
/// Made only by [`WatertightRay::new`] and [`WatertightRay::of_valid`] (the fields are
/// private): the permutation and the shear are always those of a ray, so a test answers
/// about that ray. (A shear made up by hand would report hits off the ray.)
///
/// ```compile_fail,E0451
/// use halfray_core::triangle::WatertightRay;
/// use halfray_core::Vec3;
/// // Not possible: the fields are private.
/// let made_up = WatertightRay { k: [0, 1, 2], shear: Vec3::new(5.0, 0.0, 1.0) };
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatertightRay {
    /// Permuted axes `(kx, ky, kz)`; `kz = argmax |d_i|` (ties: lowest index), `kx, ky` follow
    /// cyclically and are swapped when `d_kz < 0` so that the permutation and the scaling by
    /// `1/d_kz` together preserve orientation.
    pub(crate) k: [usize; 3],
    /// Shear `(d_kx/d_kz, d_ky/d_kz, 1/d_kz)`.
    pub(crate) shear: Vec3,
}

impl WatertightRay {
    /// Prepares `ray`; `None` for an invalid ray.
    #[inline(always)]
    #[must_use]
    pub fn new(ray: &Ray) -> Option<Self> {
        ray.is_valid().then(|| Self::of_valid(ray))
    }

    /// Prepares `ray`, which the caller has checked ([`Ray::is_valid`]); for another ray the
    /// result is meaningless (never undefined: no check is skipped that memory safety needs).
    #[inline(always)]
    #[must_use]
    pub fn of_valid(ray: &Ray) -> Self {
        let d = ray.direction;
        let [kx, ky, kz] = crate::triangle::projection_axes(d);
        // The three quotients in one four-lane division (each lane the same IEEE quotient).
        // Indexed through a four-lane array with `& 3`: no bounds check, no branch.
        let c = [d.x, d.y, d.z, 0.0];
        let shear = glam::Vec3A::new(c[kx & 3], c[ky & 3], 1.0) / glam::Vec3A::splat(c[kz & 3]);
        Self {
            k: [kx, ky, kz],
            shear: shear.into(),
        }
    }

    /// `k` as indices the compiler knows are below 3: `min(2)` keeps every index in range
    /// without a bounds check (each is 0, 1 or 2 already).
    #[inline(always)]
    pub(super) fn axes(&self) -> [usize; 3] {
        let [kx, ky, kz] = self.k;
        [kx.min(2), ky.min(2), kz.min(2)]
    }

    /// The lanes of `lanes` among whose three `f32` edge functions (the filter of
    /// [`Watertight`]) two have certain, opposite signs: the triangles both watertight tests
    /// miss (the exact signs of those two already differ, whatever the third). The same
    /// `f32` operations as the projection and the scalar filter, lane by lane (no
    /// fused multiply-add), so a lane is reported exactly when the scalar test rejects it on
    /// its `f32` signs; NaN lanes (unused ones among them) are never reported.
    ///
    /// [`Watertight`]: super::Watertight
    #[inline(always)]
    #[must_use]
    pub fn certain_misses(&self, origin: Vec3, lanes: &TriangleLanes) -> u32 {
        let [kx, ky, kz] = self.axes();
        let o = origin.to_array();
        let (ox, oy, oz) = (
            F32x4::splat(o[kx]),
            F32x4::splat(o[ky]),
            F32x4::splat(o[kz]),
        );
        let (sx, sy) = (F32x4::splat(self.shear.x), F32x4::splat(self.shear.y));
        // Sheared 2-D coordinates of each vertex: (p_kx − o_kx) − s_x·(p_kz − o_kz), …
        let project = |p: &[[f32; LANES]; 3]| {
            let z = F32x4::load(&p[kz]).sub(oz);
            (
                F32x4::load(&p[kx]).sub(ox).sub(sx.mul(z)),
                F32x4::load(&p[ky]).sub(oy).sub(sy.mul(z)),
            )
        };
        let [p0, p1, p2] = &lanes.v;
        let ((ax, ay), (bx, by), (cx, cy)) = (project(p0), project(p1), project(p2));
        // The filter of `intersect_prepared`, argument for argument.
        let e = [
            cx.mul(by).sub(cy.mul(bx)).sign_bits(),
            ax.mul(cy).sub(ay.mul(cx)).sign_bits(),
            bx.mul(ay).sub(by.mul(ax)).sign_bits(),
        ];
        // A zero or NaN edge sets neither bit: only certain signs count.
        let any = e[0] | e[1] | e[2];
        any & (any >> 4) & 0xF
    }

    /// [`WatertightRay::certain_misses`] of two groups, `first` (bits 0–3) and `second`
    /// (bits 4–7), with `level`'s eight-lane kernel when it has one (the same bits either
    /// way).
    #[inline(always)]
    #[must_use]
    pub fn certain_misses2<L: SimdLevel>(
        &self,
        level: L,
        origin: Vec3,
        first: &TriangleLanes,
        second: &TriangleLanes,
    ) -> u32 {
        let k = self.axes();
        let o = origin.to_array();
        let q = Sheared8 {
            first: permuted_rows(first, k),
            second: permuted_rows(second, k),
            origin: [o[k[0]], o[k[1]], o[k[2]]],
            shear: [self.shear.x, self.shear.y],
        };
        level.certain_misses8(&q).unwrap_or_else(|| {
            crate::triangle::pair_mask(
                self.certain_misses(origin, first),
                self.certain_misses(origin, second),
            )
        })
    }

    /// How the ray crosses triangle `v` when **each point of the plane is counted once**: `+1`
    /// or `−1` (the sign of the watertight test's `det`, `+1` when the triangle faces the ray,
    /// as [`TriangleHit::front_face`]) when the ray, moved by an infinitesimal `(ε, ε²)` in
    /// the sheared plane, passes strictly inside the triangle; `0` otherwise.
    ///
    /// Where the closed test ([`Watertight`]) reports a ray through an edge shared by two
    /// triangles for both, and through a vertex for its whole fan, this rule (symbolic
    /// perturbation: the half-open "top-left" rule of rasterisers) keeps exactly one of them,
    /// and counts a silhouette edge (one triangle facing the ray, its neighbour facing away)
    /// for both or neither: summed over a closed, consistently oriented mesh, the signs are
    /// the change of its winding number along the line, exactly, whatever edge or vertex the
    /// line passes through. Exact: the edge functions are the exact `f64` differences of
    /// exact products of the sheared coordinates, and a zero one is decided by the sign of an
    /// `f32` coordinate difference, which rounding cannot change. `0` for a triangle whose
    /// projection is degenerate (`det = 0`). A non-zero result implies that the closed test
    /// reports the crossing (when its `t` lies in the interval).
    ///
    /// [`TriangleHit::front_face`]: crate::triangle::TriangleHit::front_face
    /// [`Watertight`]: super::Watertight
    #[must_use]
    pub fn crossing_sign(&self, origin: Vec3, v: &[Vec3; 3]) -> i8 {
        let (x, y, _) = self.project_triangle(origin, v);
        let ([ax, bx, cx], [ay, by, cy]) = (x, y);
        // Edge functions at the ray (the sheared origin) of the edges C→B, A→C, B→A, the
        // operands of `Watertight`'s edges, and each edge's direction T − S.
        let [e0, e1, e2] = exact_edges(x, y);
        let edges = [
            (e0, bx - cx, by - cy),
            (e1, cx - ax, cy - ay),
            (e2, ax - bx, ay - by),
        ];
        // E_ST(p + (ε, ε²)) = E_ST(p) + d_x·ε² − d_y·ε: when E is exactly zero its sign is
        // −sign(d_y), or sign(d_x) for a horizontal edge (d = 0 only for a degenerate
        // projection, whose det is 0).
        let sign = |x: f64| i8::from(x > 0.0) - i8::from(x < 0.0);
        let perturbed = |(e, dx, dy): (f64, f32, f32)| -> i8 {
            if e != 0.0 {
                sign(e)
            } else if dy != 0.0 {
                -sign(f64::from(dy))
            } else {
                sign(f64::from(dx))
            }
        };
        let s = edges.map(perturbed);
        if s[0] != 0 && s[0] == s[1] && s[1] == s[2] {
            s[0]
        } else {
            0
        }
    }

    /// The three vertices projected with [`WatertightRay::project`]: `([x'], [y'], [z'])`.
    #[inline(always)]
    pub(in crate::triangle) fn project_triangle(
        &self,
        origin: Vec3,
        v: &[Vec3; 3],
    ) -> ([f32; 3], [f32; 3], [f32; 3]) {
        let (ax, ay, az) = self.project(origin, v[0]);
        let (bx, by, bz) = self.project(origin, v[1]);
        let (cx, cy, cz) = self.project(origin, v[2]);
        ([ax, bx, cx], [ay, by, cy], [az, bz, cz])
    }

    /// The sheared 2-D coordinates of `p − o` and its scaled depth `(x', y', z')`. Plain `f32`
    /// operations (never fused), so the result is a deterministic function of the vertex: a
    /// vertex shared by several triangles projects to the same point in all of them.
    #[inline(always)]
    fn project(&self, origin: Vec3, p: Vec3) -> (f32, f32, f32) {
        let a = p - origin;
        // Indexed through a four-lane array with `& 3`: no bounds check (`k` holds axes 0–2).
        let a = [a.x, a.y, a.z, 0.0];
        let [kx, ky, kz] = self.k;
        let z = a[kz & 3];
        (
            a[kx & 3] - self.shear.x * z,
            a[ky & 3] - self.shear.y * z,
            self.shear.z * z,
        )
    }
}

/// The rows of `lanes`, vertex by vertex, in the axis order `k` (each axis `< 3`).
#[inline(always)]
fn permuted_rows(lanes: &TriangleLanes, k: [usize; 3]) -> [[&[f32; LANES]; 3]; 3] {
    // Written out: `array::map` is not always inlined, and this is on the leaf path.
    let [a, b, c] = &lanes.v;
    let [kx, ky, kz] = k;
    [
        [&a[kx], &a[ky], &a[kz]],
        [&b[kx], &b[ky], &b[kz]],
        [&c[kx], &c[ky], &c[kz]],
    ]
}
