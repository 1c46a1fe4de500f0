//! The oracle of the tree targets (`bvh`, `bvh_load`, `grid`, `kdtree`): which primitives a
//! tree must hold, brute force with the trees' tie rule over them, and the checks of a tree's
//! closest and any hit on one ray against it.

use super::bvh::{projection_underflows, within_domain};
use super::{fmt_ray, reached};
use core::fmt::Debug;
use glam::Vec3;
use halfray_core::mesh::{PrimitiveSource, TriangleMesh};
use halfray_core::query::{Query, RayQuery, Triangles};
use halfray_core::ray::Ray;
use halfray_core::triangle::{F64Reference, TriangleHit, TriangleIntersector};

/// Smallest barycentric coordinate (of the `f64` reference solution) for which a brute-force
/// hit counts as **clear** outside the exact domain ([`Oracle::assert_finds_clear_hit`]):
/// `10⁻³`, far beyond any `f32` intersector's rounding on the triangles where it holds, so the
/// ray's exact crossing lies inside the triangle and therefore inside every box that holds
/// it. Unitless.
pub const CLEAR_HIT_BARYCENTRIC: f64 = 1e-3;

/// For each triangle of `mesh`, whether its bounds are usable (finite and valid): the
/// triangles a BVH or kd-tree holds when `exclude_non_finite` is on, and the first one that
/// is not is the one a build without it must name.
pub(crate) fn usable_primitives(mesh: &TriangleMesh<'_>) -> Vec<bool> {
    (0..mesh.primitive_count())
        .map(|i| {
            let b = mesh.primitive_bounds(i);
            b.is_finite() && b.is_valid()
        })
        .collect()
}

/// The box queries' oracle, written from their contract and sharing no code with `Aabb` or
/// the trees: whether triangle `v` overlaps the closed box `[lo, hi]`. A triangle with a
/// non-finite coordinate overlaps nothing (its bounds are unusable, so no tree holds it);
/// otherwise it overlaps exactly when, on every axis, the closed interval from the smallest
/// to the largest of its three vertex coordinates meets `[lo, hi]` — compared in `f64`, so a
/// NaN bound meets nothing.
///
/// The core's unit tests have the same oracle in their `test_util` module, which only the
/// core's own `cargo test` compiles; this crate cannot use the `halfray-tests` support crate
/// either (that crate dev-depends on this one, and the cargo-fuzz targets build this one
/// alone). Hence one copy on each side of that boundary.
pub(crate) fn triangle_meets_box(v: &[Vec3; 3], lo: Vec3, hi: Vec3) -> bool {
    let coords = v.map(|p| [f64::from(p.x), f64::from(p.y), f64::from(p.z)]);
    if !coords.iter().flatten().all(|c| c.is_finite()) {
        return false;
    }
    let (lo, hi) = (lo.to_array(), hi.to_array());
    (0..3).all(|axis| {
        // Finite coordinates (checked above): `min`/`max` are the plain order.
        let [a, b, c] = coords.map(|p| p[axis]);
        a.min(b).min(c) <= f64::from(hi[axis]) && f64::from(lo[axis]) <= a.max(b).max(c)
    })
}

/// Brute force with the BVH's rule: the smallest `t` in the ray's interval, ties to the
/// smaller primitive index, over the primitives in the tree (`in_tree[i]`), shared by the
/// `bvh`, `grid` and `kdtree` targets.
pub(crate) fn brute<T: TriangleIntersector>(
    mesh: &TriangleMesh<'_>,
    isect: &T,
    ray: &Ray,
    in_tree: &[bool],
) -> Option<(u32, TriangleHit)> {
    let mut best: Option<(u32, TriangleHit)> = None;
    for (i, &live) in in_tree.iter().enumerate() {
        let Some(v) = mesh.triangle(i).filter(|_| live) else {
            continue;
        };
        if let Some(h) = isect.intersect(ray, &v)
            && best.is_none_or(|(_, b)| h.t < b.t)
        {
            best = Some((i as u32, h));
        }
    }
    best
}

/// A tree build's result against the rule for unusable primitives: with none, or with
/// `exclude` (`exclude_non_finite`) on, the build succeeds and the tree is returned; with
/// `exclude` off it refuses, naming the first one, `first_bad`, and `None` is returned.
/// Anything else panics, with `ctx()`. `non_finite` reads the index out of the structure's
/// `NonFinite` error (`None` for its other errors).
pub(crate) fn checked_build<T, E: Debug>(
    built: Result<T, E>,
    non_finite: impl Fn(&E) -> Option<usize>,
    first_bad: Option<usize>,
    exclude: bool,
    ctx: &dyn Fn() -> String,
) -> Option<T> {
    match (built, first_bad) {
        (Ok(t), None) => Some(t),
        (Ok(t), Some(_)) if exclude => Some(t),
        (Err(e), Some(bad)) if !exclude && non_finite(&e).is_some() => {
            reached();
            assert_eq!(
                non_finite(&e),
                Some(bad),
                "NonFinite names the wrong primitive\n{}",
                ctx()
            );
            None
        }
        (r, _) => panic!(
            "build gave {:?} (first unusable primitive {first_bad:?})\n{}",
            r.err(),
            ctx()
        ),
    }
}

