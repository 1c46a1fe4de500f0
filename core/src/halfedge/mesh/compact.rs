//! [`Mesh::compact`]: dense renumbering.

use crate::halfedge::handles::{EdgeId, FaceId, NONE, VertexId};
use crate::halfedge::storage::{DEAD_BIT, EdgeRec, FREE_END, MeshStorage};

use super::{Mesh, Moved};

impl<S: MeshStorage> Mesh<S> {
    /// Renumbers every element densely (live elements to `0..len`), moving the last live
    /// element into the first hole, pmp/CGAL style, and reports every move to `on_move` so
    /// the caller can update stored handles. All other handles keep their meaning. Afterwards
    /// [`Mesh::is_compact`] holds and the free lists are empty. O(V + E + F).
    pub fn compact(&mut self, mut on_move: impl FnMut(Moved)) {
        // Vertices.
        let (mut i, mut j) = (0usize, self.s.vertices().len());
        loop {
            while i < j && self.v_live(i as u32) {
                i += 1;
            }
            while j > i && !self.v_live((j - 1) as u32) {
                j -= 1;
            }
            if j <= i {
                break;
            }
            let (to, from) = (i as u32, (j - 1) as u32);
            let rec = self.vr(from);
            if let Some(r) = self.vr_mut(to) {
                *r = rec;
            }
            if let Some(r) = self.vr_mut(from) {
                r.out = DEAD_BIT | FREE_END;
            }
            let start = rec.out;
            if start != NONE {
                let mut h = start;
                for _ in 0..self.walk_bound() {
                    self.set_head(h ^ 1, to);
                    h = self.rot_ccw(h);
                    if h == start {
                        break;
                    }
                }
            }
            on_move(Moved::Vertex {
                from: VertexId(from),
                to: VertexId(to),
            });
            i += 1;
            j -= 1;
        }
        // Edges.
        let (mut i, mut j) = (0usize, self.s.edges().len());
        loop {
            while i < j && self.e_live(i as u32) {
                i += 1;
            }
            while j > i && !self.e_live((j - 1) as u32) {
                j -= 1;
            }
            if j <= i {
                break;
            }
            let (to, from) = (i as u32, (j - 1) as u32);
            let map = |x: u32| {
                if x >> 1 == from {
                    (to << 1) | (x & 1)
                } else {
                    x
                }
            };
            let mut rec = self
                .s
                .edges()
                .get(from as usize)
                .copied()
                .unwrap_or(EdgeRec::EMPTY);
            for r in &mut rec.h {
                r.next = map(r.next);
                r.prev = map(r.prev);
            }
            if let Some(r) = self.s.edges_mut().get_mut(to as usize) {
                *r = rec;
            }
            if let Some(r) = self.s.edges_mut().get_mut(from as usize) {
                *r = EdgeRec::EMPTY;
            }
            for s in 0..2u32 {
                let (old, new) = ((from << 1) | s, (to << 1) | s);
                let r = self.hr(new);
                self.link(new, r.next);
                self.link(r.prev, new);
                if r.face != NONE && self.fh(r.face) == old {
                    self.set_fh(r.face, new);
                }
                let tail = self.head_raw(new ^ 1);
                if self.out_raw(tail) == old {
                    self.set_out(tail, new);
                }
            }
            on_move(Moved::Edge {
                from: EdgeId(from),
                to: EdgeId(to),
            });
            i += 1;
            j -= 1;
        }
        // Faces.
        let (mut i, mut j) = (0usize, self.s.faces().len());
        loop {
            while i < j && self.f_live(i as u32) {
                i += 1;
            }
            while j > i && !self.f_live((j - 1) as u32) {
                j -= 1;
            }
            if j <= i {
                break;
            }
            let (to, from) = (i as u32, (j - 1) as u32);
            let h0 = self.fh(from);
            self.set_fh(to, h0);
            self.set_fh(from, DEAD_BIT | FREE_END);
            let mut h = h0;
            for _ in 0..3 {
                self.set_face(h, to);
                h = self.next_raw(h);
            }
            on_move(Moved::Face {
                from: FaceId(from),
                to: FaceId(to),
            });
            i += 1;
            j -= 1;
        }
        self.s.truncate(self.live);
        self.free_v = NONE;
        self.free_e = NONE;
        self.free_f = NONE;
    }
}
