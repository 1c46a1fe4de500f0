//! Typed errors of the half-edge module. Every refusal names the rule and, where there is
//! one, the offending element. A refused operation never changes the mesh.

use core::fmt;

use super::handles::{EdgeId, FaceId, HalfedgeId, VertexId};
use crate::error::NonFiniteError;
pub use crate::error::{CapacityError, ElementKind};

/// Why [`super::Mesh::build`] rejected a triangle list. On any error the mesh is left
/// empty (and valid). Every variant but [`BuildError::Capacity`] names an offending input
/// element ([`BuildError::culprit`]), so a caller can point at where its input came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum BuildError {
    /// More vertices, edges or faces than the storage holds
    /// ([`crate::error::Storage::MeshSlots`]), or a scratch slice shorter than
    /// [`super::build_scratch_len`] ([`crate::error::Storage::MeshBuildScratch`]).
    Capacity(CapacityError),
    /// A position has a NaN or infinite coordinate
    /// ([`crate::error::InputElement::Vertex`], the index in the input).
    NonFinite(NonFiniteError),
    /// A triangle refers to a vertex index ≥ the number of positions.
    IndexOutOfRange {
        /// The triangle (its index in the input).
        face: FaceId,
        /// The bad index.
        index: u32,
    },
    /// A triangle uses the same vertex twice.
    RepeatedIndex {
        /// The triangle.
        face: FaceId,
        /// The repeated vertex.
        vertex: VertexId,
    },
    /// The undirected edge `a`–`b` is used by more than two triangles.
    NonManifoldEdge {
        /// Smaller endpoint.
        a: VertexId,
        /// Larger endpoint.
        b: VertexId,
        /// The triangle that made the edge's count exceed two: the third-lowest-numbered
        /// triangle using the edge (the third user in input order).
        face: FaceId,
    },
    /// The directed edge `a → b` is used by two triangles (neighbours disagree on the
    /// orientation).
    InconsistentOrientation {
        /// Tail of the repeated directed edge.
        a: VertexId,
        /// Head of the repeated directed edge.
        b: VertexId,
        /// The later of the two triangles running `a → b`.
        face: FaceId,
    },
    /// The triangles around this vertex form more than one fan (a bowtie / pinch vertex).
    NonManifoldVertex {
        /// The vertex.
        vertex: VertexId,
    },
}

/// The input element a [`BuildError`] is about: a position or a triangle, by its index in
/// the slices given to [`super::Mesh::build`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Culprit {
    /// A position.
    Vertex(VertexId),
    /// A triangle.
    Face(FaceId),
}

impl BuildError {
    /// The offending input element; `None` for [`BuildError::Capacity`] (the whole input).
    #[must_use]
    pub fn culprit(&self) -> Option<Culprit> {
        match *self {
            Self::Capacity(_) => None,
            Self::NonFinite(e) => Some(Culprit::Vertex(VertexId(e.index as u32))),
            Self::IndexOutOfRange { face, .. }
            | Self::RepeatedIndex { face, .. }
            | Self::NonManifoldEdge { face, .. }
            | Self::InconsistentOrientation { face, .. } => Some(Culprit::Face(face)),
            Self::NonManifoldVertex { vertex } => Some(Culprit::Vertex(vertex)),
        }
    }

    /// The error's sentence with vertices and triangles numbered from `first` instead of 0
    /// (an OBJ file numbers from 1). `Display` is `numbered_from(0)`.
    #[must_use]
    pub fn numbered_from(&self, first: u32) -> impl fmt::Display + '_ {
        Numbered(self, u64::from(first))
    }
}

/// [`BuildError::numbered_from`].
struct Numbered<'a>(&'a BuildError, u64);

