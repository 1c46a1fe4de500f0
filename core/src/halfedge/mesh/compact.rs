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
        self.fill_holes(self.s.vertices().len(), Self::v_live, |m, to, from| {
            let rec = m.vr(from);
            if let Some(r) = m.vr_mut(to) {
                *r = rec;
            }
            if let Some(r) = m.vr_mut(from) {
                r.out = DEAD_BIT | FREE_END;
            }
            let start = rec.out;
            if start != NONE {
                let mut h = start;
                for _ in 0..m.walk_bound() {
                    m.set_head(h ^ 1, to);
                    h = m.rot_ccw(h);
                    if h == start {
                        break;
                    }
                }
            }
            on_move(Moved::Vertex {
                from: VertexId(from),
                to: VertexId(to),
            });
        });
        self.fill_holes(self.s.edges().len(), Self::e_live, |m, to, from| {
            let map = |x: u32| {
                if x >> 1 == from {
                    (to << 1) | (x & 1)
                } else {
                    x
                }
            };
            let mut rec =
                m.s.edges()
                    .get(from as usize)
                    .copied()
                    .unwrap_or(EdgeRec::EMPTY);
            for r in &mut rec.h {
                r.next = map(r.next);
                r.prev = map(r.prev);
            }
            if let Some(r) = m.s.edges_mut().get_mut(to as usize) {
                *r = rec;
            }
            if let Some(r) = m.s.edges_mut().get_mut(from as usize) {
                *r = EdgeRec::EMPTY;
            }
            for s in 0..2u32 {
                let (old, new) = ((from << 1) | s, (to << 1) | s);
                let r = m.hr(new);
                m.link(new, r.next);
                m.link(r.prev, new);
                if r.face != NONE && m.fh(r.face) == old {
                    m.set_fh(r.face, new);
                }
                let tail = m.head_raw(new ^ 1);
                if m.out_raw(tail) == old {
                    m.set_out(tail, new);
                }
            }
            on_move(Moved::Edge {
                from: EdgeId(from),
                to: EdgeId(to),
            });
        });
        self.fill_holes(self.s.faces().len(), Self::f_live, |m, to, from| {
            let h0 = m.fh(from);
            m.set_fh(to, h0);
            m.set_fh(from, DEAD_BIT | FREE_END);
            let mut h = h0;
            for _ in 0..3 {
                m.set_face(h, to);
                h = m.next_raw(h);
            }
            on_move(Moved::Face {
                from: FaceId(from),
                to: FaceId(to),
            });
        });
        self.s.truncate(self.live);
        self.free_v = NONE;
        self.free_e = NONE;
        self.free_f = NONE;
    }

    /// The two-finger scan of [`Mesh::compact`] over `len` slots of one element kind: the
    /// last live slot is moved into the first hole (`relocate(mesh, to, from)`) until the live
    /// slots are `0..count`.
    fn fill_holes(
        &mut self,
        len: usize,
        live: fn(&Self, u32) -> bool,
        mut relocate: impl FnMut(&mut Self, u32, u32),
    ) {
        let (mut i, mut j) = (0usize, len);
        loop {
            while i < j && live(self, i as u32) {
                i += 1;
            }
            while j > i && !live(self, (j - 1) as u32) {
                j -= 1;
            }
            if j <= i {
                break;
            }
            relocate(self, i as u32, (j - 1) as u32);
            i += 1;
            j -= 1;
        }
    }
}
