//! The leaf test: what a query does with one primitive, behind one trait ([`LeafTest`]),
//! implemented by closures and by [`Triangles`] (a mesh with any triangle intersector).

use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::sealed::Inside;
use crate::simd_level::SimdLevel;
use crate::triangle::{BehindPlane, ShearedRays, TriangleHit, TriangleIntersector, TriangleLanes};
use glam::Vec3;

/// The test of one primitive against a ray, called by every structure's queries
/// ([`super::RayQuery`]).
///
/// One required test ([`LeafTest::intersect`]) and a per-ray setup ([`LeafTest::prepare`]);
/// another crate may also override [`LeafTest::prepare_valid`] (a ray the query has already
/// checked) and [`LeafTest::with_prepared`] (the test as one closure).
///
/// The other provided methods are this crate's internal hooks, hidden from these docs: the
/// test of a triangle whose vertices a wide tree stores, with the lane culls that tree runs
/// on four (eight) of them at once, their behind-the-origin refusals and the cull across
/// rays. [`Triangles`] forwards them to its [`TriangleIntersector`]'s. As there (see its
/// docs), their first argument is of a type no other crate can name or make, so another
/// crate can neither override nor call them: its leaf test keeps the defaults (no cull:
/// every primitive goes to [`LeafTest::intersect`]).
///
/// ```compile_fail,E0603
/// use halfray_core::Ray;
/// use halfray_core::query::LeafTest;
/// use halfray_core::simd_level::SimdLevel;
/// use halfray_core::triangle::TriangleLanes;
/// struct Nothing;
/// impl LeafTest for Nothing {
///     type Hit = ();
///     type Prepared = ();
///     fn prepare(&self, _: &Ray) -> Option<()> {
///         Some(())
///     }
///     fn intersect(&mut self, _: &(), _: u32, _: &Ray) -> Option<(f32, ())> {
///         None
///     }
///     // Not possible: `sealed` is private (and without its `Inside` the signature is not
///     // the trait's).
///     fn certain_misses<L: SimdLevel>(
///         &self,
///         _: halfray_core::sealed::Inside,
///         _: L,
///         _: &(),
///         _: &Ray,
///         _: &TriangleLanes,
///         _: Option<&TriangleLanes>,
///     ) -> u32 {
///         0xFF
///     }
/// }
/// ```
///
/// Implemented by every closure `FnMut(prim: u32, ray: &Ray) -> Option<(t, payload)>` (no
/// setup) and by [`Triangles`].
pub trait LeafTest {
    /// What a hit carries besides its `t`.
    type Hit;
    /// What the test precomputes once per ray.
    type Prepared;

    /// The per-ray setup, for a ray the query has not checked yet; `None` refuses the ray (an
    /// invalid one, [`Ray::validate`]), which then hits nothing.
    fn prepare(&self, ray: &Ray) -> Option<Self::Prepared>;

    /// [`LeafTest::prepare`] for a ray the query has already checked ([`Ray::is_valid`]):
    /// may skip the check. The default calls `prepare`.
    #[inline(always)]
    fn prepare_valid(&self, ray: &Ray) -> Option<Self::Prepared> {
        self.prepare(ray)
    }

    /// `(t, payload)` of a hit of primitive `prim` with `t` in `ray`'s interval
    /// `(t_min, t_max]`, where `t_max` is the current closest `t` (inclusive); hits outside it
    /// are ignored by the queries. `None` for a miss.
    fn intersect(&mut self, pre: &Self::Prepared, prim: u32, ray: &Ray)
    -> Option<(f32, Self::Hit)>;