impl fmt::Display for Numbered<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = |i: u32| u64::from(i) + self.1;
        match *self.0 {
            BuildError::Capacity(c) => write!(f, "cannot build half-edge mesh: {c}"),
            BuildError::NonFinite(e) => write!(
                f,
                "vertex {} has a NaN or infinite coordinate",
                (e.index as u64).saturating_add(self.1)
            ),
            BuildError::IndexOutOfRange { face, index } => write!(
                f,
                "triangle {} refers to vertex {}, which does not exist",
                n(face.0),
                n(index)
            ),
            BuildError::RepeatedIndex { face, vertex } => write!(
                f,
                "triangle {} uses vertex {} twice",
                n(face.0),
                n(vertex.0)
            ),
            BuildError::NonManifoldEdge { a, b, face } => write!(
                f,
                "non-manifold edge between vertices {} and {}: used by more than two triangles; the third is triangle {}",
                n(a.0),
                n(b.0),
                n(face.0)
            ),
            BuildError::InconsistentOrientation { a, b, face } => write!(
                f,
                "inconsistent orientation: triangle {} runs from vertex {} to vertex {} as an earlier triangle does (neighbours must traverse a shared edge in opposite directions; or a face is repeated)",
                n(face.0),
                n(a.0),
                n(b.0)
            ),
            BuildError::NonManifoldVertex { vertex } => write!(
                f,
                "non-manifold vertex {} is a pinch: its triangles form more than one fan (a bowtie vertex)",
                n(vertex.0)
            ),
        }
    }
}

/// Which invariant [`super::Mesh::validate`] found broken, and where.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum InvariantError {
    /// A free list is corrupt (cycle, live entry, or live + free ≠ used slots).
    FreeList(ElementKind),
    /// Exactly one halfedge of this edge is dead.
    HalfedgePair(EdgeId),
    /// A `next`, `prev`, `head` or `face` field is out of range or points at a dead element.
    DanglingLink(HalfedgeId),
    /// `prev(next(h)) ≠ h` or `next(prev(h)) ≠ h`.
    NextPrev(HalfedgeId),
    /// Head and tail of the halfedge coincide.
    SelfLoop(HalfedgeId),
    /// `head(h) ≠ tail(next(h))`.
    HeadTail(HalfedgeId),
    /// The face's halfedge is dead, out of range or has another face.
    FaceHalfedge(FaceId),
    /// The face is not a 3-cycle of halfedges all naming it.
    FaceCycle(FaceId),
    /// Neither halfedge of the edge has a face.
    IsolatedEdge(EdgeId),
    /// A boundary halfedge's `next` has a face (boundary loops must be closed).
    BoundaryCycle(HalfedgeId),
    /// The vertex's halfedge is dead, out of range or does not start at the vertex.
    VertexHalfedge(VertexId),
    /// The fan walk around the vertex does not close, leaves the vertex, or misses some of
    /// its outgoing halfedges.
    VertexFan(VertexId),
    /// A boundary vertex's stored halfedge is not a boundary halfedge.
    BoundaryVertexConvention(VertexId),
    /// The vertex has more than one outgoing boundary halfedge.
    NonManifoldVertex(VertexId),
    /// Two edges join the same pair of vertices (`a` is the vertex where it was found).
    DuplicateEdge(VertexId),
    /// A position is NaN or infinite.
    NonFinitePosition(VertexId),
}

/// Why [`super::Mesh::flip_edge`] refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FlipError {
    /// The edge is dead or out of range.
    Dead,
    /// The edge is on the boundary (one side has no face).
    Boundary,
    /// The two opposite ("wing") vertices are the same vertex.
    WingsCoincide,
    /// The wing vertices are already joined by an edge.
    DuplicateEdge,
    /// An endpoint would be left with fewer than three incident edges.
    DegreeTooLow(VertexId),
}

/// Why [`super::Mesh::split_edge`] refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SplitError {
    /// The edge is dead or out of range.
    Dead,
    /// The requested point is not finite.
    NonFinitePosition,
    /// Not enough free slots.
    Capacity(CapacityError),
    /// Both faces on the edge have the same opposite vertex (two triangles glued along all
    /// three edges): the two new edges would join the same pair of vertices.
    WingsCoincide,
}

