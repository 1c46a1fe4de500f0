//! One interface for every surface a ray can hit (bounds, closest hit, the crossings of a
//! line and where it starts, for CSG): [`Sphere`], [`Ellipsoid`], [`Polygon`], the triangle
//! `[Vec3; 3]` (with [`Watertight`]), the box [`Aabb`] ([`box_crossings`]), the [`Plane`],
//! the general [`Quadric`] and the [`ClippedQuadric`]. Every one answers with the one hit
//! type, [`Hit`]. The bounded ones are also [`crate::mesh::Primitive`]s, so a BVH can be built
//! over a slice of them and queried with [`Shape::closest_hit`] as its intersector.

use crate::aabb::Aabb;
use crate::float::gamma;
use crate::hit::Hit;
use crate::plane::Plane;
use crate::polygon::Polygon;
use crate::quadric::{ClippedQuadric, Ellipsoid, Quadric};
use crate::ray::Ray;
use crate::sphere::Sphere;
use crate::triangle::{TriangleIntersector, Watertight};
use glam::Vec3;

mod cuboid;

pub use cuboid::box_crossings;

/// A surface a ray can hit.
pub trait Shape {
    /// A box containing the exact surface. The corners of a curved shape's box come from
    /// rounded `f32` arithmetic, so they are padded outward by [`CURVED_BOUNDS_PAD`]; flat
    /// shapes' boxes are their vertices' exact range. Infinite for an unbounded surface (a
    /// plane, a quadric without a clip box); non-finite for an unusable shape.
    fn bounds(&self) -> Aabb;

    /// The closest hit of `ray` in its interval `(t_min, t_max]`; `None` for a miss or an
    /// invalid ray.
    fn closest_hit(&self, ray: &Ray) -> Option<Hit>;

    /// Where the ray's whole line (`t` over all reals, the interval ignored) crosses the
    /// surface, nearest first: a closed shape's entry and exit (neither for a tangent line,
    /// whose double root enters and leaves at once), a flat shape's one crossing. What CSG
    /// combines. Each hit is the one [`Shape::closest_hit`] computes at that `t`.
    fn line_crossings(&self, ray: &Ray) -> [Option<Hit>; 2] {
        [self.closest_hit(&whole_line(ray)), None]
    }

    /// Whether the ray's line is inside the solid the surface bounds as `t → −∞` (the state
    /// before its first [`Shape::line_crossings`]). `false` for a bounded shape; an unbounded
    /// solid (the half-space behind a plane, a quadric's `f < 0` side) may start inside.
    fn line_starts_inside(&self, _ray: &Ray) -> bool {
        false
    }
}

/// The box of everything: the bounds of an unbounded surface.
const EVERYWHERE: Aabb = Aabb {
    min: Vec3::NEG_INFINITY,
    max: Vec3::INFINITY,
};

/// `ray` with the interval of its whole line.
fn whole_line(ray: &Ray) -> Ray {
    Ray::with_interval(ray.origin, ray.direction, f32::NEG_INFINITY, f32::INFINITY)
}

/// The hit `intersect` (a nearest-root intersector) gives at the root `t` of `ray`'s line: the
/// interval narrowed to `(t⁻, t]` (one ulp below `t`), so exactly that root, computed as in a
/// plain query.
pub fn hit_at_root(ray: &Ray, t: f32, intersect: impl Fn(&Ray) -> Option<Hit>) -> Option<Hit> {
    intersect(&Ray::with_interval(
        ray.origin,
        ray.direction,
        t.next_down(),
        t,
    ))
}

/// The crossings of a closed quadric surface at the roots `t0 ≤ t1` of `ray`'s line
/// ([`hit_at_root`] of each); none for a double root (a tangent line) or no roots.
pub fn crossings_at_roots(
    ray: &Ray,
    roots: Option<(f32, f32)>,
    intersect: impl Fn(&Ray) -> Option<Hit>,
) -> [Option<Hit>; 2] {
    match roots {
        Some((t0, t1)) if t0 != t1 => [t0, t1].map(|t| hit_at_root(ray, t, &intersect)),
        _ => [None, None],
    }
}

/// The crossings of a quadric surface: [`crossings_at_roots`] of its `f64` roots along the
/// whole line (`roots`), rounded to `f32`.
fn quadric_crossings(
    ray: &Ray,
    roots: impl Fn(&Ray) -> Option<(f64, f64)>,
    intersect: impl Fn(&Ray) -> Option<Hit>,
) -> [Option<Hit>; 2] {
    let roots = roots(&whole_line(ray)).map(|(t0, t1)| (t0 as f32, t1 as f32));
    crossings_at_roots(ray, roots, intersect)
}

