//! Typed errors of the core. Every fallible constructor returns one of these; nothing panics.

use core::fmt;

/// Why a ray was rejected by [`crate::Ray::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RayError {
    /// An origin component is NaN or infinite.
    NonFiniteOrigin,
    /// A direction component is NaN or infinite.
    NonFiniteDirection,
    /// The direction is `(0, 0, 0)` (either sign of zero).
    ZeroDirection,
    /// `t_min` or `t_max` is NaN, `t_min` is `+∞`, or `t_min > t_max`.
    BadInterval,
}

impl fmt::Display for RayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFiniteOrigin => "ray origin is not finite",
            Self::NonFiniteDirection => "ray direction is not finite",
            Self::ZeroDirection => "ray direction is zero",
            Self::BadInterval => "ray interval is NaN or empty (t_min > t_max)",
        })
    }
}

impl core::error::Error for RayError {}

/// Why a primitive could not be constructed from its data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum GeometryError {
    /// A coordinate or parameter is NaN or infinite.
    NonFinite,
    /// The primitive has no area or volume (zero radius, zero normal, collinear vertices…).
    Degenerate,
    /// A polygon's vertices do not lie in one plane within [`crate::tolerance::PLANARITY_REL`].
    NonPlanar,
    /// A polygon has fewer than three vertices or more than the fixed capacity.
    VertexCount,
    /// A transform matrix is singular (or not invertible within `f32`).
    SingularTransform,
}

impl fmt::Display for GeometryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite coordinate",
            Self::Degenerate => "degenerate primitive (zero area or volume)",
            Self::NonPlanar => "polygon is not planar",
            Self::VertexCount => "polygon vertex count out of range",
            Self::SingularTransform => "singular transform",
        })
    }
}

impl core::error::Error for GeometryError {}

/// A half-edge mesh element kind, for capacity and free-list errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementKind {
    /// Vertices.
    Vertex,
    /// Edges (halfedge pairs).
    Edge,
    /// Faces.
    Face,
}

impl fmt::Display for ElementKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Vertex => "vertex",
            Self::Edge => "edge",
            Self::Face => "face",
        })
    }
}

/// Caller-provided storage an operation can run out of, named in [`CapacityError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Storage {
    /// A BVH's nodes ([`crate::bvh::node_capacity`]).
    BvhNodes,
    /// A BVH's primitive indices (one per primitive).
    BvhIndices,
    /// A BVH builder's scratch ([`crate::bvh::scratch_capacity`]).
    BvhScratch,
    /// A wide BVH's triangle groups ([`crate::bvh::wide::group_capacity`]).
    WideTriangleGroups,
    /// The bitset of [`crate::bvh::Bvh::from_parts`] ([`crate::bvh::load_scratch_len`] words).
    BvhLoadBitset,
    /// A kd-tree's nodes.
    KdNodes,
    /// A kd-tree's primitive references ([`crate::kdtree::min_reference_capacity`]).
    KdReferences,
    /// A kd-tree builder's scratch.
    KdScratch,
    /// A grid's cell offsets ([`crate::grid::GridPlan::required_offsets`]).
    GridOffsets,
    /// A grid's cell references ([`crate::grid::GridPlan::required_references`]).
    GridReferences,
    /// A half-edge mesh's vertex, edge or face slots.
    MeshSlots(ElementKind),
    /// The scratch of [`crate::halfedge::Mesh::build`] ([`crate::halfedge::build_scratch_len`]).
    MeshBuildScratch,
    /// The output of [`crate::halfedge::Mesh::vertex_normals`] (one per vertex slot in use).
    VertexNormals,
}

impl fmt::Display for Storage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::BvhNodes => "BVH node storage",
            Self::BvhIndices => "BVH index storage",
            Self::BvhScratch => "BVH build scratch",
            Self::WideTriangleGroups => "wide BVH triangle group storage",
            Self::BvhLoadBitset => "BVH load bitset",
            Self::KdNodes => "kd-tree node storage",
            Self::KdReferences => "kd-tree reference storage",
            Self::KdScratch => "kd-tree build scratch",
            Self::GridOffsets => "grid offset storage",
            Self::GridReferences => "grid reference storage",
            Self::MeshSlots(ElementKind::Vertex) => "half-edge mesh vertex storage",
            Self::MeshSlots(ElementKind::Edge) => "half-edge mesh edge storage",
            Self::MeshSlots(ElementKind::Face) => "half-edge mesh face storage",
            Self::MeshBuildScratch => "half-edge build scratch",
            Self::VertexNormals => "vertex normal output",
        })
    }
}

