//! Planar simple polygons (convex or concave) with a fixed vertex capacity: the ray–plane hit
//! ([`crate::plane`]), then a 2-D crossing-number test (Haines, "Point in Polygon Strategies",
//! Graphics Gems IV).
//!
//! **Projection.** The hit point and the vertices are projected onto the coordinate plane where
//! the polygon's projection is largest: the axis `k = argmax |N_k|` of the (Newell, `f64`)
//! normal is dropped. **Tie rule:** among equal `|N_k|` the lowest index wins (x before y
//! before z), so the choice is a deterministic function of the vertices. The 2-D axes are
//! `(k+1, k+2) mod 3`.
//!
//! **Crossings.** A 2-D test ray goes from the projected hit point `P` towards `+u`. Edge
//! `(a, b)` is counted iff it straddles the test ray's line under the **half-open rule**
//! `(a_v > P_v) ≠ (b_v > P_v)` and its crossing lies strictly on the `+u` side of `P`, decided
//! without a division by the sign of `orient(a, b, P)` (evaluated in `f64`) chosen by the edge's
//! direction. Consequences:
//! * a vertex lying exactly on the test ray counts as *below-or-on*: of the two edges sharing
//!   it, a pass-through vertex is counted exactly once and a touching vertex 0 or 2 times;
//! * horizontal edges (`a_v = b_v`) are never counted;
//! * **even–odd rule**: an odd count is inside.
//!
//! **On-edge policy** (a hit exactly on the projected boundary): deterministic and half-open,
//! like a rasteriser's fill rule. A point on an edge whose interior lies towards `+u` (a "left"
//! edge) is inside, on an edge whose interior lies towards `−u` (a "right" edge) outside; on a
//! horizontal edge, inside when the interior lies towards `+v` (a "bottom" edge). Two coplanar
//! polygons sharing an edge therefore claim a point of that edge exactly once *when they compute
//! the same `P`*; since `P` is a rounded plane hit computed from each polygon's own plane, this
//! is **not watertight** across shared edges in general (triangles are:
//! [`crate::triangle::Watertight`]).
//!
//! **Validation** ([`Polygon::new`]): 3 to `N` finite vertices; twice the area (the Newell normal
//! about the centroid, in `f64`) above [`POLYGON_MIN_AREA_REL`]` × diag²` (else
//! [`GeometryError::Degenerate`]); every vertex within [`PLANARITY_REL`]` × diag` of the plane
//! through the centroid (else [`GeometryError::NonPlanar`]); `diag` is the bounding-box
//! diagonal. Both tests are relative, and the plane takes the unit normal (normalised in
//! `f64`), so a polygon is accepted or refused alike at every scale of finite `f32`
//! coordinates. Simplicity (no self-intersection) is *not* checked: a self-intersecting outline
//! is classified by the even–odd rule. The area test is on the **signed** (Newell) area, in
//! which the lobes of a self-intersecting outline that wind in opposite directions cancel: a
//! bow-tie with equal lobes has a zero normal and is refused as
//! [`GeometryError::Degenerate`] (its plane is not determined by that normal), one with
//! unequal lobes is accepted if the difference passes, with the normal of the lobe of larger
//! area (so a ray hitting the other lobe's front side sees a back face).

use crate::error::GeometryError;
use crate::hit::Hit;
use crate::plane::Plane;
use crate::ray::Ray;
use crate::tolerance::{PLANARITY_REL, POLYGON_MIN_AREA_REL};
use glam::{DVec3, Vec3};

/// A planar polygon of at most `N` vertices, stored inline (`heapless::Vec`).
#[derive(Clone, Debug)]
pub struct Polygon<const N: usize> {
    vertices: heapless::Vec<Vec3, N>,
    plane: Plane,
    axis: usize,
}

