//! The traits the core's docs name as meant for other crates (`halfray_core`'s crate docs,
//! "Traits: which to implement") can be implemented here, outside the core, through its
//! public interface alone, and each implementation is used the way the core uses its own:
//! `Primitive`, `PrimitiveSource`, `LeafTest`, `TriangleIntersector`, `VariantVisitor`,
//! `Shape`, `PointSet`, `RayQuery`; `LeafTest` and `TriangleIntersector` with only the
//! methods another crate can write (their internal hooks are sealed). (The sealed traits,
//! `Stack` and `ShearedTest`, and those hooks have `compile_fail` doctests in the core.)

use glam::Vec3;
use halfray_core::aabb::Aabb;
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
use halfray_core::hit::Hit;
use halfray_core::mesh::{Primitive, PrimitiveSource, TriangleMesh};
use halfray_core::query::{LeafTest, Query, RayQuery, Stack, StackEntry, Triangles};
use halfray_core::shape::Shape;
use halfray_core::simd_level::SimdLevel;
use halfray_core::sphere::Sphere;
use halfray_core::triangle::{
    TriangleHit, TriangleIntersector, TriangleVariant, VariantVisitor, Watertight, WatertightRay,
};
use halfray_core::volume::{BoundingSphere, PointSet};
use halfray_core::{Ray, solids};

/// A cube of half-size `h` around `c`.
#[derive(Clone, Copy, Debug)]
struct Cube {
    c: Vec3,
    h: f32,
}

impl Primitive for Cube {
    fn bounds(&self) -> Aabb {
        Aabb::new(self.c - self.h, self.c + self.h)
    }
}

/// Cubes along `x`, one every 3 units, without a slice.
struct Row(u32);

impl PrimitiveSource for Row {
    fn primitive_count(&self) -> usize {
        self.0 as usize
    }

    fn primitive_bounds(&self, index: usize) -> Aabb {
        Cube {
            c: Vec3::new(3.0 * index as f32, 0.0, 0.0),
            h: 1.0,
        }
        .bounds()
    }
}

/// The box of each of `Row`'s cubes as the leaf test, counting its calls.
struct RowBoxes<'a> {
    row: &'a Row,
    tests: usize,
}

impl LeafTest for RowBoxes<'_> {
    type Hit = ();
    type Prepared = ();

    fn prepare(&self, ray: &Ray) -> Option<()> {
        ray.is_valid().then_some(())
    }

    fn intersect(&mut self, _: &(), prim: u32, ray: &Ray) -> Option<(f32, ())> {
        self.tests += 1;
        let (t, _) = self
            .row
            .primitive_bounds(prim as usize)
            .intersect_ray(ray)?;
        (t > ray.t_min).then_some((t, ()))
    }
}

/// The watertight test under another name.
#[derive(Clone, Copy, Debug)]
struct Renamed;

impl TriangleIntersector for Renamed {
    type Prepared = WatertightRay;

    fn name(&self) -> &'static str {
        "renamed"
    }

    fn prepare(&self, ray: &Ray) -> Option<WatertightRay> {
        Watertight.prepare(ray)
    }

    fn intersect_prepared(
        &self,
        pre: &WatertightRay,
        ray: &Ray,
        v: &[Vec3; 3],
    ) -> Option<TriangleHit> {
        Watertight.intersect_prepared(pre, ray, v)
    }
}

/// A sphere seen through a newtype.
struct Ball(Sphere);

impl Shape for Ball {
    fn bounds(&self) -> Aabb {
        Shape::bounds(&self.0)
    }

    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        Shape::closest_hit(&self.0, ray)
    }
}

/// The corners of the unit cube.
struct Corners;

impl PointSet for Corners {
    fn point_count(&self) -> usize {
        8
    }

    fn point(&self, index: usize) -> Option<Vec3> {
        (index < 8).then(|| {
            Vec3::new(
                (index & 1) as f32,
                (index >> 1 & 1) as f32,
                (index >> 2 & 1) as f32,
            )
        })
    }
}

/// A brute-force "structure" over `n` primitives: every query tests all of them.
struct Brute(u32);

impl Brute {
    fn walk<T: LeafTest>(&self, ray: &Ray, leaf: &mut T, any: bool) -> Option<(u32, T::Hit)> {
        let pre = leaf.prepare(ray)?;
        let mut r = *ray;
        let mut best = None;
        for prim in 0..self.0 {
            if let Some((t, h)) = leaf.intersect(&pre, prim, &r) {
                // Of equal t the smaller index, the core's tie rule: shrink past it.
                r.t_max = t.next_down();
                best = Some((prim, h));
                if any {
                    break;
                }
            }
        }
        best
    }
}

impl RayQuery for Brute {
    fn closest_hit<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut T,
        _ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, T::Hit)> {
        S::answer(Ok(self.walk(ray, leaf, false)))
    }

    fn any_hit<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut T,
        _ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, T::Hit)> {
        S::answer(Ok(self.walk(ray, leaf, true)))
    }

    fn query_box<P: PrimitiveSource + ?Sized>(
        &self,
        source: &P,
        query: &Aabb,
        mut found: impl FnMut(u32) -> bool,
    ) -> usize {
        let mut n = 0;
        for prim in 0..self.0 {
            if source.primitive_bounds(prim as usize).overlaps(query) {
                n += 1;
                if !found(prim) {
                    break;
                }
            }
        }
        n
    }

    fn primitive_count(&self) -> usize {
        self.0 as usize
    }

    fn bytes_used(&self) -> usize {
        0
    }
}

