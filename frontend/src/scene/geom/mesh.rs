//! A mesh instance's queries: the closest hit with its shading normal, and every counted
//! crossing of a line (the other primitives are the core's [`halfray_core::shape::Shape`]s).

use super::*;
use glam::Vec3;
use halfray_core::prelude::*;
use halfray_core::query::{Query, TraversalStats};
use halfray_core::triangle::{TriangleHit, TriangleIntersector, Watertight};
use halfray_core::{Hit, Ray};

impl MeshShape {
    pub(super) fn closest(
        &self,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<(Hit, Vec3, Option<Vec3>)> {
        let (i, th) = self.accel.closest(&Watertight, ray, stats)?;
        Some(self.surface(i, &th))
    }

    /// [`MeshShape::closest`] of each of `rays` (the same answers), traced as one batch
    /// ([`crate::accel::MeshAccel::closest_batch`]).
    pub(super) fn closest_batch(
        &self,
        rays: &[Ray],
        stats: &mut TraversalStats,
    ) -> Vec<Option<(Hit, Vec3, Option<Vec3>)>> {
        let answers = self.accel.closest_batch(&Watertight, rays, Some(stats));
        answers
            .into_iter()
            .map(|a| a.map(|(i, th)| self.surface(i, &th)))
            .collect()
    }

    /// The hit record, barycentrics and shading normal of triangle `i`'s hit `th`.
    fn surface(&self, i: u32, th: &TriangleHit) -> (Hit, Vec3, Option<Vec3>) {
        let v = self.accel.mesh.triangle(i as usize);
        let bary = Vec3::new(th.b0(), th.b1, th.b2);
        let hit = th.to_hit(&v);
        (hit, bary, self.shading_normal(i as usize, bary, hit.normal))
    }

    /// The interpolated vertex normal of triangle `tri` at barycentrics `bary`, turned to the
    /// side of the geometric normal `geometric`; `None` without vertex normals or where they
    /// cancel.
    pub fn shading_normal(&self, tri: usize, bary: Vec3, geometric: Vec3) -> Option<Vec3> {
        let normals = self.normals.as_ref()?;
        let t = self.accel.mesh.triangles.get(tri)?;
        let n = t
            .iter()
            .zip(bary.to_array())
            .map(|(&k, b)| normals.get(k as usize).copied().unwrap_or(Vec3::ZERO) * b)
            .sum::<Vec3>()
            .try_normalize()?;
        Some(if n.dot(geometric) < 0.0 { -n } else { n })
    }

    /// Every triangle the closed watertight test hits on the ray's interval, with its index
    /// and [`halfray_core::triangle::WatertightRay::crossing_sign`] (0 for a triangle that the
    /// rule does not count: the second triangle of an edge, the rest of a vertex's fan).
    pub(super) fn all_hits(&self, ray: &Ray, stats: &mut TraversalStats, out: &mut Vec<MeshHit>) {
        let Some(pre) = Watertight.prepare(ray) else {
            return;
        };
        let mesh = self.accel.triangles();
        let mut leaf = |prim: u32, r: &Ray| -> Option<(f32, ())> {
            // `r.t_max` never shrinks: we never report a hit, so every crossing is seen.
            let v = mesh.triangle(prim as usize)?;
            if let Some(th) = Watertight.intersect_prepared(&pre, r, &v) {
                out.push(MeshHit {
                    prim,
                    hit: th.to_hit(&v),
                    bary: Vec3::new(th.b0(), th.b1, th.b2),
                    sign: pre.crossing_sign(r.origin, &v),
                });
            }
            None
        };
        let _ = self
            .accel
            .bvh()
            .closest_hit(ray, &mut leaf, &mut Query::new().stats(stats));
    }
}

/// One triangle hit of [`MeshShape::all_hits`].
pub(super) struct MeshHit {
    prim: u32,
    hit: Hit,
    bary: Vec3,
    sign: i8,
}

/// The crossings of a closed mesh along a whole line, from its triangle hits: **one per
/// surface crossing**, whatever edge or vertex the line passes through. Hits at equal `t` form
/// one point of the line; there the crossings [`WatertightRay::crossing_sign`] counts (those
/// of the line moved infinitesimally off the edge) become events, alternating from the state
/// before the point, so the winding count changes by exactly their sum. A point where the
/// closed test hits but the rule counts nothing (the line grazes an edge or vertex) becomes an
/// empty interval, two events at the same `t`: the surface is still seen there, as a plain
/// closest hit sees it. Each point's first event carries the hit of its smallest triangle
/// index, the closest-hit rule, so a mesh traced through this path shows the same picture
/// (`--force-all-effects`).
///
/// [`WatertightRay::crossing_sign`]: halfray_core::triangle::WatertightRay::crossing_sign
pub(super) fn mesh_events(
    mut hits: Vec<MeshHit>,
    event: impl Fn(Hit, Vec3, u32, bool) -> Event,
) -> Vec<Event> {
    hits.sort_by(|a, b| a.hit.t.total_cmp(&b.hit.t).then(a.prim.cmp(&b.prim)));
    let mut out = Vec::with_capacity(hits.len());
    let mut inside = false;
    let mut i = 0;
    while i < hits.len() {
        let t = hits[i].hit.t;
        let group = hits[i..].iter().take_while(|h| h.hit.t == t).count();
        let point = &hits[i..i + group];
        let counted = point.iter().filter(|h| h.sign != 0).count();
        // An empty interval where nothing is counted; else one event per counted crossing.
        let n = if counted == 0 { 2 } else { counted };
        for k in 0..n {
            inside = !inside;
            // The first event: the closest-hit record; later ones: a counted triangle.
            let h = if k == 0 {
                &point[0]
            } else {
                point
                    .iter()
                    .filter(|h| h.sign != 0)
                    .nth(k)
                    .unwrap_or(&point[0])
            };
            out.push(event(h.hit, h.bary, h.prim, inside));
        }
        i += group;
    }
    out
}