/// Caller-provided storage is too small: every builder's and every fixed-capacity
/// operation's one capacity error. Returned before anything is written unless the operation
/// says otherwise. Counts are in the storage's own units (nodes, indices, slots, words…).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapacityError {
    /// Which storage.
    pub storage: Storage,
    /// Entries the operation needs (at least).
    pub needed: usize,
    /// Entries the storage has (for a half-edge mesh: free-list entries plus unused capacity).
    pub available: usize,
}

impl CapacityError {
    /// `Err` when `available < needed`.
    pub(crate) const fn check(
        storage: Storage,
        needed: usize,
        available: usize,
    ) -> Result<(), Self> {
        if available < needed {
            Err(Self {
                storage,
                needed,
                available,
            })
        } else {
            Ok(())
        }
    }
}

impl fmt::Display for CapacityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} too small: {} needed, {} available",
            self.storage, self.needed, self.available
        )
    }
}

impl core::error::Error for CapacityError {}

/// The kind of input element a [`NonFiniteError`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum InputElement {
    /// A primitive of a [`crate::mesh::PrimitiveSource`]: its bounds are NaN, infinite or empty
    /// (a non-finite vertex or an out-of-range vertex index).
    Primitive,
    /// A triangle of a mesh: a non-finite vertex or an out-of-range vertex index.
    Triangle,
    /// A point of a point set (for a mesh, the `3·triangle + corner`-th referenced corner).
    Point,
    /// A vertex position.
    Vertex,
}

/// An input element is NaN or infinite: every builder's one non-finite-input error, naming
/// the first offending element by its index in the input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NonFiniteError {
    /// What kind of element.
    pub element: InputElement,
    /// Its index in the input.
    pub index: usize,
}

impl NonFiniteError {
    /// Element `index` of kind `element`.
    #[must_use]
    pub const fn new(element: InputElement, index: usize) -> Self {
        Self { element, index }
    }

    /// Primitive `index` of a source ([`InputElement::Primitive`]).
    #[must_use]
    pub const fn primitive(index: usize) -> Self {
        Self::new(InputElement::Primitive, index)
    }
}

impl fmt::Display for NonFiniteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = self.index;
        match self.element {
            InputElement::Primitive => write!(f, "primitive {i} has non-finite or empty bounds"),
            InputElement::Triangle => write!(
                f,
                "triangle {i} has a non-finite vertex or an out-of-range vertex index"
            ),
            InputElement::Point => write!(f, "point {i} has a NaN or infinite coordinate"),
            InputElement::Vertex => write!(f, "vertex {i} has a NaN or infinite coordinate"),
        }
    }
}

impl core::error::Error for NonFiniteError {}

/// Writes the message of a too-much-input error:
/// `"too many {items} for {structure}: {count} (max {max})"` (`items` plural, e.g.
/// `"primitives"`; `structure` with its article, e.g. `"a BVH"`).
pub(crate) fn write_too_many(
    f: &mut fmt::Formatter<'_>,
    items: &str,
    structure: &str,
    count: usize,
    max: usize,
) -> fmt::Result {
    write!(f, "too many {items} for {structure}: {count} (max {max})")
}

#[cfg(test)]
mod tests {
    use crate::bvh::BvhError;
    use crate::grid::GridError;
    use crate::kdtree::KdTreeError;
    use std::string::ToString;

    /// The shared writers give each structure's messages word for word.
    #[test]
    fn storage_and_size_messages() {
        let cases = [
            (
                BvhError::Capacity(crate::error::CapacityError {
                    storage: crate::error::Storage::BvhIndices,
                    needed: 10,
                    available: 9,
                })
                .to_string(),
                "BVH index storage too small: 10 needed, 9 available",
            ),
            (
                BvhError::NonFinite(crate::error::NonFiniteError {
                    element: crate::error::InputElement::Primitive,
                    index: 2,
                })
                .to_string(),
                "primitive 2 has non-finite or empty bounds",
            ),
            (
                KdTreeError::TooManyPrimitives { count: 1 << 30 }.to_string(),
                "too many primitives for a kd-tree: 1073741824 (max 1073741823)",
            ),
            (
                GridError::Capacity(crate::error::CapacityError {
                    storage: crate::error::Storage::GridOffsets,
                    needed: 3,
                    available: 0,
                })
                .to_string(),
                "grid offset storage too small: 3 needed, 0 available",
            ),
            (
                GridError::TooManyTriangles { count: 5 }.to_string(),
                "too many triangles for a grid: 5 (max 4294967295)",
            ),
        ];
        for (got, want) in cases {
            assert_eq!(got, want);
        }
    }
}