/// A BVH over another crate's `PrimitiveSource` of `Primitive`s, queried with its
/// `LeafTest`, answers as the brute-force `RayQuery` does, through both the default stack
/// and a caller's.
#[test]
fn primitives_sources_leaf_tests_and_a_ray_query_of_another_crate() {
    let row = Row(9);
    let mut nodes = vec![BvhNode::EMPTY; node_capacity(9)];
    let mut indices = vec![0u32; index_capacity(9)];
    let bvh = Bvh::build(&row, &mut nodes, &mut indices, &BuildOptions::default()).unwrap();
    let brute = Brute(9);
    let mut stack = [StackEntry::EMPTY; 16];
    for (o, d, want) in [
        (Vec3::new(-5.0, 0.0, 0.0), Vec3::X, Some(0)),
        (Vec3::new(30.0, 0.5, 0.0), -Vec3::X, Some(8)),
        (Vec3::new(12.0, 5.0, 0.0), -Vec3::Y, Some(4)),
        (Vec3::new(12.0, 5.0, 0.0), Vec3::Y, None),
    ] {
        let ray = Ray::new(o, d);
        let mut leaf = RowBoxes {
            row: &row,
            tests: 0,
        };
        let ours = bvh
            .closest_hit(&ray, &mut leaf, &mut Query::new())
            .map(|h| h.0);
        let theirs = brute_closest(&brute, &row, &ray);
        assert_eq!((ours, theirs), (want, want), "{ray:?}");
        let mut ctx = Query::new().stack(&mut stack);
        let on_stack = brute.any_hit(&ray, &mut leaf, &mut ctx).unwrap();
        assert_eq!(on_stack.is_some(), want.is_some(), "{ray:?}");
        assert!(leaf.tests > 0);
    }
    let mut seen = Vec::new();
    let one = Cube {
        c: Vec3::new(6.0, 0.0, 0.0),
        h: 0.1,
    };
    let reported = brute.query_box(&row, &one.bounds(), |p| {
        seen.push(p);
        true
    });
    assert_eq!((reported, seen), (1, vec![2]));
    assert_eq!(bvh.query_box(&row, &one.bounds(), |_| true), 1);
}

fn brute_closest(brute: &Brute, row: &Row, ray: &Ray) -> Option<u32> {
    let mut leaf = RowBoxes { row, tests: 0 };
    brute
        .closest_hit(ray, &mut leaf, &mut Query::new())
        .map(|h| h.0)
}

/// Another crate's triangle intersector works in `Triangles` (through a BVH), and a
/// `VariantVisitor` runs a query with each variant's intersector.
#[test]
fn a_triangle_intersector_and_a_variant_visitor_of_another_crate() {
    let mesh = TriangleMesh::new(&solids::OCTAHEDRON_VERTICES, &solids::OCTAHEDRON_TRIANGLES);
    let n = mesh.len();
    let mut nodes = vec![BvhNode::EMPTY; node_capacity(n)];
    let mut indices = vec![0u32; index_capacity(n)];
    let bvh = Bvh::build(&mesh, &mut nodes, &mut indices, &BuildOptions::default()).unwrap();
    let ray = Ray::new(Vec3::new(0.1, 0.2, 5.0), -Vec3::Z);
    let mine = bvh.closest_hit(
        &ray,
        &mut Triangles::new(&mesh, &Renamed),
        &mut Query::new(),
    );
    let wt = bvh.closest_hit(
        &ray,
        &mut Triangles::new(&mesh, &Watertight),
        &mut Query::new(),
    );
    assert!(mine.is_some());
    assert_eq!(mine, wt);

    // A visitor that closest-hits the mesh through the BVH with each variant's intersector:
    // every variant finds the watertight test's triangle on this plain ray.
    struct Closest<'a, B>(&'a B, &'a TriangleMesh<'a>, Ray);
    impl<B: RayQuery> VariantVisitor for Closest<'_, B> {
        type Output = Option<u32>;
        fn visit<I: TriangleIntersector>(self, isect: &I) -> Option<u32> {
            let mut leaf = Triangles::new(self.1, isect);
            let hit = self.0.closest_hit(&self.2, &mut leaf, &mut Query::new());
            hit.map(|(prim, _)| prim)
        }
    }
    for v in TriangleVariant::ALL {
        let prim = v.visit(Closest(&bvh, &mesh, ray));
        assert_eq!(prim, wt.map(|h| h.0), "{}", v.name());
    }
}

/// Another crate's `Shape` and `PointSet`.
#[test]
fn a_shape_and_a_point_set_of_another_crate() {
    let ball = Ball(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap());
    let hit = Shape::closest_hit(&ball, &Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
    // Exactly 4: on the axis through the centre every intermediate value (the offset
    // `(0, 0, −5)`, its projection, the discriminant, its square root 1) is a small integer,
    // so nothing rounds.
    assert_eq!(hit.t, 4.0, "{hit:?}");
    assert!(ball.bounds().contains_point(Vec3::new(0.0, 0.0, 6.0)));
    let fit = BoundingSphere::fit(&Corners).unwrap();
    for i in 0..8 {
        assert!(fit.contains_point(Corners.point(i).unwrap()));
    }
}
