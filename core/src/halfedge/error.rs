//! Typed errors of the half-edge module. Every refusal names the rule and, where there is
//! one, the offending element. A refused operation never changes the mesh.

use core::fmt;

use super::handles::{EdgeId, FaceId, HalfedgeId, VertexId};

/// An element kind, for capacity and free-list errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementKind {
    /// Vertices.
    Vertex,
    /// Edges (halfedge pairs).
    Edge,
    /// Faces.
    Face,
}

/// An operation needs more slots of `kind` than the storage has free.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapacityError {
    /// The kind that ran out.
    pub kind: ElementKind,
    /// Slots the operation needs.
    pub needed: usize,
    /// Slots available (free-list entries plus unused capacity).
    pub available: usize,
}

/// Why [`super::Mesh::build`] rejected a triangle list. On any error the mesh is left
/// empty (and valid).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildError {
    /// More vertices, edges or faces than the storage holds.
    Capacity(CapacityError),
    /// The scratch slice is shorter than [`super::build_scratch_len`].
    ScratchTooSmall {
        /// Required length in `u32`s.
        needed: usize,
        /// Length provided.
        provided: usize,
    },
    /// A position has a NaN or infinite coordinate.
    NonFinitePosition {
        /// The vertex (its index in the input).
        vertex: VertexId,
    },
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
    },
    /// The directed edge `a → b` is used by two triangles (neighbours disagree on the
    /// orientation).
    InconsistentOrientation {
        /// Tail of the repeated directed edge.
        a: VertexId,
        /// Head of the repeated directed edge.
        b: VertexId,
    },
    /// The triangles around this vertex form more than one fan (a bowtie / pinch vertex).
    NonManifoldVertex {
        /// The vertex.
        vertex: VertexId,
    },
}

/// Which invariant [`super::Mesh::validate`] found broken, and where.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
pub enum SubdivideError {
    /// The source has tombstoned slots; call [`super::Mesh::compact`] first.
    NotCompact,
    /// The output mesh is too small.
    Capacity(CapacityError),
    /// A subdivided position would not be finite (coordinates near `f32::MAX` overflow the
    /// weighted sums).
    NonFinitePosition,
    /// The two faces on this edge have the same three vertices (two triangles glued along all
    /// their edges): their middle triangles would share all three edges (duplicate edges).
    CoincidentFaces(super::EdgeId),
}

/// Why [`super::Mesh::export`] failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
pub enum PositionError {
    /// The vertex is dead or out of range.
    Dead,
    /// The position is not finite.
    NonFinite,
}

macro_rules! display_via_debug {
    ($($t:ty => $what:literal),* $(,)?) => {$(
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($what, ": {:?}"), self)
            }
        }
        impl core::error::Error for $t {}
    )*};
}

display_via_debug!(
    CapacityError => "half-edge mesh capacity exceeded",
    BuildError => "cannot build half-edge mesh",
    InvariantError => "half-edge invariant broken",
    FlipError => "edge flip refused",
    SplitError => "edge split refused",
    CollapseError => "edge collapse refused",
    SubdivideError => "Loop subdivision refused",
    ExportError => "half-edge export failed",
    DiffuseError => "diffusion refused",
    PositionError => "position refused",
);
