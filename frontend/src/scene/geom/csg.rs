//! CSG on intervals: every crossing of a node's boundary along the whole line, and the
//! combination of two operands' crossings by a boolean operation.

use super::mesh::*;
use super::*;
use glam::Vec3;
use halfray_core::{Hit, Ray};

impl Node {
    /// Every boundary crossing along the ray's line (the ray's interval is ignored: the whole
    /// line is used), sorted by `t`, in the parent's space, and whether the line starts inside.
    pub fn events(&self, ray: &Ray, ctx: &mut QueryCtx, out: &mut Vec<Event>) -> bool {
        match &self.transform {
            Some(t) => {
                let local = t.ray_to_object(ray);
                let start = out.len();
                let inside = self.events_local(&local, ctx, out);
                for e in &mut out[start..] {
                    e.hit = to_world(t, e.hit);
                }
                inside
            }
            None => self.events_local(ray, ctx, out),
        }
    }

    fn event(&self, hit: Hit, bary: Option<Vec3>) -> Event {
        Event {
            t: hit.t,
            enter: hit.front_face,
            hit: self.surf(hit, bary),
        }
    }

    pub(super) fn events_local(&self, ray: &Ray, ctx: &mut QueryCtx, out: &mut Vec<Event>) -> bool {
        let line = Ray::with_interval(ray.origin, ray.direction, f32::NEG_INFINITY, f32::INFINITY);
        if let Some(s) = self.shape.primitive() {
            out.extend(
                s.line_crossings(&line)
                    .into_iter()
                    .flatten()
                    .map(|h| self.event(h, self.shape.barycentrics(&h))),
            );
            return s.line_starts_inside(&line);
        }
        match &self.shape {
            Geometry::Mesh(m) => {
                let mut hits = Vec::new();
                m.all_hits(&line, &mut ctx.stats, &mut hits);
                out.extend(mesh_events(hits, |h, b, prim, enter| {
                    let mut e = Event {
                        enter,
                        ..self.event(h, Some(b))
                    };
                    e.hit.shading = m.shading_normal(prim as usize, b, h.normal);
                    e
                }));
                false
            }
            Geometry::Csg(op, a, b) => {
                let mut ea = Vec::new();
                let mut eb = Vec::new();
                let ia = a.events(&line, ctx, &mut ea);
                let ib = b.events(&line, ctx, &mut eb);
                combine(*op, &ea, ia, &eb, ib, out)
            }
            _ => false,
        }
    }
}

/// Combines two sorted crossing lists with a boolean operation; appends the result's
/// crossings to `out` and returns whether the result starts inside.
pub fn combine(
    op: CsgOp,
    a: &[Event],
    a_inside: bool,
    b: &[Event],
    b_inside: bool,
    out: &mut Vec<Event>,
) -> bool {
    let mut ca = i32::from(a_inside);
    let mut cb = i32::from(b_inside);
    let start = op.apply(a_inside, b_inside);
    let mut state = start;
    let (mut i, mut j) = (0usize, 0usize);
    while i < a.len() || j < b.len() {
        let take_a = j >= b.len() || (i < a.len() && a[i].t <= b[j].t);
        let (e, from_b) = if take_a {
            i += 1;
            (a[i - 1], false)
        } else {
            j += 1;
            (b[j - 1], true)
        };
        let c = if from_b { &mut cb } else { &mut ca };
        *c += if e.enter { 1 } else { -1 };
        let now = op.apply(ca > 0, cb > 0);
        if now != state {
            state = now;
            let mut hit = e.hit;
            if from_b && op == CsgOp::Difference {
                hit.hit.normal = -hit.hit.normal;
                hit.hit.front_face = !hit.hit.front_face;
            }
            out.push(Event {
                t: e.t,
                enter: now,
                hit,
            });
        }
    }
    start
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(shape: Geometry) -> Node {
        Node::new(shape, 0, None)
    }

    #[test]
    fn sphere_difference_carves_a_hole() {
        let a = node(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap()));
        let b = node(Geometry::Sphere(Sphere::new(Vec3::Z, 0.5).unwrap()));
        let csg = node(Geometry::Csg(CsgOp::Difference, Box::new(a), Box::new(b)));
        let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let h = csg.closest(&ray, &mut QueryCtx::default()).unwrap();
        // Hits the inside of the small sphere at z = 0.5, normal pointing out of the result (+z).
        assert!((h.hit.t - 4.5).abs() < 1e-5, "{h:?}");
        assert!((h.hit.normal - Vec3::Z).length() < 1e-5);
        assert!(h.hit.front_face);
    }

    #[test]
    fn forced_intervals_give_identical_hits() {
        for shape in [
            Geometry::Sphere(Sphere::new(Vec3::new(0.1, 0.2, 0.0), 1.0).unwrap()),
            Geometry::Box(Aabb::new(Vec3::splat(-1.0), Vec3::ONE)),
            Geometry::Ellipsoid(Ellipsoid::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.5)).unwrap()),
        ] {
            let n = node(shape);
            for o in [Vec3::new(0.3, 0.1, 5.0), Vec3::new(0.0, 0.0, 0.0)] {
                let ray = Ray::new(o, Vec3::new(0.01, -0.02, -1.0));
                let a = n.closest(&ray, &mut QueryCtx::default());
                let mut ctx = QueryCtx {
                    force_intervals: true,
                    ..QueryCtx::default()
                };
                let b = n.closest(&ray, &mut ctx);
                assert_eq!(a, b);
            }
        }
    }
}
