//! Cost and accuracy of each ray–triangle variant, measured on the same rays in one run.

use crate::crosscheck::judge::{near_boundary, plane_crossing, ray_space_barycentrics};
use crate::crosscheck::sets::{self, Adjacency, Rng};
use crate::obj::ObjMesh;
use crate::raysets::named::no_hits;
use crate::timing::{median_of, per_million};
use glam::{DVec3, Vec3};
use halfray_core::Ray;
use halfray_core::triangle::{TriangleIntersector, TriangleVariant, VariantVisitor};
use std::hint::black_box;
use std::time::Instant;

/// How far outside a triangle the "just outside" rays aim, in ulps (`2⁻²³`) of the largest
/// vertex coordinate relative to the ray origin (the magnitude the `f32` tests round), measured
/// perpendicular to the edge in the triangle's plane and divided by `|cos θ|` (ray against
/// normal) so that the offset survives the projection along the ray. Rays are then kept only
/// if the ray-space test ([`crate::crosscheck::judge::ray_space_barycentrics`]) puts them
/// outside by more than its boundary margin (64 ulps): outside beyond every variant's rounding,
/// so a correct test never hits them, while tests with sloppy edges (epsilons, rounded sums
/// evaluated from a different base vertex) still can.
pub const OUTSIDE_OFFSET_ULPS: f64 = 96.0;

/// Accuracy figures of one variant.
#[derive(Clone, Debug, Default)]
pub struct Accuracy {
    /// Transversal edge and vertex rays tested.
    pub leak_rays: usize,
    /// Of those, rays that hit none of the incident triangles.
    pub leaks: usize,
    /// Rays aimed just outside a triangle (by [`OUTSIDE_OFFSET_ULPS`]).
    pub outside_rays: usize,
    /// Of those, rays the variant reports as hitting that triangle.
    pub false_hits: usize,
    /// Relative `t` error against the oracle ([`oracle_t`]) over hits both report: sorted
    /// samples.
    pub rel_t_errors: Vec<f64>,
    /// Rays where the variant and the oracle ([`oracle_t`]) disagree on hit/miss, counted over
    /// rays whose barycentrics are farther from every edge than
    /// [`crate::crosscheck::judge::ray_space_barycentrics`]' margin (closer than that, both
    /// answers are valid).
    pub hit_miss_disagreements: usize,
    /// Rays in the hit/miss comparison.
    pub hit_miss_rays: usize,
}

impl Accuracy {
    /// Leaks per million edge/vertex rays.
    pub fn leaks_per_million(&self) -> f64 {
        per_million(self.leaks, self.leak_rays)
    }
    /// False hits per million just-outside rays.
    pub fn false_hits_per_million(&self) -> f64 {
        per_million(self.false_hits, self.outside_rays)
    }
    /// Largest relative `t` error.
    pub fn max_rel_t_error(&self) -> f64 {
        self.rel_t_errors.last().copied().unwrap_or(0.0)
    }
    /// Median relative `t` error.
    pub fn median_rel_t_error(&self) -> f64 {
        self.rel_t_errors
            .get(self.rel_t_errors.len() / 2)
            .copied()
            .unwrap_or(0.0)
    }
    /// Hit/miss disagreements with the oracle ([`oracle_t`]) per million rays.
    pub fn disagreements_per_million(&self) -> f64 {
        per_million(self.hit_miss_disagreements, self.hit_miss_rays)
    }
}

/// The workloads shared by every variant (generated once, so every variant sees the same rays).
pub struct Workload {
    /// Edge/vertex rays with their incident triangles (transversal crossings only).
    pub leak_rays: Vec<(Ray, Vec<[Vec3; 3]>)>,
    /// Rays aimed just outside one triangle, with that triangle.
    pub outside_rays: Vec<(Ray, [Vec3; 3])>,
    /// Rays aimed at a random point of one triangle (interior or edge), with that triangle.
    pub pair_rays: Vec<(Ray, [Vec3; 3])>,
    /// Rays for the cost loop and the triangles they are all tested against.
    pub cost_rays: Vec<Ray>,
    /// Triangles of the cost loop.
    pub cost_tris: Vec<[Vec3; 3]>,
    /// For each leak ray, the index of its mesh in `leak_meshes`.
    pub leak_mesh: Vec<usize>,
    /// For each outside ray, its `(mesh index, triangle index)` in `meshes`.
    pub outside_ids: Vec<(usize, u32)>,
    /// For each pair ray, its `(mesh index, triangle index)` in `meshes`.
    pub pair_ids: Vec<(usize, u32)>,
}

