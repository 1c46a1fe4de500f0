//! Element records and the storage that holds them.
//!
//! # Memory layout (bytes per element, asserted in the tests)
//!
//! | element  | record                                   | bytes |
//! |----------|------------------------------------------|------:|
//! | vertex   | position `Vec3` (12) + outgoing halfedge | 16    |
//! | halfedge | `next`, `prev`, `head`, `face` (u32 each)| 16    |
//! | edge     | its two halfedges, nothing else          | 32    |
//! | face     | one halfedge                             | 4     |
//!
//! Twins and edges are implicit (halfedges `2e`, `2e + 1` form edge `e`), so an edge costs
//! exactly its two halfedges. A closed triangle mesh (E ≈ 3V, F ≈ 2V) costs about
//! 16 + 3·32 + 2·4 = 120 B per vertex.
//!
//! Liveness is encoded in the records themselves, with no extra flag storage:
//! * a dead vertex or face stores `DEAD_BIT | next_free` in its halfedge field (a live one
//!   stores a halfedge index `< DEAD_BIT`, or for an isolated vertex the none sentinel);
//! * a dead edge stores the none sentinel in both halfedges' `head`, and the next free edge
//!   in its first halfedge's `next` (CGAL-style intrusive free lists).
//!
//! # Storage choices
//! * [`InlineStorage`]: const-generic `heapless::Vec`s inside the mesh value. Good for small
//!   meshes and `static`s; a large one placed on the stack overflows it (a 2 MiB test thread
//!   holds about 17 000 vertices' worth), and `Box::new(..)` may build it on the stack first.
//! * [`SliceStorage`]: caller-provided `&mut [Record]` slices, e.g. `vec![VertexRec::EMPTY; n]`
//!   in std code or `static` buffers on a device. Nothing large ever lives on the stack; this
//!   is the path for big meshes such as the bunny.

use glam::Vec3;

use super::handles::NONE;

/// High bit of a vertex or face halfedge field: set on dead (free-list) slots.
pub(crate) const DEAD_BIT: u32 = 1 << 31;
/// Free-list terminator stored (with [`DEAD_BIT`]) in the last dead vertex or face slot.
pub(crate) const FREE_END: u32 = 0x7FFF_FFFE;
/// Largest number of vertices, edges or faces any mesh can hold (2³⁰ − 1), whatever the
/// storage: halfedge indices must stay below 2³¹ (the dead-slot marker bit) and distinct from
/// the sentinels.
pub const MAX_ELEMENTS: usize = (1 << 30) - 1;

/// A vertex record: position and one outgoing halfedge. 16 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexRec {
    pub(crate) pos: Vec3,
    pub(crate) out: u32,
}

impl VertexRec {
    /// An empty (dead) record, for initialising caller buffers.
    pub const EMPTY: Self = Self {
        pos: Vec3::ZERO,
        out: DEAD_BIT | FREE_END,
    };
}

impl Default for VertexRec {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// A halfedge record: `next`, `prev`, `head` (the vertex it points to) and `face`. 16 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HalfedgeRec {
    pub(crate) next: u32,
    pub(crate) prev: u32,
    pub(crate) head: u32,
    pub(crate) face: u32,
}

impl HalfedgeRec {
    /// A dead record (also what internal reads of an out-of-range slot return).
    pub(crate) const DEAD: Self = Self {
        next: NONE,
        prev: NONE,
        head: NONE,
        face: NONE,
    };
}

/// An edge record: its two halfedges (`2e`, `2e + 1`). 32 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeRec {
    pub(crate) h: [HalfedgeRec; 2],
}

impl EdgeRec {
    /// An empty (dead) record, for initialising caller buffers.
    pub const EMPTY: Self = Self {
        h: [HalfedgeRec::DEAD; 2],
    };
}

impl Default for EdgeRec {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// A face record: one of its halfedges. 4 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceRec {
    pub(crate) h: u32,
}

