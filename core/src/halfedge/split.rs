//! Edge split.

use glam::Vec3;

use super::error::SplitError;
use super::handles::{EdgeId, NONE, VertexId};
use super::mesh::Mesh;
use super::storage::{Counts, MeshStorage};

/// The midpoint `(p + q)/2`, in `f64` and rounded to `f32` once: each coordinate lies between
/// `p`'s and `q`'s (subnormal ones too, where `p·0.5` in `f32` can round to 0), and it is
/// finite for any finite `p`, `q` (their `f32` sum can overflow).
pub(super) fn midpoint(p: Vec3, q: Vec3) -> Vec3 {
    ((p.as_dvec3() + q.as_dvec3()) * 0.5).as_vec3()
}

impl<S: MeshStorage> Mesh<S> {
    /// Splits `e` at its midpoint (each coordinate between the endpoints', subnormal ones
    /// too); see [`Mesh::split_edge_at`].
    ///
    /// # Errors
    ///
    /// As [`Mesh::split_edge_at`]; the mesh is unchanged.
    pub fn split_edge(&mut self, e: EdgeId) -> Result<VertexId, SplitError> {
        let [a, b] = self.edge_vertices(e).ok_or(SplitError::Dead)?;
        self.split_edge_at(e, midpoint(self.pos_raw(a.0), self.pos_raw(b.0)))
    }

    /// Splits edge `e = a–b` (halfedge `2e` runs `a → b`) at point `p`, inserting a new
    /// vertex `m` and connecting it to the opposite vertex of each incident triangle.
    ///
    /// * Interior edge: +1 vertex, +3 edges, +2 faces. Boundary edge: +1 vertex, +2 edges,
    ///   +1 face (the new vertex is a boundary vertex).
    /// * Edge `e` keeps the half `a–m`: afterwards halfedge `2e` runs `a → m`. The original
    ///   faces keep the corners at `a`.
    /// * `p` need not lie on the segment (any finite point is accepted; a far point can
    ///   fold faces over, which is the caller's choice).
    ///
    /// # Errors
    /// `Dead`, `NonFinitePosition`, `WingsCoincide` (both faces have the same opposite vertex),
    /// or `Capacity`; all checked before anything changes.
    pub fn split_edge_at(&mut self, e: EdgeId, p: Vec3) -> Result<VertexId, SplitError> {
        if !self.e_live(e.0) {
            return Err(SplitError::Dead);
        }
        if !p.is_finite() {
            return Err(SplitError::NonFinitePosition);
        }
        let (h, t) = (e.0 << 1, (e.0 << 1) | 1);
        let (f0, f1) = (self.face_raw(h), self.face_raw(t));
        if f0 != NONE
            && f1 != NONE
            && self.head_raw(self.next_raw(h)) == self.head_raw(self.next_raw(t))
        {
            return Err(SplitError::WingsCoincide); // found by the halfedge_ops fuzz target
        }
        let sides = (f0 != NONE) as usize + (f1 != NONE) as usize;
        self.check_room(Counts {
            vertices: 1,
            edges: 1 + sides,
            faces: sides,
        })
        .map_err(SplitError::Capacity)?;

        let (hn, hp) = (self.next_raw(h), self.prev_raw(h));
        let (tn, tp) = (self.next_raw(t), self.prev_raw(t));
        let b = self.head_raw(h);
        let m = self.alloc_vertex(p);
        let e2 = self.alloc_edge();
        let (g, gt) = (e2 << 1, (e2 << 1) | 1); // g: m→b, gt: b→m
        self.set_head(h, m);
        self.set_head(g, b);
        self.set_head(gt, m);

        // Side of h: triangle (a, b, c) or a boundary loop.
        if f0 != NONE {
            let c = self.head_raw(hn);
            let e3 = self.alloc_edge();
            let (k, kt) = (e3 << 1, (e3 << 1) | 1); // k: m→c, kt: c→m
            let f2 = self.alloc_face();
            self.set_head(k, c);
            self.set_head(kt, m);
            // f0 = (a, m, c): h, k, hp.
            self.link(h, k);
            self.link(k, hp);
            self.set_face(k, f0);
            self.set_fh(f0, h);
            // f2 = (m, b, c): g, hn, kt.
            self.link(g, hn);
            self.link(hn, kt);
            self.link(kt, g);
            self.set_face(g, f2);
            self.set_face(hn, f2);
            self.set_face(kt, f2);
            self.set_fh(f2, g);
        } else {
            self.link(h, g);
            self.link(g, hn);
            self.set_face(g, NONE);
        }
        // Side of t (now m → a): triangle (b, a, d) or a boundary loop.
        if f1 != NONE {
            let d = self.head_raw(tn);
            let e4 = self.alloc_edge();
            let (l, lt) = (e4 << 1, (e4 << 1) | 1); // l: m→d, lt: d→m
            let f3 = self.alloc_face();
            self.set_head(l, d);
            self.set_head(lt, m);
            // f1 = (m, a, d): t, tn, lt.
            self.link(tn, lt);
            self.link(lt, t);
            self.set_face(lt, f1);
            self.set_fh(f1, t);
            // f3 = (b, m, d): gt, l, tp.
            self.link(gt, l);
            self.link(l, tp);
            self.link(tp, gt);
            self.set_face(gt, f3);
            self.set_face(l, f3);
            self.set_face(tp, f3);
            self.set_fh(f3, gt);
        } else {
            self.link(tp, gt);
            self.link(gt, t);
            self.set_face(gt, NONE);
        }
        // Outgoing halfedges: m gets its boundary halfedge if any; b lost `t`.
        // (`g` is m's boundary halfedge when the `h` side is open, and interior otherwise.)
        let m_out = if f1 == NONE { t } else { g };
        self.set_out(m, m_out);
        if self.out_raw(b) == t {
            self.set_out(b, gt);
        }
        Ok(VertexId(m))
    }
}
