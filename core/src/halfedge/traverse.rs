//! Allocation-free traversal iterators.
//!
//! Every iterator is bounded by the number of halfedge slots, so even a corrupt mesh cannot
//! make it loop forever. Iterators on a dead or isolated element are empty.

use super::handles::{EdgeId, FaceId, HalfedgeId, NONE, VertexId};
use super::mesh::Mesh;
use super::storage::MeshStorage;

/// Outgoing halfedges of a vertex in counter-clockwise order, starting at the vertex's
/// stored halfedge (for a boundary vertex: its outgoing boundary halfedge, so the faces
/// then follow in counter-clockwise order from one side of the boundary gap to the other).
#[derive(Clone, Debug)]
pub struct Outgoing<'m, S: MeshStorage> {
    mesh: &'m Mesh<S>,
    start: u32,
    cur: u32,
    left: usize,
}

impl<S: MeshStorage> Iterator for Outgoing<'_, S> {
    type Item = HalfedgeId;
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.cur == NONE || self.left == 0 {
            return None;
        }
        let h = self.cur;
        self.left -= 1;
        let n = self.mesh.rot_ccw(h);
        self.cur = if n == self.start { NONE } else { n };
        Some(HalfedgeId(h))
    }
}

/// The three halfedges of a face, starting at its stored halfedge.
#[derive(Clone, Debug)]
pub struct FaceHalfedges<'m, S: MeshStorage> {
    mesh: &'m Mesh<S>,
    cur: u32,
    left: u8,
}

impl<S: MeshStorage> Iterator for FaceHalfedges<'_, S> {
    type Item = HalfedgeId;
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let h = self.cur;
        self.cur = self.mesh.next_raw(h);
        Some(HalfedgeId(h))
    }
}

impl<S: MeshStorage> Mesh<S> {
    /// Live vertices in slot order.
    pub fn vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.s.vertices().len() as u32)
            .filter(|&v| self.v_live(v))
            .map(VertexId)
    }
    /// Live edges in slot order.
    pub fn edges(&self) -> impl Iterator<Item = EdgeId> + '_ {
        (0..self.s.edges().len() as u32)
            .filter(|&e| self.e_live(e))
            .map(EdgeId)
    }
    /// Live faces in slot order.
    pub fn faces(&self) -> impl Iterator<Item = FaceId> + '_ {
        (0..self.s.faces().len() as u32)
            .filter(|&f| self.f_live(f))
            .map(FaceId)
    }
    /// Live halfedges in slot order.
    pub fn halfedges(&self) -> impl Iterator<Item = HalfedgeId> + '_ {
        (0..self.s.edges().len() as u32 * 2)
            .filter(|&h| self.h_live(h))
            .map(HalfedgeId)
    }

    /// Outgoing halfedges of `v`, counter-clockwise (see [`Outgoing`]).
    #[must_use]
    pub fn outgoing_halfedges(&self, v: VertexId) -> Outgoing<'_, S> {
        let start = if self.v_live(v.0) {
            self.out_raw(v.0)
        } else {
            NONE
        };
        Outgoing {
            mesh: self,
            start,
            cur: start,
            left: self.walk_bound(),
        }
    }
    /// Neighbouring vertices of `v` (heads of its outgoing halfedges), counter-clockwise.
    pub fn vertex_neighbors(&self, v: VertexId) -> impl Iterator<Item = VertexId> + '_ {
        self.outgoing_halfedges(v)
            .map(|h| VertexId(self.head_raw(h.0)))
    }
    /// Faces around `v`, counter-clockwise (boundary gaps skipped).
    pub fn vertex_faces(&self, v: VertexId) -> impl Iterator<Item = FaceId> + '_ {
        self.outgoing_halfedges(v).filter_map(|h| self.face(h))
    }
    /// Edges incident to `v`, counter-clockwise.
    pub fn vertex_edges(&self, v: VertexId) -> impl Iterator<Item = EdgeId> + '_ {
        self.outgoing_halfedges(v).map(|h| h.edge())
    }
    /// The ring of edges opposite `v` (one per incident face, the face's edge not touching
    /// `v`), counter-clockwise. For an interior vertex it starts at
    /// `edge(next(vertex_halfedge(v)))`; for a boundary vertex at the opposite edge of the
    /// first face after the boundary gap.
    pub fn opposite_edges(&self, v: VertexId) -> impl Iterator<Item = EdgeId> + '_ {
        self.outgoing_halfedges(v)
            .filter(|h| self.face_raw(h.0) != NONE)
            .map(|h| EdgeId(self.next_raw(h.0) >> 1))
    }
    /// Number of edges incident to `v` (0 for isolated or dead vertices).
    #[must_use]
    pub fn valence(&self, v: VertexId) -> usize {
        self.outgoing_halfedges(v).count()
    }

    /// The three halfedges of `f` (empty for a dead face).
    #[must_use]
    pub fn face_halfedges(&self, f: FaceId) -> FaceHalfedges<'_, S> {
        let live = self.f_live(f.0);
        FaceHalfedges {
            mesh: self,
            cur: self.fh(f.0),
            left: if live { 3 } else { 0 },
        }
    }
    /// Vertices of `f` in counter-clockwise order (as [`Mesh::face_vertices`]).
    pub fn face_vertex_iter(&self, f: FaceId) -> impl Iterator<Item = VertexId> + '_ {
        self.face_halfedges(f).map(|h| VertexId(self.tail_raw(h.0)))
    }
    /// Edges of `f`, counter-clockwise from its stored halfedge.
    pub fn face_edges(&self, f: FaceId) -> impl Iterator<Item = EdgeId> + '_ {
        self.face_halfedges(f).map(|h| h.edge())
    }
    /// Faces sharing an edge with `f` (boundary sides skipped).
    pub fn face_neighbors(&self, f: FaceId) -> impl Iterator<Item = FaceId> + '_ {
        self.face_halfedges(f).filter_map(|h| self.face(h.twin()))
    }

    /// The halfedge from `a` to `b`, if the edge exists.
    #[must_use]
    pub fn find_halfedge(&self, a: VertexId, b: VertexId) -> Option<HalfedgeId> {
        self.outgoing_halfedges(a)
            .find(|h| self.head_raw(h.0) == b.0)
    }

    /// Halfedges of the boundary loop (or face) containing `h`, following `next`.
    pub fn loop_halfedges(&self, h: HalfedgeId) -> impl Iterator<Item = HalfedgeId> + '_ {
        let start = if self.h_live(h.0) { h.0 } else { NONE };
        let mut cur = start;
        let mut left = self.walk_bound();
        core::iter::from_fn(move || {
            if cur == NONE || left == 0 {
                return None;
            }
            left -= 1;
            let out = cur;
            let n = self.next_raw(cur);
            cur = if n == start { NONE } else { n };
            Some(HalfedgeId(out))
        })
    }

    /// One representative halfedge (the lowest-numbered) per boundary loop.
    /// Cost O(Σ loop length²) over boundary loops.
    pub fn boundary_loops(&self) -> impl Iterator<Item = HalfedgeId> + '_ {
        self.halfedges().filter(move |&h| {
            self.face_raw(h.0) == NONE && self.loop_halfedges(h).all(|g| g.0 >= h.0)
        })
    }
}