/// Why [`super::Mesh::collapse_edge`] refused: the rule that failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CollapseError {
    /// The halfedge is dead or out of range.
    Dead,
    /// Link condition: this vertex is adjacent to both endpoints but is not a wing vertex.
    LinkCondition(VertexId),
    /// Both faces' opposite vertices are the same vertex.
    WingsCoincide,
    /// A face next to the edge has its two other edges on the boundary (an "ear").
    Ear(FaceId),
    /// The edge is interior but both endpoints are boundary vertices (would pinch).
    InteriorEdgeJoinsBoundaries,
    /// An interior wing vertex has valence 3 and would drop to 2 (e.g. a tetrahedron).
    WingValence(VertexId),
    /// Moving the surviving vertex would flip this face's normal over.
    FoldOver(FaceId),
    /// The target position is not finite.
    NonFinitePosition,
}

/// Why [`super::Mesh::subdivide_loop`] refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SubdivideError {
    /// The source has tombstoned slots; call [`super::Mesh::compact`] first.
    NotCompact,
    /// The output mesh is too small.
    Capacity(CapacityError),
    /// The two faces on this edge have the same three vertices (two triangles glued along all
    /// their edges): their middle triangles would share all three edges (duplicate edges).
    CoincidentFaces(super::EdgeId),
}

/// Why [`super::Mesh::export`] failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ExportError {
    /// An output buffer is too short.
    BufferTooSmall {
        /// Positions needed (vertex slots in use).
        positions: usize,
        /// Triangles needed (live faces).
        triangles: usize,
    },
}

/// Why a smoothing step refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum DiffuseError {
    /// The vertex is dead or out of range.
    Dead,
    /// The step size or a resulting position is not finite.
    NonFinite,
    /// The scratch slice is shorter than the number of vertex slots in use.
    ScratchTooSmall {
        /// Required length.
        needed: usize,
    },
}

/// Why [`super::Mesh::set_position`] refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum PositionError {
    /// The vertex is dead or out of range.
    Dead,
    /// The position is not finite.
    NonFinite,
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.numbered_from(0).fmt(f)
    }
}

impl fmt::Display for InvariantError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("half-edge invariant broken: ")?;
        match *self {
            Self::FreeList(k) => write!(f, "the {k} free list is corrupt"),
            Self::HalfedgePair(e) => write!(f, "exactly one halfedge of edge {} is dead", e.0),
            Self::DanglingLink(h) => {
                write!(f, "halfedge {} links to a dead or missing element", h.0)
            }
            Self::NextPrev(h) => write!(f, "next/prev of halfedge {} do not match", h.0),
            Self::SelfLoop(h) => write!(f, "halfedge {} starts and ends at the same vertex", h.0),
            Self::HeadTail(h) => write!(f, "halfedge {} does not end where its next starts", h.0),
            Self::FaceHalfedge(t) => write!(f, "face {} has a bad halfedge", t.0),
            Self::FaceCycle(t) => write!(f, "face {} is not a cycle of three halfedges", t.0),
            Self::IsolatedEdge(e) => write!(f, "edge {} has no face on either side", e.0),
            Self::BoundaryCycle(h) => {
                write!(f, "boundary loop through halfedge {} is not closed", h.0)
            }
            Self::VertexHalfedge(v) => write!(f, "vertex {} has a bad outgoing halfedge", v.0),
            Self::VertexFan(v) => write!(f, "the fan around vertex {} does not close", v.0),
            Self::BoundaryVertexConvention(v) => write!(
                f,
                "boundary vertex {} does not store its boundary halfedge",
                v.0
            ),
            Self::NonManifoldVertex(v) => {
                write!(
                    f,
                    "vertex {} has more than one outgoing boundary halfedge",
                    v.0
                )
            }
            Self::DuplicateEdge(v) => {
                write!(f, "two edges join the same vertices at vertex {}", v.0)
            }
            Self::NonFinitePosition(v) => {
                write!(f, "vertex {} has a NaN or infinite coordinate", v.0)
            }
        }
    }
}

