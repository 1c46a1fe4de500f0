//! Raw record access of the arena: reads that never panic (out-of-range reads give dead
//! records), writes, liveness, and the fan helpers the operations share.

use glam::Vec3;

use crate::halfedge::handles::NONE;
use crate::halfedge::storage::{DEAD_BIT, FREE_END, HalfedgeRec, MeshStorage, VertexRec};

use super::Mesh;

impl<S: MeshStorage> Mesh<S> {
    // ----- raw record access (never panics: out-of-range reads give dead records) -----

    #[inline]
    pub(crate) fn hr(&self, h: u32) -> HalfedgeRec {
        match self.s.edges().get((h >> 1) as usize) {
            Some(e) => e.h[(h & 1) as usize],
            None => HalfedgeRec::DEAD,
        }
    }

    #[inline]
    pub(crate) fn hr_mut(&mut self, h: u32) -> Option<&mut HalfedgeRec> {
        self.s
            .edges_mut()
            .get_mut((h >> 1) as usize)
            .map(|e| &mut e.h[(h & 1) as usize])
    }

    #[inline]
    pub(crate) fn vr(&self, v: u32) -> VertexRec {
        self.s
            .vertices()
            .get(v as usize)
            .copied()
            .unwrap_or(VertexRec::EMPTY)
    }

    #[inline]
    pub(crate) fn vr_mut(&mut self, v: u32) -> Option<&mut VertexRec> {
        self.s.vertices_mut().get_mut(v as usize)
    }

    /// Stored halfedge of face `f` (dead-marked value for dead/out-of-range faces).
    #[inline]
    pub(crate) fn fh(&self, f: u32) -> u32 {
        self.s
            .faces()
            .get(f as usize)
            .map_or(DEAD_BIT | FREE_END, |r| r.h)
    }

    #[inline]
    pub(crate) fn set_fh(&mut self, f: u32, h: u32) {
        if let Some(r) = self.s.faces_mut().get_mut(f as usize) {
            r.h = h;
        }
    }

    #[inline]
    pub(crate) fn next_raw(&self, h: u32) -> u32 {
        self.hr(h).next
    }
    #[inline]
    pub(crate) fn prev_raw(&self, h: u32) -> u32 {
        self.hr(h).prev
    }
    #[inline]
    pub(crate) fn head_raw(&self, h: u32) -> u32 {
        self.hr(h).head
    }
    #[inline]
    pub(crate) fn tail_raw(&self, h: u32) -> u32 {
        self.hr(h ^ 1).head
    }
    #[inline]
    pub(crate) fn face_raw(&self, h: u32) -> u32 {
        self.hr(h).face
    }
    #[inline]
    pub(crate) fn out_raw(&self, v: u32) -> u32 {
        self.vr(v).out
    }
    #[inline]
    pub(crate) fn pos_raw(&self, v: u32) -> Vec3 {
        self.vr(v).pos
    }

    /// Links `a.next = b` and `b.prev = a`.
    #[inline]
    pub(crate) fn link(&mut self, a: u32, b: u32) {
        if let Some(r) = self.hr_mut(a) {
            r.next = b;
        }
        if let Some(r) = self.hr_mut(b) {
            r.prev = a;
        }
    }
    #[inline]
    pub(crate) fn set_head(&mut self, h: u32, v: u32) {
        if let Some(r) = self.hr_mut(h) {
            r.head = v;
        }
    }
    #[inline]
    pub(crate) fn set_face(&mut self, h: u32, f: u32) {
        if let Some(r) = self.hr_mut(h) {
            r.face = f;
        }
    }
    #[inline]
    pub(crate) fn set_out(&mut self, v: u32, h: u32) {
        if let Some(r) = self.vr_mut(v) {
            r.out = h;
        }
    }
    #[inline]
    pub(crate) fn set_pos(&mut self, v: u32, p: Vec3) {
        if let Some(r) = self.vr_mut(v) {
            r.pos = p;
        }
    }

    #[inline]
    pub(crate) fn v_live(&self, v: u32) -> bool {
        self.s
            .vertices()
            .get(v as usize)
            .is_some_and(|r| r.out == NONE || r.out < DEAD_BIT)
    }
    #[inline]
    pub(crate) fn e_live(&self, e: u32) -> bool {
        self.s
            .edges()
            .get(e as usize)
            .is_some_and(|r| r.h[0].head != NONE)
    }
    #[inline]
    pub(crate) fn h_live(&self, h: u32) -> bool {
        self.e_live(h >> 1)
    }
    #[inline]
    pub(crate) fn f_live(&self, f: u32) -> bool {
        self.s
            .faces()
            .get(f as usize)
            .is_some_and(|r| r.h < DEAD_BIT)
    }

    /// Counter-clockwise rotation of an outgoing halfedge around its tail: `twin(prev(h))`.
    #[inline]
    pub(crate) fn rot_ccw(&self, h: u32) -> u32 {
        self.prev_raw(h) ^ 1
    }

    /// Bound on any walk: the number of halfedge slots in use (at least 1).
    #[inline]
    pub(crate) fn walk_bound(&self) -> usize {
        self.s.edges().len().saturating_mul(2).max(1)
    }

    /// Makes the stored halfedge of `v` its outgoing boundary halfedge if it has one
    /// (re-establishes the boundary convention after a local edit).
    pub(crate) fn adjust_out(&mut self, v: u32) {
        let start = self.out_raw(v);
        if start == NONE || !self.h_live(start) {
            return;
        }
        let mut h = start;
        for _ in 0..self.walk_bound() {
            if self.face_raw(h) == NONE {
                self.set_out(v, h);
                return;
            }
            h = self.rot_ccw(h);
            if h == start {
                return;
            }
        }
    }
}