/// Outward padding of a curved shape's box, relative to the largest magnitude among its
/// centre and extent: `centre ± half-extent` rounds twice in `f32` (`≤ gamma(2)` relative);
/// `gamma(4)` covers it with margin. Unitless.
pub const CURVED_BOUNDS_PAD: f32 = gamma(4);

/// The box `center ± half`, padded by [`CURVED_BOUNDS_PAD`].
fn padded_box(center: Vec3, half: Vec3) -> Aabb {
    let pad = (center.abs() + half.abs()).max_element() * CURVED_BOUNDS_PAD;
    Aabb::new(
        center - half - Vec3::splat(pad),
        center + half + Vec3::splat(pad),
    )
}

impl Shape for Sphere {
    fn bounds(&self) -> Aabb {
        padded_box(self.center(), Vec3::splat(self.radius()))
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.intersect(ray)
    }

    fn line_crossings(&self, ray: &Ray) -> [Option<Hit>; 2] {
        crossings_at_roots(ray, self.roots(&whole_line(ray)), |r| self.intersect(r))
    }
}

impl Shape for Ellipsoid {
    fn bounds(&self) -> Aabb {
        padded_box(self.center(), self.radii())
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.intersect(ray)
    }

    fn line_crossings(&self, ray: &Ray) -> [Option<Hit>; 2] {
        quadric_crossings(ray, |l| self.roots(l), |r| self.intersect(r))
    }
}

impl<const N: usize> Shape for Polygon<N> {
    fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices())
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.intersect(ray)
    }
}

impl Shape for [Vec3; 3] {
    fn bounds(&self) -> Aabb {
        Aabb::from_points(self)
    }

    /// [`Watertight`]'s hit ([`crate::triangle::TriangleHit::to_hit`]).
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        Some(Watertight.intersect(ray, self)?.to_hit(self))
    }
}

impl Shape for Plane {
    /// Infinite.
    fn bounds(&self) -> Aabb {
        EVERYWHERE
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.intersect(ray)
    }

    /// The half-space behind the normal is the solid: a line crossing the plane starts inside
    /// when it leaves through the plane (its hit is a back face); a parallel line (no
    /// crossing) when its origin is strictly behind.
    fn line_starts_inside(&self, ray: &Ray) -> bool {
        match self.intersect(&whole_line(ray)) {
            Some(h) => !h.front_face,
            None => (ray.origin - self.point()).dot(self.normal()) < 0.0,
        }
    }
}

impl Shape for Quadric {
    /// Infinite (a general quadric need not be bounded).
    fn bounds(&self) -> Aabb {
        EVERYWHERE
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.intersect(ray)
    }

    fn line_crossings(&self, ray: &Ray) -> [Option<Hit>; 2] {
        quadric_crossings(ray, |l| self.roots(l), |r| self.intersect(r))
    }

    /// The solid is `f < 0`: the sign of the leading coefficient of `f(o + t·d)` (in `f64`,
    /// the polynomial [`Quadric::roots`] solves), `d·A·d`, then of the linear one `d·∇f(o)/2`
    /// (inside when it is positive: `f` falls as `t → −∞`), then of `f(o)` for a line along
    /// which `f` is constant (a cylinder's axis).
    fn line_starts_inside(&self, ray: &Ray) -> bool {
        let [qa, qb, qc] = self.ray_polynomial(ray);
        if qa != 0.0 {
            qa < 0.0
        } else if qb != 0.0 {
            qb > 0.0
        } else {
            qc < 0.0
        }
    }
}

impl Shape for ClippedQuadric {
    /// The clip box; infinite without one.
    fn bounds(&self) -> Aabb {
        self.clip.unwrap_or(EVERYWHERE)
    }

    /// The nearest root in the ray's interval whose hit lies in the clip box (each root's hit
    /// by [`hit_at_root`], so exactly as a plain query computes it); the quadric's own hit
    /// without a clip box.
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        if self.clip.is_none() {
            return self.quadric.intersect(ray);
        }
        let (t0, t1) = self.quadric.roots(ray)?;
        [t0 as f32, t1 as f32]
            .into_iter()
            .filter(|&t| ray.contains(t))
            .filter_map(|t| hit_at_root(ray, t, |r| self.quadric.intersect(r)))
            .find(|h| self.in_clip(h))
    }

    /// The quadric's crossings whose hits lie in the clip box (a clipped quadric is open: its
    /// crossings do not alternate between inside and outside).
    fn line_crossings(&self, ray: &Ray) -> [Option<Hit>; 2] {
        self.quadric
            .line_crossings(ray)
            .map(|h| h.filter(|h| self.in_clip(h)))
    }

    /// The quadric's, without a clip box; `false` with one (no solid).
    fn line_starts_inside(&self, ray: &Ray) -> bool {
        self.clip.is_none() && self.quadric.line_starts_inside(ray)
    }
}

