//! What every structure is built over: primitives with bounds, given by index
//! ([`PrimitiveSource`], [`Primitive`]), and the indexed triangle mesh ([`TriangleMesh`]).
//! The builders ([`crate::bvh::Bvh`], [`crate::kdtree::KdTree`], [`crate::grid::Grid`]) bin
//! or clip each primitive by its box; intersection is supplied at query time
//! ([`crate::query::LeafTest`]).

use crate::aabb::Aabb;
use glam::Vec3;

/// One primitive as the builder sees it. Intersection is not part of the trait: it is passed
/// to each query as a closure, so the same tree serves any intersector.
pub trait Primitive {
    /// A box containing the primitive. Non-finite or empty bounds mark the primitive invalid
    /// (see [`crate::bvh::BuildOptions::exclude_non_finite`]). Boxes of curved primitives computed
    /// from rounded values must be padded outward so that they contain the exact surface.
    fn bounds(&self) -> Aabb;
}

/// `N` primitives by index `0..N`.
///
/// Implementations must not panic for any index below [`PrimitiveSource::primitive_count`];
/// invalid primitives report non-finite bounds. Both methods are functions of the source and
/// the index: a builder may read a primitive's bounds more than once. A source whose answers
/// change between calls still gets a well-formed structure (no panic, no cycle, every
/// primitive of a BVH in exactly one leaf), but its boxes may not contain its primitives, and
/// a kd-tree leaves out a primitive whose bounds turn unusable after the build checked them.
/// A build asks for no index at or beyond the count its first call of
/// [`PrimitiveSource::primitive_count`] returned, and takes the primitives the structure
/// holds, its root's box and the indices it stores from one pass over the source, so that
/// they agree with each other.
pub trait PrimitiveSource {
    /// Number of primitives `N`.
    fn primitive_count(&self) -> usize;

    /// Bounds of primitive `index` (see [`Primitive::bounds`]).
    fn primitive_bounds(&self, index: usize) -> Aabb;
}

/// Bounds reported for an index that does not name a valid primitive: all NaN, so the builder
/// rejects or excludes it.
pub(crate) const INVALID_BOUNDS: Aabb = Aabb::new(Vec3::NAN, Vec3::NAN);

impl<P: Primitive> PrimitiveSource for [P] {
    #[inline]
    fn primitive_count(&self) -> usize {
        self.len()
    }

    #[inline]
    fn primitive_bounds(&self, index: usize) -> Aabb {
        self.get(index).map_or(INVALID_BOUNDS, P::bounds)
    }
}

impl Primitive for Aabb {
    #[inline]
    fn bounds(&self) -> Aabb {
        *self
    }
}

impl Primitive for [Vec3; 3] {
    /// The vertices' box; all-NaN (invalid) when a vertex is not finite. (The check is explicit
    /// because `min`/`max` would silently drop a NaN coordinate.)
    #[inline]
    fn bounds(&self) -> Aabb {
        if !(self[0].is_finite() && self[1].is_finite() && self[2].is_finite()) {
            return INVALID_BOUNDS;
        }
        Aabb::new(
            self[0].min(self[1]).min(self[2]),
            self[0].max(self[1]).max(self[2]),
        )
    }
}

/// An indexed triangle mesh borrowed from the caller: triangle `i` has vertices
/// `positions[triangles[i][k]]`.
///
/// A triangle with a vertex index out of range, or a non-finite vertex, is an invalid
/// primitive (never a panic): the builder rejects or excludes it and
/// [`TriangleMesh::triangle`] returns `None` for it.
#[derive(Clone, Copy, Debug)]
pub struct TriangleMesh<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Triangles as indices into `positions`.
    pub triangles: &'a [[u32; 3]],
}

impl<'a> TriangleMesh<'a> {
    /// A mesh over the given slices.
    #[inline]
    #[must_use]
    pub const fn new(positions: &'a [Vec3], triangles: &'a [[u32; 3]]) -> Self {
        Self {
            positions,
            triangles,
        }
    }

    /// The vertices of triangle `index`; `None` when `index` or one of its vertex indices is
    /// out of range.
    #[inline]
    #[must_use]
    pub fn triangle(&self, index: usize) -> Option<[Vec3; 3]> {
        let [a, b, c] = *self.triangles.get(index)?;
        Some([
            *self.positions.get(a as usize)?,
            *self.positions.get(b as usize)?,
            *self.positions.get(c as usize)?,
        ])
    }

    /// Number of triangles.
    #[inline]
    #[must_use]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// `true` for no triangles.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

impl PrimitiveSource for TriangleMesh<'_> {
    #[inline]
    fn primitive_count(&self) -> usize {
        self.triangles.len()
    }

    #[inline(always)]
    fn primitive_bounds(&self, index: usize) -> Aabb {
        self.triangle(index)
            .map_or(INVALID_BOUNDS, |v| Primitive::bounds(&v))
    }
}

/// `true` when `b` can go into a tree: finite and non-empty.
#[inline]
pub(crate) fn is_usable(b: &Aabb) -> bool {
    b.is_finite() && b.is_valid()
}