    /// [`LeafTest::intersect`] with `pre` as one closure, which a traversal compiles into its
    /// loop. The default wraps `intersect`; an implementation may capture its parts by value
    /// instead (less indirection in the loop: [`Triangles`] does).
    #[inline(always)]
    fn with_prepared<'s>(
        &'s mut self,
        pre: &'s Self::Prepared,
    ) -> impl FnMut(u32, &Ray) -> Option<(f32, Self::Hit)> + 's {
        move |prim, ray| self.intersect(pre, prim, ray)
    }

    /// Internal hook (sealed: trait docs). [`LeafTest::intersect`] of triangle `prim` whose
    /// vertices `v` the structure stores (the wide trees), with the kernels of SIMD `level`
    /// where the test has them: the same answer as `intersect`. The default ignores `v` and
    /// `level`.
    #[doc(hidden)]
    #[inline(always)]
    fn intersect_triangle<L: SimdLevel>(
        &mut self,
        _: Inside,
        level: L,
        pre: &Self::Prepared,
        prim: u32,
        v: &[Vec3; 3],
        ray: &Ray,
    ) -> Option<(f32, Self::Hit)> {
        let _ = (level, v);
        self.intersect(pre, prim, ray)
    }

    /// Internal hook (sealed: trait docs). The lanes of one or two groups of stored triangles
    /// that this test certainly misses, at SIMD `level` (the same bits at every level): bit
    /// `i` for lane `i` of `first`, bit `4 + i` for lane `i` of `second` when given (see
    /// [`TriangleIntersector`]'s `certain_misses` and `certain_misses2`). A lane reported is
    /// never tested; one not reported is tested with `intersect_triangle`. The default culls
    /// none.
    #[doc(hidden)]
    #[inline(always)]
    fn certain_misses<L: SimdLevel>(
        &self,
        _: Inside,
        level: L,
        pre: &Self::Prepared,
        ray: &Ray,
        first: &TriangleLanes,
        second: Option<&TriangleLanes>,
    ) -> u32 {
        let _ = (level, pre, ray, first, second);
        0
    }

    /// Internal hook (sealed: trait docs). The lanes among `keep` of two groups of stored
    /// triangles (bits as in `certain_misses`; a single group passed twice) that this test
    /// misses because the ray's line certainly crosses their plane behind its origin
    /// ([`TriangleIntersector`]'s `behind_misses2`), at SIMD `level` (the same bits at every
    /// level). The any-hit walks call it on the lanes `certain_misses` kept. The default
    /// refuses none.
    #[doc(hidden)]
    #[inline(always)]
    fn behind_misses<L: SimdLevel>(
        &self,
        _: Inside,
        level: L,
        pre: &Self::Prepared,
        ray: &Ray,
        lanes: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        let _ = (level, pre, ray, lanes, keep);
        0
    }

    /// Internal hook (sealed: trait docs). The [`BehindPlane`] of a stored triangle `v`
    /// ([`TriangleIntersector`]'s `behind_plane`): a ray it [`BehindPlane::refuses`] gets
    /// `None` from `intersect_triangle`. The default has none.
    #[doc(hidden)]
    #[inline(always)]
    fn behind_plane(&self, _: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
        let _ = v;
        None
    }

    /// Internal hook (sealed: trait docs). The first [`crate::triangle::RAY_LANES`] rays of
    /// `rays` side by side for a cull across rays ([`TriangleIntersector`]'s
    /// `sheared_rays`): when `Some`, lane `i` of its [`ShearedRays::certain_misses`] is this
    /// test's `certain_misses` of `rays[i]` for every valid ray, and
    /// [`LeafTest::prepare_valid`] never refuses a valid ray. The default has none.
    #[doc(hidden)]
    #[inline(always)]
    fn sheared_rays(&self, _: Inside, rays: &[Ray]) -> Option<ShearedRays> {
        let _ = rays;
        None
    }
}

impl<H, F: FnMut(u32, &Ray) -> Option<(f32, H)>> LeafTest for F {
    type Hit = H;
    type Prepared = ();

    #[inline(always)]
    fn prepare(&self, _: &Ray) -> Option<()> {
        Some(())
    }

    #[inline(always)]
    fn intersect(&mut self, _: &(), prim: u32, ray: &Ray) -> Option<(f32, H)> {
        self(prim, ray)
    }
}

