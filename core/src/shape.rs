//! One interface for the bounded surfaces a ray can hit: [`Sphere`], [`Ellipsoid`],
//! [`Polygon`] and the triangle `[Vec3; 3]` (with [`Watertight`]). Each is also a
//! [`crate::bvh::Primitive`], so a BVH can be built over a slice of them and queried with
//! [`Shape::closest_hit`] as its intersector.

use crate::aabb::Aabb;
use crate::float::gamma;
use crate::hit::Hit;
use crate::polygon::Polygon;
use crate::quadric::Ellipsoid;
use crate::ray::Ray;
use crate::sphere::Sphere;
use crate::triangle::{TriangleIntersector, Watertight};
use glam::Vec3;

/// A bounded surface.
pub trait Shape {
    /// A box containing the exact surface. The corners of a curved shape's box come from
    /// rounded `f32` arithmetic, so they are padded outward by [`CURVED_BOUNDS_PAD`]; flat
    /// shapes' boxes are their vertices' exact range. Non-finite for an unusable shape.
    fn bounds(&self) -> Aabb;

    /// The closest hit of `ray` in its interval `(t_min, t_max]`; `None` for a miss or an
    /// invalid ray.
    fn closest_hit(&self, ray: &Ray) -> Option<Hit>;
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
}

impl Shape for Ellipsoid {
    fn bounds(&self) -> Aabb {
        padded_box(self.center(), self.radii())
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.intersect(ray)
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

/// The [`crate::bvh::Primitive`] of each shape: its [`Shape::bounds`].
macro_rules! primitive_from_shape {
    ($([$($g:tt)*] $ty:ty),+) => {
        $(impl<$($g)*> crate::bvh::Primitive for $ty {
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
            let shape =
                |i: u32, ray: &Ray| spheres[i as usize].closest_hit(ray).map(|h| (h.t, h.t));
            let got = bvh.closest_hit(&ray, shape, None);
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