impl fmt::Display for FlipError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("edge flip refused: ")?;
        match *self {
            Self::Dead => f.write_str("the edge does not exist"),
            Self::Boundary => f.write_str("the edge is on the boundary"),
            Self::WingsCoincide => f.write_str("its two opposite vertices are the same vertex"),
            Self::DuplicateEdge => {
                f.write_str("its opposite vertices are already joined by an edge")
            }
            Self::DegreeTooLow(v) => {
                write!(
                    f,
                    "vertex {} would be left with fewer than three edges",
                    v.0
                )
            }
        }
    }
}

impl fmt::Display for SplitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Dead => f.write_str("edge split refused: the edge does not exist"),
            Self::NonFinitePosition => f.write_str("edge split refused: the point is not finite"),
            Self::Capacity(c) => write!(f, "edge split refused: {c}"),
            Self::WingsCoincide => f.write_str(
                "edge split refused: both faces share their opposite vertex (the new edges would coincide)",
            ),
        }
    }
}

impl fmt::Display for CollapseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("edge collapse refused: ")?;
        match *self {
            Self::Dead => f.write_str("the halfedge does not exist"),
            Self::LinkCondition(v) => write!(
                f,
                "link condition: vertex {} is adjacent to both endpoints but is not a wing vertex",
                v.0
            ),
            Self::WingsCoincide => f.write_str("both faces have the same opposite vertex"),
            Self::Ear(t) => write!(f, "face {} has its two other edges on the boundary", t.0),
            Self::InteriorEdgeJoinsBoundaries => {
                f.write_str("the edge is interior but joins two boundary vertices (would pinch)")
            }
            Self::WingValence(v) => {
                write!(f, "interior wing vertex {} would drop to valence 2", v.0)
            }
            Self::FoldOver(t) => write!(f, "face {} would flip over", t.0),
            Self::NonFinitePosition => f.write_str("the target position is not finite"),
        }
    }
}

impl fmt::Display for SubdivideError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Loop subdivision refused: ")?;
        match *self {
            Self::NotCompact => f.write_str("the mesh has deleted slots (compact it first)"),
            Self::Capacity(c) => write!(f, "{c}"),
            Self::CoincidentFaces(e) => write!(
                f,
                "the two faces on edge {} have the same three vertices",
                e.0
            ),
        }
    }
}

impl fmt::Display for ExportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::BufferTooSmall {
                positions,
                triangles,
            } => write!(
                f,
                "half-edge export failed: buffers too small ({positions} positions and {triangles} triangles needed)"
            ),
        }
    }
}

impl fmt::Display for DiffuseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Dead => f.write_str("diffusion refused: the vertex does not exist"),
            Self::NonFinite => {
                f.write_str("diffusion refused: the step or a resulting position is not finite")
            }
            Self::ScratchTooSmall { needed } => write!(
                f,
                "diffusion refused: scratch shorter than the {needed} vertex slots in use"
            ),
        }
    }
}

impl fmt::Display for PositionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Dead => "position refused: the vertex does not exist",
            Self::NonFinite => "position refused: not finite",
        })
    }
}

impl core::error::Error for BuildError {}
impl core::error::Error for InvariantError {}
impl core::error::Error for FlipError {}
impl core::error::Error for SplitError {}
impl core::error::Error for CollapseError {}
impl core::error::Error for SubdivideError {}
impl core::error::Error for ExportError {}
impl core::error::Error for DiffuseError {}
impl core::error::Error for PositionError {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::{InputElement, Storage};
    use std::format;
    use std::string::String;
    use std::vec;
    use std::vec::Vec;