impl Workload {
    /// Builds the workloads from `meshes` (`leak_meshes` are used for edge/vertex rays, normally
    /// the closed ones): `n` just-outside rays, `n` triangle-aimed rays, and `n` edge and vertex
    /// rays generated (split evenly over `leak_meshes` and the `edges` and `vertices` sets) of
    /// which only those with a target are kept (their line crosses their edge's or vertex's
    /// triangles transversally: fewer than `n`, about 60 % on the shared meshes). Fails when the meshes do not yield
    /// `n` usable "just outside" rays within [`MAX_CANDIDATES_PER_RAY`] candidates per ray
    /// (coordinates near the `f32` range limit, where no offset ray survives rounding).
    pub fn new(
        meshes: &[ObjMesh],
        leak_meshes: &[ObjMesh],
        n: usize,
        seed: u64,
    ) -> Result<Self, String> {
        let mut leak_rays = Vec::new();
        let mut leak_mesh = Vec::new();
        let per = n / (2 * leak_meshes.len().max(1));
        for (i, m) in leak_meshes.iter().enumerate() {
            let adj = Adjacency::new(m);
            for set in ["edges", "vertices"] {
                for r in
                    sets::generate(set, m, &adj, per, seed + i as u64, &no_hits).unwrap_or_default()
                {
                    if let Some(t) = r.target {
                        let tris = t.incident.iter().map(|&f| m.triangle(f as usize)).collect();
                        leak_rays.push((r.ray, tris));
                        leak_mesh.push(i);
                    }
                }
            }
        }
        let mut rng = Rng::new(seed ^ 0xACC);
        let all: Vec<(usize, u32, [Vec3; 3])> = meshes
            .iter()
            .enumerate()
            .flat_map(|(mi, m)| (0..m.triangles.len()).map(move |f| (mi, f as u32, m.triangle(f))))
            .filter(|(_, _, t)| (t[1] - t[0]).cross(t[2] - t[0]) != Vec3::ZERO)
            .collect();
        let mut outside_rays = Vec::with_capacity(n);
        let mut pair_rays = Vec::with_capacity(n);
        let mut outside_ids = Vec::with_capacity(n);
        let mut pair_ids = Vec::with_capacity(n);
        let budget = n.saturating_mul(MAX_CANDIDATES_PER_RAY);
        let gave_up = |what: &str, got: usize| {
            format!(
                "could not generate {what} rays: {got} of {n} after {budget} candidates ({MAX_CANDIDATES_PER_RAY} per ray); are the meshes near the f32 range limit?"
            )
        };
        if !all.is_empty() {
            let mut tries = 0usize;
            while outside_rays.len() < n {
                tries += 1;
                if tries > budget {
                    return Err(gave_up("just-outside", outside_rays.len()));
                }
                let (mi, f, tri) = all[rng.below(all.len())];
                if let Some(r) = just_outside(&mut rng, &tri) {
                    outside_rays.push((r, tri));
                    outside_ids.push((mi, f));
                }
            }
            let mut tries = 0usize;
            while pair_rays.len() < n {
                tries += 1;
                if tries > budget {
                    return Err(gave_up("triangle-aimed", pair_rays.len()));
                }
                let (mi, f, tri) = all[rng.below(all.len())];
                if let Some(r) = aim_at_triangle(&mut rng, &tri) {
                    pair_rays.push((r, tri));
                    pair_ids.push((mi, f));
                }
            }
        }
        let cost_tris: Vec<[Vec3; 3]> = (0..64.min(all.len()))
            .map(|_| all[rng.below(all.len())].2)
            .collect();
        let cost_rays = pair_rays.iter().take(4096).map(|(r, _)| *r).collect();
        Ok(Self {
            leak_rays,
            outside_rays,
            pair_rays,
            cost_rays,
            cost_tris,
            leak_mesh,
            outside_ids,
            pair_ids,
        })
    }
}

/// Candidates drawn per wanted ray before a generator gives up. Usable candidates are the
/// common case on ordinary meshes (most are accepted), so this is only reached when the
/// geometry makes acceptance (near) impossible.
pub const MAX_CANDIDATES_PER_RAY: usize = 1000;

/// Smallest `|cos|` between a ray origin's direction from its target and the target's normal,
/// unitless: `0.17`, rays at least `9.8°` off the plane (`asin 0.17`), so that the rays of
/// the workload meet their targets well away from grazing the plane.
pub const MIN_ORIGIN_COS: f64 = 0.17;

