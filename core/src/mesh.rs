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

/// The array as its slice: the same primitives, the same bounds.
impl<P: Primitive, const N: usize> PrimitiveSource for [P; N] {
    #[inline]
    fn primitive_count(&self) -> usize {
        N
    }

    #[inline]
    fn primitive_bounds(&self, index: usize) -> Aabb {
        self.as_slice().primitive_bounds(index)
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
/// primitive (never a panic): the builder rejects or excludes it. [`TriangleMesh::triangle`]
/// returns `None` only for an index out of range: a triangle with a non-finite vertex comes
/// back as it is.
///
/// Two meshes are equal (`==`) when their positions and triangles are, element by element
/// (`f32` equality: a NaN position is unequal to itself), wherever the slices live.
#[derive(Clone, Copy, Debug, PartialEq)]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{BuildOptions, Bvh, BvhNode};

    /// An array of primitives is a source as its slice is: the same count, the same bounds
    /// (invalid past the end), and a BVH built over either has the same nodes and indices.
    #[test]
    fn an_array_of_primitives_is_its_slice() {
        let boxes: [Aabb; 5] =
            core::array::from_fn(|i| Aabb::new(Vec3::splat(i as f32), Vec3::splat(i as f32 + 0.5)));
        let slice: &[Aabb] = &boxes;
        assert_eq!(boxes.primitive_count(), slice.primitive_count());
        for i in 0..7 {
            let (a, s) = (boxes.primitive_bounds(i), slice.primitive_bounds(i));
            assert!(
                a == s || (i >= 5 && a.min.is_nan() && s.min.is_nan()),
                "{i}"
            );
        }
        let build = |source: &dyn Fn(&mut [BvhNode], &mut [u32]) -> u32| {
            let (mut nodes, mut indices) = ([BvhNode::EMPTY; 9], [0u32; 5]);
            let count = source(&mut nodes, &mut indices);
            (nodes, indices, count)
        };
        let options = BuildOptions::default();
        let by_array =
            build(&|n, i| Bvh::build(&boxes, n, i, &options).map_or(0, |b| b.node_count() as u32));
        let by_slice =
            build(&|n, i| Bvh::build(slice, n, i, &options).map_or(0, |b| b.node_count() as u32));
        assert!(by_array.2 > 0);
        assert_eq!(by_array, by_slice);
        let tris = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::NAN, Vec3::X, Vec3::Y],
        ];
        assert!(tris.primitive_bounds(0).is_finite());
        assert!(!tris.primitive_bounds(1).is_finite());
    }

    /// Meshes compare by content, wherever their slices live; a NaN position makes a mesh
    /// unequal to itself (`f32` equality).
    #[test]
    fn meshes_are_equal_by_content() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let triangles = [[0u32, 1, 2], [0, 1, 3]];
        let (p2, t2) = (positions, triangles);
        let a = TriangleMesh::new(&positions, &triangles);
        assert_eq!(a, TriangleMesh::new(&p2, &t2));
        assert_ne!(a, TriangleMesh::new(&positions, &triangles[..1]));
        assert_ne!(a, TriangleMesh::new(&positions, &[[0, 1, 2], [0, 2, 3]]));
        let moved = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::NEG_Z];
        assert_ne!(a, TriangleMesh::new(&moved, &triangles));
        let nan = [Vec3::NAN, Vec3::X, Vec3::Y, Vec3::Z];
        let b = TriangleMesh::new(&nan, &triangles);
        assert_ne!(b, b);
    }
}