/// The [`crate::mesh::Primitive`] of each shape: its [`Shape::bounds`].
macro_rules! primitive_from_shape {
    ($([$($g:tt)*] $ty:ty),+) => {
        $(impl<$($g)*> crate::mesh::Primitive for $ty {
            #[inline]
            fn bounds(&self) -> Aabb {
                Shape::bounds(self)
            }
        })+
    };
}

primitive_from_shape!([] Sphere, [] Ellipsoid, [const N: usize] Polygon<N>);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BuildOptions;
    use crate::prelude::*;
    use crate::query::Query;
    use crate::test_util::{Lcg, vec_bvh};
    use std::vec::Vec;

    /// The exact extreme points `centre ± half` (in `f64`) lie in the `f32` box, at every
    /// scale from 1e-3 to 1e7 and for centres far from the origin.
    #[test]
    fn curved_bounds_contain_the_exact_extremes() {
        let mut r = Lcg(5);
        for k in 0..2000 {
            let scale = 10f32.powi(k % 11 - 3);
            let c = r.v(2.0) * scale * 10.0;
            let radii = (r.v(1.0).abs() + Vec3::splat(0.01)) * scale;
            let sphere = Sphere::new(c, radii.x).unwrap();
            let ell = Ellipsoid::new(c, radii).unwrap();
            for (b, half) in [
                (Shape::bounds(&sphere), Vec3::splat(radii.x)),
                (Shape::bounds(&ell), radii),
            ] {
                let (cd, hd) = (c.as_dvec3(), half.as_dvec3());
                for corner in [cd - hd, cd + hd] {
                    let inside = corner.cmpge(b.min.as_dvec3()).all()
                        && corner.cmple(b.max.as_dvec3()).all();
                    assert!(inside, "{corner} outside {b:?}");
                }
                // Padded by little: within 1e-5 of the extent.
                let slack = (b.max.as_dvec3() - (cd + hd)).max_element();
                assert!(slack <= 1e-5 * (cd.abs() + hd).max_element(), "{slack}");
            }
        }
    }

    /// The unit sphere crossed by the line `y = 0.5`, `z = 0` along `+x` from `x = −5`: by hand
    /// at `x = ∓√0.75`, entering (outward normal against the ray) then leaving; the same
    /// through the ellipsoid of radii 1; a tangent line crosses nothing; a triangle once,
    /// whatever the ray's interval.
    #[test]
    fn line_crossings_worked_example() {
        let ray = Ray::with_interval(Vec3::new(-5.0, 0.5, 0.0), Vec3::X, 0.0, 1.0);
        let sphere = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let ell = Ellipsoid::new(Vec3::ZERO, Vec3::ONE).unwrap();
        let x = 0.75f32.sqrt();
        for crossings in [sphere.line_crossings(&ray), ell.line_crossings(&ray)] {
            let [Some(a), Some(b)] = crossings else {
                panic!("{crossings:?}");
            };
            assert!((a.t - (5.0 - x)).abs() <= 1e-6 && (b.t - (5.0 + x)).abs() <= 1e-6);
            assert!(a.front_face && !b.front_face);
            assert!(
                (a.normal - Vec3::new(-x, 0.5, 0.0)).length() <= 1e-5,
                "{}",
                a.normal
            );
        }
        let tangent = Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X);
        assert_eq!(sphere.line_crossings(&tangent), [None, None]);
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let up = Ray::with_interval(Vec3::new(0.25, 0.25, 1.0), Vec3::Z, 0.0, 1.0);
        let [Some(h), None] = tri.line_crossings(&up) else {
            panic!("one crossing behind the origin");
        };
        assert_eq!(h.t, -1.0);
    }

    /// The plane `z = 0` (normal `+z`, the solid `z < 0`): a line going down enters it at
    /// the plane and starts outside, one going up leaves it and starts inside, a parallel line
    /// below it is inside throughout and crosses nothing.
    #[test]
    fn plane_worked_example() {
        let p = Plane::new(Vec3::ZERO, Vec3::Z).unwrap();
        let down = Ray::new(Vec3::new(0.5, 0.0, 5.0), -Vec3::Z);
        let [Some(h), None] = p.line_crossings(&down) else {
            panic!("one crossing");
        };
        assert_eq!(
            (h.t, h.point, h.front_face),
            (5.0, Vec3::new(0.5, 0.0, 0.0), true)
        );
        assert!(!p.line_starts_inside(&down));
        let up = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert!(p.line_starts_inside(&up));
        let below = Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::X);
        assert_eq!(p.line_crossings(&below), [None, None]);
        assert!(p.line_starts_inside(&below));
        assert!(!p.line_starts_inside(&Ray::new(Vec3::Z, Vec3::X)));
        assert!(!Shape::bounds(&p).is_finite());
    }

    /// The unit sphere as a general quadric `x² + y² + z² − 1` crossed by the line `y = 0.5`,
    /// `z = 0` along `+x`: at `t = 5 ∓ √0.75`, as the [`Sphere`]'s, starting outside; the
    /// half-space `z < 0` as the quadric `f = z` starts inside a line going up. Clipped to
    /// `x ≥ 0`, the sphere keeps only the exit, which is then also the closest hit.
    #[test]
    fn quadric_worked_example() {
        use glam::{DMat3, DVec3};
        let q = Quadric::new(DMat3::IDENTITY, DVec3::ZERO, -1.0).unwrap();
        let ray = Ray::new(Vec3::new(-5.0, 0.5, 0.0), Vec3::X);
        let x = 0.75f32.sqrt();
        let [Some(a), Some(b)] = q.line_crossings(&ray) else {
            panic!("two crossings");
        };
        assert!((a.t - (5.0 - x)).abs() <= 1e-6 && (b.t - (5.0 + x)).abs() <= 1e-6);
        assert!(a.front_face && !b.front_face);
        assert!(!q.line_starts_inside(&ray));
        let half = Quadric::new(DMat3::ZERO, DVec3::new(0.0, 0.0, 0.5), 0.0).unwrap();
        assert!(half.line_starts_inside(&Ray::new(Vec3::ZERO, Vec3::Z)));
        assert!(!half.line_starts_inside(&Ray::new(Vec3::ZERO, -Vec3::Z)));

        let clip = Aabb::new(Vec3::new(0.0, -2.0, -2.0), Vec3::splat(2.0));
        let clipped = ClippedQuadric {
            quadric: q,
            clip: Some(clip),
        };
        assert_eq!(clipped.line_crossings(&ray), [None, Some(b)]);
        assert_eq!(clipped.closest_hit(&ray), Some(b));
        assert!(!clipped.line_starts_inside(&ray));
        assert_eq!(Shape::bounds(&clipped), clip);
        let whole = ClippedQuadric {
            quadric: q,
            clip: None,
        };
        assert_eq!(whole.closest_hit(&ray), Some(a));
    }

    /// A BVH over a slice of spheres, queried with [`Shape::closest_hit`], answers like a loop
    /// over the spheres; the triangle's hit is [`Watertight`]'s.
    #[test]
    fn a_bvh_of_shapes_equals_the_loop_over_them() {
        let mut r = Lcg(9);
        let spheres: Vec<Sphere> = (0..200)
            .map(|_| Sphere::new(r.v(20.0), 0.2 + r.v(0.5).abs().x).unwrap())
            .collect();
        let bvh = vec_bvh(&spheres[..], &BuildOptions::default()).unwrap();
        let mut hits = 0;
        for k in 0..500 {
            // Aimed at a sphere's centre: most rays hit something, many several spheres.
            let o = r.v(40.0);
            let ray = Ray::new(o, spheres[k % spheres.len()].center() - o);
            let mut shape =
                |i: u32, ray: &Ray| spheres[i as usize].closest_hit(ray).map(|h| (h.t, h.t));
            let got = bvh.closest_hit(&ray, &mut shape, &mut Query::new());
            let want = spheres
                .iter()
                .enumerate()
                .filter_map(|(i, s)| Some((i as u32, s.closest_hit(&ray)?.t)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            assert_eq!(got, want, "{ray:?}");
            hits += usize::from(want.is_some());
        }
        assert!(hits == 500, "only {hits} rays hit");

        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        let h = tri.closest_hit(&ray).unwrap();
        assert_eq!((h.t, h.normal), (1.0, Vec3::Z));
    }
}