/// Directions drawn for a ray origin before giving up: a uniform direction is accepted with
/// probability `1 − 0.17 ≈ 0.83` ([`MIN_ORIGIN_COS`]), so 64 failures in a row happen with
/// probability `0.17⁶⁴`.
pub const MAX_ORIGIN_TRIES: usize = 64;

fn random_origin_for(rng: &mut Rng, target: DVec3, scale: f64, n: DVec3) -> Option<DVec3> {
    // From the front or back side, off the plane by MIN_ORIGIN_COS.
    (0..MAX_ORIGIN_TRIES).find_map(|_| {
        let d = rng.unit_vector();
        (d.dot(n).abs() > MIN_ORIGIN_COS).then(|| target + d * scale * (1.0 + 4.0 * rng.f64()))
    })
}

fn aim_at_triangle(rng: &mut Rng, tri: &[Vec3; 3]) -> Option<Ray> {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let n = (b - a).cross(c - a).normalize();
    let (r1, r2) = (rng.f64(), rng.f64());
    let s = r1.sqrt();
    // Push a tenth of the targets exactly onto an edge midpoint-ish line, the rest inside.
    let p = if rng.below(10) == 0 {
        a + (b - a) * r2
    } else {
        a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2)
    };
    let scale = (b - a).length().max((c - a).length());
    let o = random_origin_for(rng, p, scale, n)?;
    let ray = Ray::new(o.as_vec3(), (p - o).as_vec3());
    (ray.origin.is_finite() && ray.direction.is_finite()).then_some(ray)
}

fn just_outside(rng: &mut Rng, tri: &[Vec3; 3]) -> Option<Ray> {
    let v = tri.map(|p| p.as_dvec3());
    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    let k = rng.below(3);
    let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
    let e = b - a;
    let mut out = n.cross(e).normalize();
    if out.dot(c - a) > 0.0 {
        out = -out;
    }
    let p_edge = a + e * (0.05 + 0.9 * rng.f64());
    let scale = e.length();
    let o = random_origin_for(rng, p_edge, scale, n)?;
    let mag = v
        .iter()
        .map(|x| (*x - o).abs().max_element())
        .fold(0.0, f64::max);
    let p = p_edge + out * (OUTSIDE_OFFSET_ULPS * f32::EPSILON as f64 * mag);
    let ray = Ray::new(o.as_vec3(), (p - o).as_vec3());
    // Keep only rays clearly outside in ray space (after rounding to f32).
    let (bary, margin) = ray_space_barycentrics(&ray, tri)?;
    let outside = bary.iter().copied().fold(f64::INFINITY, f64::min) < -margin
        || bary.iter().copied().fold(f64::NEG_INFINITY, f64::max) > 1.0 + margin;
    outside.then_some(ray)
}

/// The oracle of the `t` error and hit/miss figures, sharing no code or formula with any
/// variant (the `f64` reference among them, which projects along the ray's dominant axis and
/// shears): whether the ray's line passes through `tri`, by its barycentrics in the plane
/// perpendicular to the ray (all `≥ 0`: [`ray_space_barycentrics`]), and the `t` where it
/// crosses `tri`'s plane ([`plane_crossing`]), both in `f64` from the `f32` inputs. `None` for
/// a miss, a crossing at `t ≤ 0`, or a triangle edge-on to the ray or degenerate.
pub fn oracle_t(ray: &Ray, tri: &[Vec3; 3]) -> Option<f64> {
    let (b, _) = ray_space_barycentrics(ray, tri)?;
    let (t, _) = plane_crossing(ray, tri)?;
    (b.iter().all(|&x| x >= 0.0) && t > 0.0).then_some(t)
}

/// Runs the accuracy workloads through one intersector.
pub fn accuracy<I: TriangleIntersector>(isect: &I, w: &Workload) -> Accuracy {
    let mut acc = Accuracy {
        leak_rays: w.leak_rays.len(),
        outside_rays: w.outside_rays.len(),
        ..Accuracy::default()
    };
    for (ray, tris) in &w.leak_rays {
        if !tris.iter().any(|t| isect.intersect(ray, t).is_some()) {
            acc.leaks += 1;
        }
    }
    for (ray, tri) in &w.outside_rays {
        if isect.intersect(ray, tri).is_some() {
            acc.false_hits += 1;
        }
    }
    for (ray, tri) in &w.pair_rays {
        let ours = isect.intersect(ray, tri);
        let reference = oracle_t(ray, tri);
        let clear_of_edges = !near_boundary(ray, tri);
        if clear_of_edges {
            acc.hit_miss_rays += 1;
            if ours.is_some() != reference.is_some() {
                acc.hit_miss_disagreements += 1;
            }
        }
        if let (Some(h), Some(t)) = (ours, reference) {
            acc.rel_t_errors.push(((h.t as f64 - t) / t).abs());
        }
    }
    acc.rel_t_errors.sort_by(f64::total_cmp);
    acc
}