/// A tree's answer to a closest- or any-hit query: `(primitive index, hit)`, or `None`.
pub(crate) type TreeAnswer = Option<(u32, TriangleHit)>;

/// What a tree's answers on one ray are checked against: brute force over the primitives
/// `in_tree` of `mesh`.
pub struct Oracle<'a, 'm> {
    /// The triangles.
    pub mesh: &'a TriangleMesh<'m>,
    /// Which primitives the tree holds.
    pub in_tree: &'a [bool],
    /// The case (ray and input), for failure messages.
    pub ctx: &'a dyn Fn() -> String,
}

impl<'m> Oracle<'_, 'm> {
    /// Calls `check(oracle, ray)` for every ray of `rays`, the oracle's being brute force over
    /// the primitives `in_tree` of `mesh` with the ray, then `ctx()`, as its failure context.
    pub(crate) fn each_ray(
        mesh: &TriangleMesh<'m>,
        in_tree: &[bool],
        ctx: &dyn Fn() -> String,
        rays: &[Ray],
        mut check: impl FnMut(&Oracle<'_, 'm>, &Ray),
    ) {
        for ray in rays {
            let rctx = || format!("{}\n{}", fmt_ray(ray), ctx());
            let oracle = Oracle {
                mesh,
                in_tree,
                ctx: &rctx,
            };
            check(&oracle, ray);
        }
    }

    /// Brute force's closest hit of `isect` on `ray` (see [`brute`]).
    pub(crate) fn closest<T: TriangleIntersector>(
        &self,
        isect: &T,
        ray: &Ray,
    ) -> Option<(u32, TriangleHit)> {
        brute(self.mesh, isect, ray, self.in_tree)
    }

    /// `true` where a tree must give brute force's answers exactly: an `exact` intersector
    /// inside its documented domain (`Watertight` docs), with no projection underflowing.
    pub(crate) fn exact_on(&self, ray: &Ray, exact: bool) -> bool {
        exact
            && within_domain(self.mesh, ray, self.in_tree)
            && !projection_underflows(self.mesh, ray, self.in_tree)
    }

    /// Asserts that a tree's `hit` is the intersector's own answer for that primitive.
    pub(crate) fn assert_genuine<T: TriangleIntersector>(
        &self,
        isect: &T,
        ray: &Ray,
        (p, h): (u32, TriangleHit),
        what: &str,
    ) {
        let v = self
            .mesh
            .triangle(p as usize)
            .expect("hit primitive exists");
        assert_eq!(
            isect.intersect(ray, &v),
            Some(h),
            "{what}\n{}",
            (self.ctx)()
        );
    }

    /// Outside the exact domain: the tree's closest hit `got` is no nearer than brute
    /// force's `want`.
    pub(crate) fn assert_no_nearer(
        &self,
        got: Option<(u32, TriangleHit)>,
        want: Option<(u32, TriangleHit)>,
        tree: &str,
    ) {
        if let Some((_, h)) = got {
            let (_, w) = want.expect("brute force finds every BVH hit");
            assert!(
                w.t <= h.t,
                "{tree}: nearer than brute force\n{}",
                (self.ctx)()
            );
        }
    }

    /// Outside the exact domain, where the answer is still decidable: when brute force's hit
    /// `want` is **clear** (the `f64` reference, an independent solution, puts the ray's exact
    /// crossing of that triangle at every barycentric ≥ [`CLEAR_HIT_BARYCENTRIC`] and at
    /// `t_ref ≤ want.t`, beyond `t_min`), every box holding the triangle is entered no later
    /// than `t_ref`, so no cull can skip it: the tree's closest hit `got` is at `want`'s `t`
    /// (with [`Oracle::assert_no_nearer`]), and its any hit `any` exists.
    pub(crate) fn assert_finds_clear_hit(
        &self,
        ray: &Ray,
        got: Option<(u32, TriangleHit)>,
        any: Option<(u32, TriangleHit)>,
        want: Option<(u32, TriangleHit)>,
        tree: &str,
    ) {
        let Some((p, w)) = want else { return };
        let Some(v) = self.mesh.triangle(p as usize) else {
            return;
        };
        let Some((t_ref, b)) = F64Reference::solve(ray, &v) else {
            return;
        };
        let clear = b.iter().all(|&x| x >= CLEAR_HIT_BARYCENTRIC)
            && t_ref.is_finite()
            && t_ref <= f64::from(w.t)
            && t_ref > f64::from(ray.t_min);
        if !clear {
            return;
        }
        reached();
        assert!(
            got.is_some_and(|(_, h)| h.t <= w.t),
            "{tree}: missed brute force's clear hit {want:?} (reference t = {t_ref:e}, \
             barycentrics {b:?}), got {got:?}\n{}",
            (self.ctx)()
        );
        assert!(
            any.is_some(),
            "{tree}: any-hit found nothing where brute force has a clear hit {want:?}\n{}",
            (self.ctx)()
        );
    }

    /// Inside the exact domain: the tree's closest hit `got` is brute force's `want`, and its
    /// any-hit answer `any` finds a hit exactly when brute force does.
    pub(crate) fn assert_agrees(
        &self,
        (name, tree): (&str, &str),
        got: Option<(u32, TriangleHit)>,
        any: Option<(u32, TriangleHit)>,
        want: Option<(u32, TriangleHit)>,
    ) {
        let ctx = self.ctx;
        reached();
        assert_eq!(
            got,
            want,
            "{name}: {tree} closest hit differs from brute force\n{}",
            ctx()
        );
        assert_eq!(
            any.is_some(),
            want.is_some(),
            "{name}: {tree} any-hit {any:?} disagrees with brute force {want:?}\n{}",
            ctx()
        );
    }

    /// Queries `structure` for the closest and the any hit of `ray` through `isect` (portable
    /// level, default stack), checks both with [`Oracle::assert_answers`] and returns them
    /// (closest, any). `tree` names the structure in failure messages.
    pub(crate) fn check_queries<Q: RayQuery, T: TriangleIntersector>(
        &self,
        structure: &Q,
        tree: &str,
        isect: &T,
        ray: &Ray,
        exact: bool,
    ) -> (TreeAnswer, TreeAnswer) {
        let got = structure.closest_hit(
            ray,
            &mut Triangles::new(self.mesh, isect),
            &mut Query::new(),
        );
        let any = structure.any_hit(
            ray,
            &mut Triangles::new(self.mesh, isect),
            &mut Query::new(),
        );
        self.assert_answers(isect, ray, exact, tree, got, any);
        (got, any)
    }

    /// The checks a structure's closest hit `got` and any hit `any` of `ray` (with
    /// `isect`) get in every tree target: each is a
    /// genuine hit of a primitive in the tree with `t` in the ray's interval; then
    /// [`Oracle::assert_agrees`] where [`Oracle::exact_on`]`(ray, exact)`, else
    /// [`Oracle::assert_no_nearer`] and [`Oracle::assert_finds_clear_hit`]. `tree` names the
    /// structure in failure messages.
    pub(crate) fn assert_answers<T: TriangleIntersector>(
        &self,
        isect: &T,
        ray: &Ray,
        exact: bool,
        tree: &str,
        got: Option<(u32, TriangleHit)>,
        any: Option<(u32, TriangleHit)>,
    ) {
        let want = self.closest(isect, ray);
        for &(p, h) in got.iter().chain(any.iter()) {
            assert!(
                self.in_tree.get(p as usize) == Some(&true),
                "{tree}: hit of a primitive not in the tree\n{}",
                (self.ctx)()
            );
            self.assert_genuine(isect, ray, (p, h), &format!("{tree} hit record"));
            assert!(
                ray.contains(h.t),
                "{tree}: t outside the interval\n{}",
                (self.ctx)()
            );
        }
        if self.exact_on(ray, exact) {
            self.assert_agrees((isect.name(), tree), got, any, want);
        } else {
            self.assert_no_nearer(got, want, tree);
            self.assert_finds_clear_hit(ray, got, any, want, tree);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use halfray_core::Vec3;
    use halfray_core::triangle::MollerTrumbore;

    /// A ray through the centroid of a unit triangle: brute force's hit is clear, so a tree
    /// that reports nothing (or only a farther hit) fails, and one that reports it passes.
    #[test]
    fn a_missed_clear_hit_fails() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, -1.0)];
        let triangles = [[0, 1, 2], [3, 1, 2]];
        let mesh = TriangleMesh::new(&positions, &triangles);
        let in_tree = [true, true];
        let ctx = || String::from("unit test");
        let oracle = Oracle {
            mesh: &mesh,
            in_tree: &in_tree,
            ctx: &ctx,
        };
        let ray = Ray::new(Vec3::new(0.3, 0.3, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let isect = MollerTrumbore::default();
        let want = oracle.closest(&isect, &ray);
        assert_eq!(want.map(|(p, _)| p), Some(0));
        oracle.assert_finds_clear_hit(&ray, want, want, want, "tree");
        let farther = brute(&mesh, &isect, &ray, &[false, true]);
        assert!(farther.is_some_and(|(_, h)| h.t > want.unwrap().1.t));
        for got in [None, farther] {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                oracle.assert_finds_clear_hit(&ray, got, got, want, "tree");
            }));
            assert!(r.is_err(), "{got:?} must fail the check");
        }
    }
}