impl FaceRec {
    /// An empty (dead) record, for initialising caller buffers.
    pub const EMPTY: Self = Self {
        h: DEAD_BIT | FREE_END,
    };
}

impl Default for FaceRec {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Element counts (live counts, capacities or requirements, depending on context).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Vertices.
    pub vertices: usize,
    /// Edges (each is two halfedges).
    pub edges: usize,
    /// Faces (triangles).
    pub faces: usize,
}

impl Counts {
    /// Halfedges: twice the edges (saturating).
    #[must_use]
    pub const fn halfedges(&self) -> usize {
        self.edges.saturating_mul(2)
    }

    /// The counts after one level of Loop subdivision of a triangle mesh with these counts:
    /// V' = V + E, E' = 2E + 3F, F' = 4F (saturating). Exact, boundary or not.
    #[must_use]
    pub const fn after_loop(&self) -> Counts {
        Counts {
            vertices: self.vertices.saturating_add(self.edges),
            edges: self
                .edges
                .saturating_mul(2)
                .saturating_add(self.faces.saturating_mul(3)),
            faces: self.faces.saturating_mul(4),
        }
    }

    /// `true` when every count is ≤ the matching count of `capacity`.
    #[must_use]
    pub const fn fits_in(&self, capacity: &Counts) -> bool {
        self.vertices <= capacity.vertices
            && self.edges <= capacity.edges
            && self.faces <= capacity.faces
    }
}

/// Backing storage of a [`super::Mesh`]: three growable-to-capacity arrays of records.
///
/// Sealed: implemented by [`InlineStorage`] and [`SliceStorage`] only. The slices returned
/// cover the used prefix (live and dead slots, up to the high-water mark).
pub trait MeshStorage: crate::sealed::Sealed {
    /// Used vertex slots.
    fn vertices(&self) -> &[VertexRec];
    /// Used vertex slots, mutable.
    fn vertices_mut(&mut self) -> &mut [VertexRec];
    /// Used edge slots.
    fn edges(&self) -> &[EdgeRec];
    /// Used edge slots, mutable.
    fn edges_mut(&mut self) -> &mut [EdgeRec];
    /// Used face slots.
    fn faces(&self) -> &[FaceRec];
    /// Used face slots, mutable.
    fn faces_mut(&mut self) -> &mut [FaceRec];
    /// Total slots of each kind.
    fn capacity(&self) -> Counts;
    /// Appends a vertex slot; `false` (and no change) when full.
    fn push_vertex(&mut self, r: VertexRec) -> bool;
    /// Appends an edge slot; `false` (and no change) when full.
    fn push_edge(&mut self, r: EdgeRec) -> bool;
    /// Appends a face slot; `false` (and no change) when full.
    fn push_face(&mut self, r: FaceRec) -> bool;
    /// Shrinks the used prefixes to at most these lengths.
    fn truncate(&mut self, to: Counts);
}

/// Const-generic storage held inside the mesh value (`V` vertices, `E` edges, `F` faces),
/// backed by `heapless::Vec`. Size ≈ 16·V + 32·E + 4·F bytes plus three lengths.
#[derive(Clone, Debug)]
pub struct InlineStorage<const V: usize, const E: usize, const F: usize> {
    v: heapless::Vec<VertexRec, V>,
    e: heapless::Vec<EdgeRec, E>,
    f: heapless::Vec<FaceRec, F>,
}

impl<const V: usize, const E: usize, const F: usize> InlineStorage<V, E, F> {
    /// Empty storage (`const`, so it can initialise a `static`).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            v: heapless::Vec::new(),
            e: heapless::Vec::new(),
            f: heapless::Vec::new(),
        }
    }
}

impl<const V: usize, const E: usize, const F: usize> Default for InlineStorage<V, E, F> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const V: usize, const E: usize, const F: usize> crate::sealed::Sealed
    for InlineStorage<V, E, F>
{
}