/// Median ns per ray–triangle test over `reps` repetitions of every cost ray against every
/// cost triangle (mostly misses, as inside a BVH leaf).
pub fn ns_per_test<I: TriangleIntersector>(isect: &I, w: &Workload, reps: usize) -> f64 {
    median_of(reps, || {
        let start = Instant::now();
        let mut hits = 0u32;
        for ray in &w.cost_rays {
            let Some(pre) = isect.prepare(ray) else {
                continue;
            };
            for tri in &w.cost_tris {
                hits += isect
                    .intersect_prepared(&pre, ray, black_box(tri))
                    .is_some() as u32;
            }
        }
        black_box(hits);
        let tests = (w.cost_rays.len() * w.cost_tris.len()).max(1);
        start.elapsed().as_secs_f64() * 1.0e9 / tests as f64
    })
}

/// Accuracy and per-test cost of `variant` on `w`.
pub fn measure(variant: TriangleVariant, w: &Workload, reps: usize) -> (Accuracy, f64) {
    struct Measure<'a>(&'a Workload, usize);
    impl VariantVisitor for Measure<'_> {
        type Output = (Accuracy, f64);
        fn visit<I: TriangleIntersector>(self, i: &I) -> Self::Output {
            (accuracy(i, self.0), ns_per_test(i, self.0, self.1))
        }
    }
    variant.visit(Measure(w, reps))
}

/// Single-threaded closest-hit throughput through the BVH, Mrays/s (median of `reps` passes).
pub fn mrays_bvh<I: TriangleIntersector>(
    isect: &I,
    accel: &crate::accel::MeshAccel,
    rays: &[Ray],
    reps: usize,
) -> f64 {
    median_of(reps, || {
        let start = Instant::now();
        let mut hits = 0u32;
        for r in rays {
            hits += accel.closest(isect, black_box(r), None).is_some() as u32;
        }
        black_box(hits);
        crate::timing::mrays_per_second(rays.len() as u64, start.elapsed().as_secs_f64())
    })
}

/// [`mrays_bvh`] for a variant chosen at run time.
pub fn mrays_bvh_variant(
    variant: TriangleVariant,
    accel: &crate::accel::MeshAccel,
    rays: &[Ray],
    reps: usize,
) -> f64 {
    struct Mrays<'a>(&'a crate::accel::MeshAccel, &'a [Ray], usize);
    impl VariantVisitor for Mrays<'_> {
        type Output = f64;
        fn visit<I: TriangleIntersector>(self, i: &I) -> f64 {
            mrays_bvh(i, self.0, self.1, self.2)
        }
    }
    variant.visit(Mrays(accel, rays, reps))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worked by hand on the triangle `(0,0,0), (1,0,0), (0,1,0)`: a ray from `(0.25, 0.25, 2)`
    /// at four units a step down crosses it at `t = 1/2`; beside it (`x + y > 1`), away from it,
    /// and in its plane, there is nothing.
    #[test]
    fn the_oracle_is_the_plane_crossing_inside_the_triangle() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let down = Vec3::new(0.0, 0.0, -4.0);
        assert_eq!(
            oracle_t(&Ray::new(Vec3::new(0.25, 0.25, 2.0), down), &tri),
            Some(0.5)
        );
        // The same with the triangle wound the other way.
        let back = [Vec3::ZERO, Vec3::Y, Vec3::X];
        assert_eq!(
            oracle_t(&Ray::new(Vec3::new(0.25, 0.25, 2.0), down), &back),
            Some(0.5)
        );
        assert_eq!(
            oracle_t(&Ray::new(Vec3::new(0.75, 0.5, 2.0), down), &tri),
            None
        );
        assert_eq!(
            oracle_t(&Ray::new(Vec3::new(0.25, 0.25, 2.0), -down), &tri),
            None
        );
        assert_eq!(
            oracle_t(&Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::X), &tri),
            None
        );
        // Slanted: from (0, 0, 3) along (1, 1, -12)/4 the line reaches z = 0 at t = 1, at
        // (0.25, 0.25).
        let slanted = Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.25, 0.25, -3.0));
        let t = oracle_t(&slanted, &tri).unwrap();
        assert!((t - 1.0).abs() < 1e-15, "{t}");
    }
}