    /// Every message, as a user of the CLI sees it, is a sentence: it never falls back to
    /// the `Debug` form (braces, `Id(..)` wrappers or the variant's Rust name).
    #[test]
    fn messages_are_sentences_not_debug_forms() {
        let (v, e, h, t) = (VertexId(7), EdgeId(8), HalfedgeId(9), FaceId(10));
        let cap = CapacityError {
            storage: Storage::MeshSlots(ElementKind::Edge),
            needed: 12,
            available: 3,
        };
        let mut all: Vec<(String, String)> = Vec::new();
        let mut push = |debug: String, display: String| all.push((debug, display));
        for x in [
            BuildError::Capacity(cap),
            BuildError::Capacity(CapacityError {
                storage: Storage::MeshBuildScratch,
                needed: 5,
                available: 1,
            }),
            BuildError::NonFinite(NonFiniteError {
                element: InputElement::Vertex,
                index: 7,
            }),
            BuildError::IndexOutOfRange { face: t, index: 99 },
            BuildError::RepeatedIndex { face: t, vertex: v },
            BuildError::NonManifoldEdge {
                a: v,
                b: VertexId(3),
                face: t,
            },
            BuildError::InconsistentOrientation {
                a: v,
                b: VertexId(3),
                face: t,
            },
            BuildError::NonManifoldVertex { vertex: v },
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        for x in [
            InvariantError::FreeList(ElementKind::Face),
            InvariantError::HalfedgePair(e),
            InvariantError::DanglingLink(h),
            InvariantError::NextPrev(h),
            InvariantError::SelfLoop(h),
            InvariantError::HeadTail(h),
            InvariantError::FaceHalfedge(t),
            InvariantError::FaceCycle(t),
            InvariantError::IsolatedEdge(e),
            InvariantError::BoundaryCycle(h),
            InvariantError::VertexHalfedge(v),
            InvariantError::VertexFan(v),
            InvariantError::BoundaryVertexConvention(v),
            InvariantError::NonManifoldVertex(v),
            InvariantError::DuplicateEdge(v),
            InvariantError::NonFinitePosition(v),
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        for x in [
            FlipError::Dead,
            FlipError::Boundary,
            FlipError::WingsCoincide,
            FlipError::DuplicateEdge,
            FlipError::DegreeTooLow(v),
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        for x in [
            SplitError::Dead,
            SplitError::NonFinitePosition,
            SplitError::Capacity(cap),
            SplitError::WingsCoincide,
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        for x in [
            CollapseError::Dead,
            CollapseError::LinkCondition(v),
            CollapseError::WingsCoincide,
            CollapseError::Ear(t),
            CollapseError::InteriorEdgeJoinsBoundaries,
            CollapseError::WingValence(v),
            CollapseError::FoldOver(t),
            CollapseError::NonFinitePosition,
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        for x in [
            SubdivideError::NotCompact,
            SubdivideError::Capacity(cap),
            SubdivideError::CoincidentFaces(e),
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        let x = ExportError::BufferTooSmall {
            positions: 4,
            triangles: 2,
        };
        push(format!("{x:?}"), format!("{x}"));
        for x in [
            DiffuseError::Dead,
            DiffuseError::NonFinite,
            DiffuseError::ScratchTooSmall { needed: 6 },
        ] {
            push(format!("{x:?}"), format!("{x}"));
        }
        for x in [PositionError::Dead, PositionError::NonFinite] {
            push(format!("{x:?}"), format!("{x}"));
        }
        push(format!("{cap:?}"), format!("{cap}"));

        let mut seen = vec![];
        for (debug, display) in &all {
            let variant: String = debug
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric())
                .collect();
            assert!(!display.contains(['{', '}']), "{debug}: {display}");
            assert!(!display.contains("Id("), "{debug}: {display}");
            assert!(!display.contains(&*variant), "{debug}: {display}");
            assert!(
                !seen.contains(display),
                "two errors read the same: {display}"
            );
            seen.push(display.clone());
        }
        // The offending element is named by its number.
        assert!(format!("{}", FlipError::DegreeTooLow(v)).contains(" 7 "));
        assert!(format!("{cap}").contains("12") && format!("{cap}").contains('3'));
    }
}
