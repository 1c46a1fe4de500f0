//! The closest-hit / any-hit pairs of the structures' public ray queries, each pair written
//! once: [`closest_and_any!`] for one signature, [`hit_queries!`] for the grid's and the
//! kd-tree's four queries over their private `traverse`.

/// Expands, inside an inherent `impl` block, to two public methods with one signature and one
/// body: the closest-hit form, then the any-hit form, each with the attributes (doc comment
/// first) written before its name. The body sees the identifier after `const` as a
/// `const bool`: `false` in the closest-hit form, `true` in the any-hit form. The receiver is
/// spelled in the invocation (`&self`), so that the body may use it.
///
/// ```text
/// closest_and_any! {
///     /// The closest hit ...
///     fn closest_hit;
///     /// Any hit ...
///     fn any_hit;
///     <H>(&self, ray: &Ray, ...) -> Option<(u32, H)>, const ANY => { self.traverse(ray, ANY) }
/// }
/// ```
/// (A macro: the pair differs in one constant, and two copies of a signature drift apart.)
macro_rules! closest_and_any {
    (
        $(#[$closest_attr:meta])* fn $closest:ident;
        $(#[$any_attr:meta])* fn $any:ident;
        <$($gen:ident $(: $bound:path)?),*>
        (&$this:ident, $($arg:ident: $ty:ty),* $(,)?) -> $ret:ty, const $flag:ident => $body:block
    ) => {
        $(#[$closest_attr])*
        pub fn $closest<$($gen $(: $bound)?),*>(&$this, $($arg: $ty),*) -> $ret {
            const $flag: bool = false;
            $body
        }

        $(#[$any_attr])*
        pub fn $any<$($gen $(: $bound)?),*>(&$this, $($arg: $ty),*) -> $ret {
            const $flag: bool = true;
            $body
        }
    };
}

pub(crate) use closest_and_any;

/// Expands, inside an inherent `impl` block, to the public `closest_hit`, `any_hit`,
/// `closest_hit_triangles` and `any_hit_triangles`, each with the attributes (doc comment
/// first) written before its name in the invocation. The type must have
///
/// ```text
/// fn traverse<H>(&self, ray: &Ray, intersect: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
///                stats: Option<&mut $stats>, any: bool) -> Option<(u32, H)>
/// ```
///
/// returning the closest hit (`any == false`) or any hit (`any == true`) and adding its
/// counters to `stats`. The `_triangles` forms prepare the intersector once per ray
/// ([`crate::bvh::TriangleMesh`]'s `prepared_intersect`) and return `None` for a ray it
/// refuses, without traversing. (A macro: inherent methods cannot come from a function, and
/// a trait would make callers import it.)
macro_rules! hit_queries {
    (
        stats: $stats:ty;
        $(#[$closest:meta])* closest_hit;
        $(#[$any:meta])* any_hit;
        $(#[$closest_tri:meta])* closest_hit_triangles;
        $(#[$any_tri:meta])* any_hit_triangles;
    ) => {
        $crate::hit_queries::hit_queries!(@closure $stats, [$(#[$closest])*] closest_hit, false);
        $crate::hit_queries::hit_queries!(@closure $stats, [$(#[$any])*] any_hit, true);
        $crate::hit_queries::hit_queries!(
            @triangles $stats, [$(#[$closest_tri])*] closest_hit_triangles, false
        );
        $crate::hit_queries::hit_queries!(
            @triangles $stats, [$(#[$any_tri])*] any_hit_triangles, true
        );
    };
    (@closure $stats:ty, [$(#[$attr:meta])*] $name:ident, $any:literal) => {
        $(#[$attr])*
        pub fn $name<H>(
            &self,
            ray: &$crate::ray::Ray,
            intersect: impl FnMut(u32, &$crate::ray::Ray) -> Option<(f32, H)>,
            stats: Option<&mut $stats>,
        ) -> Option<(u32, H)> {
            self.traverse(ray, intersect, stats, $any)
        }
    };
    (@triangles $stats:ty, [$(#[$attr:meta])*] $name:ident, $any:literal) => {
        $(#[$attr])*
        pub fn $name<T: $crate::triangle::TriangleIntersector>(
            &self,
            mesh: &$crate::bvh::TriangleMesh<'_>,
            isect: &T,
            ray: &$crate::ray::Ray,
            stats: Option<&mut $stats>,
        ) -> Option<(u32, $crate::triangle::TriangleHit)> {
            self.traverse(ray, mesh.prepared_intersect(isect, ray)?, stats, $any)
        }
    };
}

pub(crate) use hit_queries;