impl<const V: usize, const E: usize, const F: usize> MeshStorage for InlineStorage<V, E, F> {
    fn vertices(&self) -> &[VertexRec] {
        &self.v
    }
    fn vertices_mut(&mut self) -> &mut [VertexRec] {
        &mut self.v
    }
    fn edges(&self) -> &[EdgeRec] {
        &self.e
    }
    fn edges_mut(&mut self) -> &mut [EdgeRec] {
        &mut self.e
    }
    fn faces(&self) -> &[FaceRec] {
        &self.f
    }
    fn faces_mut(&mut self) -> &mut [FaceRec] {
        &mut self.f
    }
    fn capacity(&self) -> Counts {
        Counts {
            vertices: V,
            edges: E,
            faces: F,
        }
    }
    fn push_vertex(&mut self, r: VertexRec) -> bool {
        self.v.push(r).is_ok()
    }
    fn push_edge(&mut self, r: EdgeRec) -> bool {
        self.e.push(r).is_ok()
    }
    fn push_face(&mut self, r: FaceRec) -> bool {
        self.f.push(r).is_ok()
    }
    fn truncate(&mut self, to: Counts) {
        self.v.truncate(to.vertices);
        self.e.truncate(to.edges);
        self.f.truncate(to.faces);
    }
}

/// Storage in caller-provided slices; the slices' lengths are the capacities. Their initial
/// contents are ignored (every slot starts unused).
#[derive(Debug)]
pub struct SliceStorage<'a> {
    v: &'a mut [VertexRec],
    nv: usize,
    e: &'a mut [EdgeRec],
    ne: usize,
    f: &'a mut [FaceRec],
    nf: usize,
}

impl<'a> SliceStorage<'a> {
    /// Storage over the given buffers, initially empty.
    pub fn new(
        vertices: &'a mut [VertexRec],
        edges: &'a mut [EdgeRec],
        faces: &'a mut [FaceRec],
    ) -> Self {
        Self {
            v: vertices,
            nv: 0,
            e: edges,
            ne: 0,
            f: faces,
            nf: 0,
        }
    }
}

impl crate::sealed::Sealed for SliceStorage<'_> {}

fn push_into<T>(buf: &mut [T], len: &mut usize, r: T) -> bool {
    match buf.get_mut(*len) {
        Some(slot) => {
            *slot = r;
            *len += 1;
            true
        }
        None => false,
    }
}

impl MeshStorage for SliceStorage<'_> {
    fn vertices(&self) -> &[VertexRec] {
        self.v.get(..self.nv).unwrap_or(&[])
    }
    fn vertices_mut(&mut self) -> &mut [VertexRec] {
        self.v.get_mut(..self.nv).unwrap_or(&mut [])
    }
    fn edges(&self) -> &[EdgeRec] {
        self.e.get(..self.ne).unwrap_or(&[])
    }
    fn edges_mut(&mut self) -> &mut [EdgeRec] {
        self.e.get_mut(..self.ne).unwrap_or(&mut [])
    }
    fn faces(&self) -> &[FaceRec] {
        self.f.get(..self.nf).unwrap_or(&[])
    }
    fn faces_mut(&mut self) -> &mut [FaceRec] {
        self.f.get_mut(..self.nf).unwrap_or(&mut [])
    }
    fn capacity(&self) -> Counts {
        Counts {
            vertices: self.v.len(),
            edges: self.e.len(),
            faces: self.f.len(),
        }
    }
    fn push_vertex(&mut self, r: VertexRec) -> bool {
        push_into(self.v, &mut self.nv, r)
    }
    fn push_edge(&mut self, r: EdgeRec) -> bool {
        push_into(self.e, &mut self.ne, r)
    }
    fn push_face(&mut self, r: FaceRec) -> bool {
        push_into(self.f, &mut self.nf, r)
    }
    fn truncate(&mut self, to: Counts) {
        self.nv = self.nv.min(to.vertices);
        self.ne = self.ne.min(to.edges);
        self.nf = self.nf.min(to.faces);
    }
}