/// The triangles of `mesh` tested with the intersector `isect`, prepared once per ray:
/// a hit is the triangle's [`TriangleHit`]. Triangles whose vertex indices are out of range
/// are missed. The wide trees test the copies of the vertices they store (made from the mesh
/// they were built over), with the intersector's lane culls and SIMD kernels.
#[derive(Debug)]
pub struct Triangles<'a, I> {
    mesh: &'a TriangleMesh<'a>,
    isect: &'a I,
}

impl<I> Clone for Triangles<'_, I> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<I> Copy for Triangles<'_, I> {}

impl<'a, I: TriangleIntersector> Triangles<'a, I> {
    /// The triangles of `mesh` with the intersector `isect`.
    #[inline(always)]
    #[must_use]
    pub const fn new(mesh: &'a TriangleMesh<'a>, isect: &'a I) -> Self {
        Self { mesh, isect }
    }
}

impl<I: TriangleIntersector> LeafTest for Triangles<'_, I> {
    type Hit = TriangleHit;
    type Prepared = I::Prepared;

    #[inline(always)]
    fn prepare(&self, ray: &Ray) -> Option<I::Prepared> {
        self.isect.prepare(ray)
    }

    #[inline(always)]
    fn prepare_valid(&self, ray: &Ray) -> Option<I::Prepared> {
        self.isect.prepare_valid(ray)
    }

    #[inline(always)]
    fn intersect(&mut self, pre: &I::Prepared, prim: u32, ray: &Ray) -> Option<(f32, TriangleHit)> {
        let v = self.mesh.triangle(prim as usize)?;
        self.isect
            .intersect_prepared(pre, ray, &v)
            .map(|h| (h.t, h))
    }

    #[inline(always)]
    fn with_prepared<'s>(
        &'s mut self,
        pre: &'s I::Prepared,
    ) -> impl FnMut(u32, &Ray) -> Option<(f32, TriangleHit)> + 's {
        let (mesh, isect) = (self.mesh, self.isect);
        move |prim, ray| {
            let v = mesh.triangle(prim as usize)?;
            isect.intersect_prepared(pre, ray, &v).map(|h| (h.t, h))
        }
    }

    #[inline(always)]
    fn intersect_triangle<L: SimdLevel>(
        &mut self,
        inside: Inside,
        level: L,
        pre: &I::Prepared,
        _: u32,
        v: &[Vec3; 3],
        ray: &Ray,
    ) -> Option<(f32, TriangleHit)> {
        let hit = self
            .isect
            .intersect_prepared_on(inside, level, pre, ray, v)?;
        Some((hit.t, hit))
    }

    #[inline(always)]
    fn certain_misses<L: SimdLevel>(
        &self,
        inside: Inside,
        level: L,
        pre: &I::Prepared,
        ray: &Ray,
        first: &TriangleLanes,
        second: Option<&TriangleLanes>,
    ) -> u32 {
        match second {
            Some(second) => self
                .isect
                .certain_misses2(inside, level, pre, ray, first, second),
            None => self.isect.certain_misses(inside, pre, ray, first),
        }
    }

    #[inline(always)]
    fn behind_misses<L: SimdLevel>(
        &self,
        inside: Inside,
        level: L,
        pre: &I::Prepared,
        ray: &Ray,
        lanes: [&TriangleLanes; 2],
        keep: u32,
    ) -> u32 {
        self.isect
            .behind_misses2(inside, level, pre, ray, lanes, keep)
    }

    #[inline(always)]
    fn behind_plane(&self, inside: Inside, v: &[Vec3; 3]) -> Option<BehindPlane> {
        self.isect.behind_plane(inside, v)
    }

    #[inline(always)]
    fn sheared_rays(&self, inside: Inside, rays: &[Ray]) -> Option<ShearedRays> {
        self.isect.sheared_rays(inside, rays)
    }
}
