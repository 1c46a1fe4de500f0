//! The public navigation accessors: typed handles in, `Option`s out.

use glam::Vec3;

use crate::halfedge::error::PositionError;
use crate::halfedge::handles::{EdgeId, FaceId, HalfedgeId, NONE, VertexId};
use crate::halfedge::storage::MeshStorage;

use super::Mesh;

impl<S: MeshStorage> Mesh<S> {
    // ----- public navigation -----

    /// `true` if `v` is a live vertex of this mesh.
    #[must_use]
    pub fn contains_vertex(&self, v: VertexId) -> bool {
        self.v_live(v.0)
    }
    /// `true` if `e` is a live edge.
    #[must_use]
    pub fn contains_edge(&self, e: EdgeId) -> bool {
        self.e_live(e.0)
    }
    /// `true` if `h` is a live halfedge.
    #[must_use]
    pub fn contains_halfedge(&self, h: HalfedgeId) -> bool {
        self.h_live(h.0)
    }
    /// `true` if `f` is a live face.
    #[must_use]
    pub fn contains_face(&self, f: FaceId) -> bool {
        self.f_live(f.0)
    }

    /// Position of `v`; `None` for a dead or out-of-range vertex.
    #[must_use]
    pub fn position(&self, v: VertexId) -> Option<Vec3> {
        self.v_live(v.0).then(|| self.pos_raw(v.0))
    }

    /// Moves `v` to `p`. Refuses non-finite positions (the mesh stays unchanged).
    ///
    /// # Errors
    ///
    /// [`PositionError::Dead`] for a dead or out-of-range vertex, [`PositionError::NonFinite`]
    /// for a non-finite `p`; the mesh is unchanged.
    pub fn set_position(&mut self, v: VertexId, p: Vec3) -> Result<(), PositionError> {
        if !self.v_live(v.0) {
            return Err(PositionError::Dead);
        }
        if !p.is_finite() {
            return Err(PositionError::NonFinite);
        }
        self.set_pos(v.0, p);
        Ok(())
    }

    /// The stored outgoing halfedge of `v` (a boundary halfedge for a boundary vertex);
    /// `None` for an isolated or dead vertex.
    #[must_use]
    pub fn vertex_halfedge(&self, v: VertexId) -> Option<HalfedgeId> {
        let h = self.out_raw(v.0);
        (self.v_live(v.0) && h != NONE).then_some(HalfedgeId(h))
    }

    /// One halfedge of face `f` (the one from its first to its second vertex, see
    /// [`Mesh::face_vertices`]); `None` for a dead face.
    #[must_use]
    pub fn face_halfedge(&self, f: FaceId) -> Option<HalfedgeId> {
        self.f_live(f.0).then(|| HalfedgeId(self.fh(f.0)))
    }

    /// Next halfedge around the face (or boundary loop); `None` for a dead halfedge.
    #[must_use]
    pub fn next(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        self.h_live(h.0).then(|| HalfedgeId(self.next_raw(h.0)))
    }
    /// Previous halfedge around the face (or boundary loop).
    #[must_use]
    pub fn prev(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        self.h_live(h.0).then(|| HalfedgeId(self.prev_raw(h.0)))
    }
    /// Twin halfedge, if `h` is live (the arithmetic form is [`HalfedgeId::twin`]).
    #[must_use]
    pub fn twin(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        self.h_live(h.0).then(|| h.twin())
    }
    /// The vertex `h` points to.
    #[must_use]
    pub fn head(&self, h: HalfedgeId) -> Option<VertexId> {
        self.h_live(h.0).then(|| VertexId(self.head_raw(h.0)))
    }
    /// The vertex `h` starts from.
    #[must_use]
    pub fn tail(&self, h: HalfedgeId) -> Option<VertexId> {
        self.h_live(h.0).then(|| VertexId(self.tail_raw(h.0)))
    }
    /// The face on the left of `h`; `None` for a boundary or dead halfedge.
    #[must_use]
    pub fn face(&self, h: HalfedgeId) -> Option<FaceId> {
        let f = self.face_raw(h.0);
        (self.h_live(h.0) && f != NONE).then_some(FaceId(f))
    }
    /// `true` for a live halfedge without a face.
    #[must_use]
    pub fn is_boundary_halfedge(&self, h: HalfedgeId) -> bool {
        self.h_live(h.0) && self.face_raw(h.0) == NONE
    }
    /// `true` for a live edge with a face on one side only.
    #[must_use]
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.e_live(e.0)
            && (self.face_raw(e.0 << 1) == NONE || self.face_raw((e.0 << 1) | 1) == NONE)
    }
    /// `true` for a live vertex on the boundary (O(1), by the boundary convention).
    #[must_use]
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        let h = self.out_raw(v.0);
        self.v_live(v.0) && h != NONE && self.face_raw(h) == NONE
    }
    /// `true` for a live vertex with no incident edge.
    #[must_use]
    pub fn is_isolated(&self, v: VertexId) -> bool {
        self.v_live(v.0) && self.out_raw(v.0) == NONE
    }
    /// Endpoints `[tail, head]` of halfedge `2e`.
    #[must_use]
    pub fn edge_vertices(&self, e: EdgeId) -> Option<[VertexId; 2]> {
        self.e_live(e.0).then(|| {
            [
                VertexId(self.tail_raw(e.0 << 1)),
                VertexId(self.head_raw(e.0 << 1)),
            ]
        })
    }
    /// The face's corners in counter-clockwise order, starting at the tail of its stored
    /// halfedge. For a freshly built mesh this is exactly the input triangle.
    #[must_use]
    pub fn face_vertices(&self, f: FaceId) -> Option<[VertexId; 3]> {
        if !self.f_live(f.0) {
            return None;
        }
        let h = self.fh(f.0);
        let n = self.next_raw(h);
        Some([
            VertexId(self.tail_raw(h)),
            VertexId(self.head_raw(h)),
            VertexId(self.head_raw(n)),
        ])
    }

    /// Corner positions of a live face (internal; dead faces give zeros).
    pub(crate) fn face_positions_raw(&self, f: u32) -> [Vec3; 3] {
        let h = self.fh(f);
        let n = self.next_raw(h);
        [
            self.pos_raw(self.tail_raw(h)),
            self.pos_raw(self.head_raw(h)),
            self.pos_raw(self.head_raw(n)),
        ]
    }

    /// Unnormalised normal `(b − a) × (c − a)` of a live face (twice its area, pointing to the
    /// front); `None` for a dead face.
    #[must_use]
    pub fn face_normal_unnormalized(&self, f: FaceId) -> Option<Vec3> {
        self.f_live(f.0).then(|| {
            let [a, b, c] = self.face_positions_raw(f.0);
            (b - a).cross(c - a)
        })
    }

    // ----- compaction -----
}