impl<const N: usize> Polygon<N> {
    /// Validates and stores `vertices` (in order; counter-clockwise seen from the side the
    /// normal points to).
    ///
    /// # Errors
    ///
    /// [`GeometryError::VertexCount`] for fewer than 3 or more than
    /// `N` vertices, [`GeometryError::NonFinite`], [`GeometryError::Degenerate`],
    /// [`GeometryError::NonPlanar`] (module documentation).
    pub fn new(vertices: &[Vec3]) -> Result<Self, GeometryError> {
        let n = vertices.len();
        if n < 3 || n > N {
            return Err(GeometryError::VertexCount);
        }
        if !vertices.iter().all(|&v| v.is_finite()) {
            return Err(GeometryError::NonFinite);
        }
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut sum = DVec3::ZERO;
        for v in vertices {
            let v = v.as_dvec3();
            lo = lo.min(v);
            hi = hi.max(v);
            sum += v;
        }
        let centroid = sum / n as f64;
        let diag = (hi - lo).length();
        let mut normal = DVec3::ZERO;
        for i in 0..n {
            let a = vertices[i].as_dvec3() - centroid;
            let b = vertices[(i + 1) % n].as_dvec3() - centroid;
            normal += a.cross(b);
        }
        let twice_area = normal.length();
        if !(twice_area > POLYGON_MIN_AREA_REL as f64 * diag * diag) {
            return Err(GeometryError::Degenerate);
        }
        let unit = normal / twice_area;
        let tolerance = PLANARITY_REL as f64 * diag;
        if vertices
            .iter()
            .any(|v| (v.as_dvec3() - centroid).dot(unit).abs() > tolerance)
        {
            return Err(GeometryError::NonPlanar);
        }
        let axis = normal.abs().max_position();
        // The unit normal: the raw Newell normal scales as the square of the polygon's size
        // and would overflow or underflow `f32` for valid polygons of extreme size.
        let plane = Plane::new(centroid.as_vec3(), unit.as_vec3())?;
        let vertices =
            heapless::Vec::from_slice(vertices).map_err(|_| GeometryError::VertexCount)?;
        Ok(Self {
            vertices,
            plane,
            axis,
        })
    }

    /// The vertices, in order.
    #[inline]
    #[must_use]
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// The polygon's plane (through the centroid, unit Newell normal).
    #[inline]
    #[must_use]
    pub fn plane(&self) -> &Plane {
        &self.plane
    }

