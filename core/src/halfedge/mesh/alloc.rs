//! Element allocation and release through intrusive free lists (callers check capacity
//! first with `check_room`).

use glam::Vec3;

use crate::halfedge::handles::NONE;
use crate::halfedge::storage::{
    DEAD_BIT, EdgeRec, FREE_END, FaceRec, HalfedgeRec, MAX_ELEMENTS, MeshStorage, VertexRec,
};

use super::Mesh;

impl<S: MeshStorage> Mesh<S> {
    // ----- allocation (callers check capacity first with `check_room`) -----

    pub(crate) fn alloc_vertex(&mut self, pos: Vec3) -> u32 {
        let rec = VertexRec { pos, out: NONE };
        if self.free_v != NONE {
            let v = self.free_v;
            let link = self.vr(v).out & !DEAD_BIT;
            self.free_v = if link == FREE_END { NONE } else { link };
            if let Some(r) = self.vr_mut(v) {
                *r = rec;
            }
            self.live.vertices += 1;
            return v;
        }
        let v = self.s.vertices().len() as u32;
        if self.s.vertices().len() < MAX_ELEMENTS && self.s.push_vertex(rec) {
            self.live.vertices += 1;
            v
        } else {
            NONE
        }
    }

    pub(crate) fn alloc_edge(&mut self) -> u32 {
        let fresh = HalfedgeRec {
            next: NONE,
            prev: NONE,
            head: 0,
            face: NONE,
        };
        let rec = EdgeRec { h: [fresh; 2] };
        if self.free_e != NONE {
            let e = self.free_e;
            self.free_e = self.hr(e << 1).next;
            if let Some(r) = self.s.edges_mut().get_mut(e as usize) {
                *r = rec;
            }
            self.live.edges += 1;
            return e;
        }
        let e = self.s.edges().len() as u32;
        if self.s.edges().len() < MAX_ELEMENTS && self.s.push_edge(rec) {
            self.live.edges += 1;
            e
        } else {
            NONE
        }
    }

    pub(crate) fn alloc_face(&mut self) -> u32 {
        if self.free_f != NONE {
            let f = self.free_f;
            let link = self.fh(f) & !DEAD_BIT;
            self.free_f = if link == FREE_END { NONE } else { link };
            self.set_fh(f, NONE);
            self.live.faces += 1;
            return f;
        }
        let f = self.s.faces().len() as u32;
        if self.s.faces().len() < MAX_ELEMENTS && self.s.push_face(FaceRec { h: NONE }) {
            self.live.faces += 1;
            f
        } else {
            NONE
        }
    }

    pub(crate) fn free_vertex(&mut self, v: u32) {
        let link = if self.free_v == NONE {
            FREE_END
        } else {
            self.free_v
        };
        if let Some(r) = self.vr_mut(v) {
            *r = VertexRec {
                pos: Vec3::ZERO,
                out: DEAD_BIT | link,
            };
            self.free_v = v;
            self.live.vertices -= 1;
        }
    }

    pub(crate) fn free_edge(&mut self, e: u32) {
        let link = self.free_e;
        if let Some(r) = self.s.edges_mut().get_mut(e as usize) {
            *r = EdgeRec::EMPTY;
            r.h[0].next = link;
            self.free_e = e;
            self.live.edges -= 1;
        }
    }

    pub(crate) fn free_face(&mut self, f: u32) {
        let link = if self.free_f == NONE {
            FREE_END
        } else {
            self.free_f
        };
        if let Some(r) = self.s.faces_mut().get_mut(f as usize) {
            r.h = DEAD_BIT | link;
            self.free_f = f;
            self.live.faces -= 1;
        }
    }
}