    /// The unit normal (counter-clockwise vertices face it).
    #[inline]
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.plane.normal()
    }

    /// The dropped axis `k` of the projection (module documentation, tie rule included).
    #[inline]
    #[must_use]
    pub fn dominant_axis(&self) -> usize {
        self.axis
    }

    /// The crossing-number test of a point assumed to lie in the polygon's plane (only its
    /// projection is used): `true` inside under the even–odd rule and the on-edge policy of
    /// the module documentation. Non-finite points are outside.
    #[must_use]
    pub fn contains_projected(&self, p: Vec3) -> bool {
        if !p.is_finite() {
            return false;
        }
        let (iu, iv) = ((self.axis + 1) % 3, (self.axis + 2) % 3);
        let (pu, pv) = (p[iu], p[iv]);
        let n = self.vertices.len();
        let mut inside = false;
        for i in 0..n {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % n];
            let (a_above, b_above) = (a[iv] > pv, b[iv] > pv);
            if a_above == b_above {
                continue;
            }
            // orient(a, b, P) > 0 iff P is left of a→b. For an upward edge (b above) the
            // crossing is on the +u side of P iff P is left of the edge; downward, iff right.
            let (au, av) = (a[iu] as f64, a[iv] as f64);
            let orient =
                (b[iu] as f64 - au) * (pv as f64 - av) - (b[iv] as f64 - av) * (pu as f64 - au);
            if (b_above && orient > 0.0) || (!b_above && orient < 0.0) {
                inside = !inside;
            }
        }
        inside
    }

    /// Ray–polygon intersection: [`Plane::intersect`] (with its point, error bound, normal,
    /// `front_face` and in-plane `uv`), kept when [`Polygon::contains_projected`] accepts the
    /// hit point. Invalid rays and rays parallel to the plane give `None`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let hit = self.plane.intersect(ray)?;
        self.contains_projected(hit.point).then_some(hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::{TriangleIntersector, Watertight};

    /// Half-width of the band around the star's boundary that the grid test skips (world
    /// units; the star's outer radius is 1). The test's own boundary radius is computed in
    /// `f32` (a few unit roundoffs off), so points closer to it than this are not judged.
    const STAR_BOUNDARY_BAND: f32 = 1e-3;

    type P = Polygon<16>;

    fn v(x: f32, y: f32) -> Vec3 {
        Vec3::new(x, y, 0.0)
    }

    /// A ray straight down onto z = 0 at (x, y): the projected point is exactly (x, y).
    fn down(x: f32, y: f32) -> Ray {
        Ray::new(Vec3::new(x, y, 3.0), -Vec3::Z)
    }

    #[test]
    fn constructor_validation() {
        assert_eq!(
            P::new(&[v(0.0, 0.0), v(1.0, 0.0)]).unwrap_err(),
            GeometryError::VertexCount
        );
        let many = [v(0.0, 0.0); 17];
        assert_eq!(P::new(&many).unwrap_err(), GeometryError::VertexCount);
        assert_eq!(
            P::new(&[v(0.0, 0.0), v(f32::NAN, 0.0), v(0.0, 1.0)]).unwrap_err(),
            GeometryError::NonFinite
        );
        // P8: zero area (collinear, repeated point, back-and-forth) → degenerate.
        assert_eq!(
            P::new(&[v(0.0, 0.0), v(1.0, 1.0), v(2.0, 2.0)]).unwrap_err(),
            GeometryError::Degenerate
        );
        assert_eq!(
            P::new(&[v(1.0, 1.0); 4]).unwrap_err(),
            GeometryError::Degenerate
        );
        assert_eq!(
            P::new(&[v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(1.0, 0.0)]).unwrap_err(),
            GeometryError::Degenerate
        );
        // Non-planar: one vertex of a unit square lifted by a hundred times the tolerance.
        assert_eq!(
            P::new(&[
                v(0.0, 0.0),
                v(1.0, 0.0),
                Vec3::new(1.0, 1.0, 100.0 * PLANARITY_REL),
                v(0.0, 1.0)
            ])
            .unwrap_err(),
            GeometryError::NonPlanar
        );
        // ... but a lift far below the tolerance (scene-file rounding) is accepted.
        assert!(
            P::new(&[
                v(0.0, 0.0),
                v(1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.01 * PLANARITY_REL),
                v(0.0, 1.0)
            ])
            .is_ok()
        );
        let sq = P::new(&[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]).unwrap();
        assert_eq!(sq.normal(), Vec3::Z);
        assert_eq!(sq.dominant_axis(), 2);
        assert_eq!(sq.vertices().len(), 4);
    }

    /// Self-intersecting outlines (module documentation, *validation*): the equal-lobe bow-tie
    /// `(0,0) (2,2) (2,0) (0,2)` has a zero signed area and is refused; the bow-tie
    /// `(0,0) (4,4) (4,0) (0,1)`, edges crossing at `(0.8, 0.8)`, has lobes of areas `0.4`
    /// (counter-clockwise) and `6.4` (clockwise): accepted with the larger lobe's normal `−z`,
    /// and under the even–odd rule a point in either lobe is inside.
    #[test]
    fn self_intersecting_outlines_use_the_signed_area() {
        assert_eq!(
            P::new(&[v(0.0, 0.0), v(2.0, 2.0), v(2.0, 0.0), v(0.0, 2.0)]).err(),
            Some(GeometryError::Degenerate)
        );
        let p = P::new(&[v(0.0, 0.0), v(4.0, 4.0), v(4.0, 0.0), v(0.0, 1.0)]).unwrap();
        assert_eq!(p.normal(), -Vec3::Z);
        for (x, y, inside) in [
            (3.5, 1.0, true),
            (0.2, 0.5, true),
            (2.0, 3.0, false),
            (0.5, 1.5, false),
        ] {
            assert_eq!(p.intersect(&down(x, y)).is_some(), inside, "({x}, {y})");
        }
    }

    #[test]
    fn concave_l_shape() {
        // L: the square [0,2]² minus [1,2]×[1,2].
        let l = P::new(&[
            v(0.0, 0.0),
            v(2.0, 0.0),
            v(2.0, 1.0),
            v(1.0, 1.0),
            v(1.0, 2.0),
            v(0.0, 2.0),
        ])
        .unwrap();
        for (x, y, inside) in [
            (0.5, 0.5, true),
            (1.5, 0.5, true),
            (0.5, 1.5, true),
            (1.5, 1.5, false),
            (2.5, 0.5, false),
            (-0.5, 0.5, false),
            (0.5, 2.5, false),
            (1.25, 1.75, false),
        ] {
            assert_eq!(l.intersect(&down(x, y)).is_some(), inside, "({x}, {y})");
        }
        let h = l.intersect(&down(0.5, 0.5)).unwrap();
        assert_eq!(h.point, v(0.5, 0.5));
        assert_eq!(h.t, 3.0);
        assert!(h.front_face, "a ray along −z arrives against the +z normal");
    }

    #[test]
    fn star_polygon() {
        // A 5-pointed star (10 vertices, simple, concave), outer radius 1, inner 0.4.
        let mut verts = [Vec3::ZERO; 10];
        for (i, p) in verts.iter_mut().enumerate() {
            let ang = core::f32::consts::FRAC_PI_2 + i as f32 * core::f32::consts::PI / 5.0;
            let r = if i % 2 == 0 { 1.0 } else { 0.4 };
            *p = v(r * libm::cosf(ang), r * libm::sinf(ang));
        }
        let star = P::new(&verts).unwrap();
        assert!(star.contains_projected(v(0.0, 0.0)));
        assert!(star.contains_projected(v(0.0, 0.9))); // inside the top point
        assert!(!star.contains_projected(v(0.0, -0.5))); // in the notch between two points
        assert!(!star.contains_projected(v(0.5, 0.5)));
        assert!(!star.contains_projected(v(2.0, 0.0)));
        // Against an independent angular test on a grid.
        let mut checked = 0;
        for i in 0..41 {
            for j in 0..41 {
                let p = v(
                    -1.0 + i as f32 * 0.05 + 0.0123,
                    -1.0 + j as f32 * 0.05 + 0.0071,
                );
                let r = p.length();
                let ang = libm::atan2f(p.y, p.x) - core::f32::consts::FRAC_PI_2;
                let sector = ang.rem_euclid(2.0 * core::f32::consts::PI / 5.0);
                let s =
                    (sector - core::f32::consts::PI / 5.0).abs() / (core::f32::consts::PI / 5.0);
                // Boundary radius along a straight edge between (1, 0°) and (0.4, 36°): skip a
                // thin band around it instead of computing it exactly.
                let tip = v(1.0, 0.0);
                let notch = v(
                    0.4 * libm::cosf(core::f32::consts::PI / 5.0),
                    0.4 * libm::sinf(core::f32::consts::PI / 5.0),
                );
                let phi = (1.0 - s) * core::f32::consts::PI / 5.0;
                let dir = v(libm::cosf(phi), libm::sinf(phi));
                // Intersect the ray from 0 along dir with the segment tip–notch.
                let e = notch - tip;
                let den = dir.x * e.y - dir.y * e.x;
                let rb = (tip.x * e.y - tip.y * e.x) / den;
                if (r - rb).abs() < STAR_BOUNDARY_BAND {
                    continue;
                }
                checked += 1;
                assert_eq!(star.contains_projected(p), r < rb, "{p:?}");
            }
        }
        assert!(checked > 1500);
    }

    #[test]
    fn vertex_on_the_test_ray_counts_once() {
        // P2. Diamond with vertices exactly on y = 0.5 to the right of P.
        let diamond = P::new(&[v(1.0, 0.0), v(2.0, 0.5), v(1.0, 1.0), v(0.0, 0.5)]).unwrap();
        assert!(diamond.contains_projected(v(1.0, 0.5)));
        assert!(diamond.contains_projected(v(0.5, 0.5)));
        assert!(!diamond.contains_projected(v(-0.5, 0.5)));
        assert!(!diamond.contains_projected(v(2.5, 0.5)));
        // Pass-through vertex at (3, 1) on the test ray y = 1 from P = (1, 1): counted once.
        let pass = P::new(&[
            v(0.0, 0.0),
            v(4.0, 0.0),
            v(3.0, 1.0),
            v(4.0, 2.0),
            v(0.0, 2.0),
        ])
        .unwrap();
        assert!(pass.contains_projected(v(1.0, 1.0)));
        assert!(!pass.contains_projected(v(3.5, 1.0)));
        // Touching vertices (local extremes) on the test ray: counted 0 or 2 times.
        let zig = P::new(&[
            v(0.0, 0.0),
            v(2.0, 1.0), // local max touching y = 1 from below
            v(3.0, 0.0),
            v(5.0, 0.0),
            v(5.0, 3.0),
            v(4.0, 1.0), // local min touching y = 1 from above
            v(3.0, 3.0),
            v(0.0, 3.0),
        ])
        .unwrap();
        assert!(zig.contains_projected(v(0.5, 1.0)));
        assert!(zig.contains_projected(v(4.8, 1.0)));
        assert!(!zig.contains_projected(v(6.0, 1.0)));
        assert!(zig.contains_projected(v(2.5, 2.0)));
    }

    #[test]
    fn horizontal_edges_are_never_counted() {
        // P3. A staircase whose horizontal edges lie on the test ray y = 1.
        let stairs = P::new(&[
            v(0.0, 0.0),
            v(4.0, 0.0),
            v(4.0, 1.0),
            v(3.0, 1.0),
            v(3.0, 2.0),
            v(2.0, 2.0),
            v(2.0, 1.0),
            v(1.0, 1.0),
            v(1.0, 3.0),
            v(0.0, 3.0),
        ])
        .unwrap();
        // P = (0.5, 1): the test ray runs along the edges (2,1)–(1,1) and (4,1)–(3,1).
        assert!(stairs.contains_projected(v(0.5, 1.0)));
        // P on a bottom-facing horizontal edge (interior above): inside.
        assert!(stairs.contains_projected(v(2.5, 1.0)));
        // P on a top-facing horizontal edge (interior below): outside.
        assert!(!stairs.contains_projected(v(1.5, 1.0)));
        assert!(!stairs.contains_projected(v(3.5, 1.0)));
        assert!(stairs.contains_projected(v(3.5, 0.5)));
        assert!(!stairs.contains_projected(v(1.5, 1.5)));
    }

    #[test]
    fn on_edge_policy_is_half_open() {
        let sq = P::new(&[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]).unwrap();
        // Left and bottom edges (and their shared corner) inside; right and top outside.
        assert!(sq.contains_projected(v(0.0, 0.5)));
        assert!(sq.contains_projected(v(0.5, 0.0)));
        assert!(sq.contains_projected(v(0.0, 0.0)));
        assert!(!sq.contains_projected(v(1.0, 0.5)));
        assert!(!sq.contains_projected(v(0.5, 1.0)));
        assert!(!sq.contains_projected(v(1.0, 1.0)));
        // Two coplanar squares sharing the edge x = 1: each point of it is claimed exactly once.
        let right = P::new(&[v(1.0, 0.0), v(2.0, 0.0), v(2.0, 1.0), v(1.0, 1.0)]).unwrap();
        for i in 0..=16 {
            let p = v(1.0, i as f32 / 16.0);
            let n = [&sq, &right]
                .iter()
                .filter(|q| q.contains_projected(p))
                .count();
            assert_eq!(n, usize::from(i < 16), "y = {}", p.y);
        }
        assert!(!sq.contains_projected(Vec3::new(f32::NAN, 0.5, 0.0)));
    }

    #[test]
    fn dominant_axis_tie_is_deterministic() {
        // P6: plane x + y = 1 (|n_x| = |n_y|): the lowest index (x) is dropped.
        let quad = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
        ];
        let p = P::new(&quad).unwrap();
        assert_eq!(p.dominant_axis(), 0);
        let mut rev = quad;
        rev.reverse();
        assert_eq!(P::new(&rev).unwrap().dominant_axis(), 0);
        // A three-way tie (normal exactly ∝ (1, 1, 1): exact centroid 0) also drops x.
        let tri = P::new(&[
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ])
        .unwrap();
        assert_eq!(tri.dominant_axis(), 0);
        // Hits work through the tie.
        let target = Vec3::new(0.5, 0.5, 0.5);
        let o = target + Vec3::new(2.0, 2.0, 0.3);
        assert!(p.intersect(&Ray::new(o, target - o)).is_some());
        let off = Vec3::new(0.5, 0.5, 1.5);
        assert!(p.intersect(&Ray::new(o, off - o)).is_none());
        // |n_y| = |n_z| tie (plane y = z): y is dropped.
        let yz = P::new(&[
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ])
        .unwrap();
        assert_eq!(yz.dominant_axis(), 1);
    }

    #[test]
    fn square_agrees_with_its_two_watertight_triangles() {
        // A tilted square in 3-D, and the two triangles of its diagonal split; oblique rays on
        // a grid that includes the diagonal and avoids the outer boundary by half a step.
        let (c, e1, e2) = (
            Vec3::new(10.0, -3.0, 2.0),
            Vec3::new(2.0, 1.0, 0.5),
            Vec3::new(-0.8, 1.6, 0.0),
        );
        let e2 = e2 - e1 * (e1.dot(e2) / e1.dot(e1));
        let q = [c, c + e1, c + e1 + e2, c + e2];
        let poly = P::new(&q).unwrap();
        let t1 = [q[0], q[1], q[2]];
        let t2 = [q[0], q[2], q[3]];
        let n = poly.normal();
        let steps = 40;
        let mut inside = 0;
        for i in 0..steps {
            for j in 0..steps {
                let s = (i as f32 + 0.5) / steps as f32 * 1.5 - 0.25;
                let t = (j as f32 + 0.5) / steps as f32 * 1.5 - 0.25;
                for target in [c + e1 * s + e2 * t, c + (e1 + e2) * s] {
                    let o = target + n * 5.0 + e1 * 0.7 - e2 * 0.4;
                    let ray = Ray::new(o, target - o);
                    let tri = Watertight.intersect(&ray, &t1).is_some()
                        || Watertight.intersect(&ray, &t2).is_some();
                    let pol = poly.intersect(&ray);
                    assert_eq!(pol.is_some(), tri, "s = {s}, t = {t}");
                    if let Some(h) = pol {
                        inside += 1;
                        let wt = Watertight
                            .intersect(&ray, &t1)
                            .or_else(|| Watertight.intersect(&ray, &t2))
                            .unwrap();
                        assert!((h.t - wt.t).abs() <= 1e-5 * wt.t);
                        assert_eq!(h.front_face, wt.front_face);
                    }
                }
            }
        }
        assert!(inside > 1000, "{inside}");
    }

    /// Relative error allowed in `t` for the scaled squares' hits (unit: relative to `t`).
    /// The plane's point (the centroid) and unit normal are each rounded once to `f32`, and
    /// `t = ((p₀ − o)·N)/(d·N)` rounds about eight more times, every rounding relative to
    /// magnitudes of at most `1.5·t` here; `γ₁₆` covers them with room and is still far below
    /// anything a wrong plane (off by the square's size) would give.
    const SCALED_HIT_T_REL: f32 = crate::float::gamma(16);

    /// A unit square scaled by `s` from `10⁻³⁰` to `10³⁷`, in the plane `z = 0` and tilted
    /// into `z = y`, is accepted (the audit: `Err(NonFinite)` from `10²⁰` on, its Newell
    /// normal `s²` overflowing `f32`; `Err(Degenerate)` from `10⁻²³` down, underflowing), its
    /// normal is the unit normal worked by hand, and a ray straight down through its centre
    /// hits at `t` = the origin's height above the plane there, computed in `f64` from the
    /// `f32` inputs.
    #[test]
    fn scaled_squares_are_accepted_and_hit_where_expected() {
        let tilted = Vec3::new(0.0, -1.0, 1.0) / 2.0f32.sqrt();
        for s in [1e-30f32, 1e-25, 1e-23, 1e-20, 1.0, 1e20, 1e30, 1e37] {
            let h = s / 2.0;
            for (quad, normal) in [
                (
                    [
                        Vec3::ZERO,
                        Vec3::new(s, 0.0, 0.0),
                        Vec3::new(s, s, 0.0),
                        Vec3::new(0.0, s, 0.0),
                    ],
                    Vec3::Z,
                ),
                (
                    [
                        Vec3::ZERO,
                        Vec3::new(s, 0.0, 0.0),
                        Vec3::new(s, s, s),
                        Vec3::new(0.0, s, s),
                    ],
                    tilted,
                ),
            ] {
                let poly = Polygon::<4>::new(&quad).unwrap_or_else(|e| panic!("{s:e}: {e:?}"));
                let n = poly.normal();
                assert!(
                    (n - normal).abs().max_element() <= SCALED_HIT_T_REL,
                    "{s:e}: {n:?}"
                );
                // The plane's height at (h, h): 0 flat, h tilted (z = y).
                let below = if normal == Vec3::Z { 0.0 } else { h };
                let ray = Ray::new(Vec3::new(h, h, below + s), -Vec3::Z);
                let want = f64::from(ray.origin.z) - f64::from(below);
                let hit = poly
                    .intersect(&ray)
                    .unwrap_or_else(|| panic!("{s:e}: {ray:?}"));
                let err = (f64::from(hit.t) - want).abs();
                assert!(
                    err <= f64::from(SCALED_HIT_T_REL) * want,
                    "{s:e}: t {} vs {want}",
                    hit.t
                );
            }
        }
    }

    #[test]
    fn invalid_rays_never_hit() {
        let sq = P::new(&[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]).unwrap();
        for b in [f32::NAN, f32::INFINITY] {
            let mut r = down(0.5, 0.5);
            r.origin.x = b;
            assert!(sq.intersect(&r).is_none());
            let mut r = down(0.5, 0.5);
            r.direction.x = b;
            assert!(sq.intersect(&r).is_none());
        }
        // In-plane ray: no hit (P1).
        assert!(sq.intersect(&Ray::new(v(-1.0, 0.5), Vec3::X)).is_none());
    }
}
