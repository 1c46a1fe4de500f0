//! Edge flip.

use super::error::FlipError;
use super::handles::{EdgeId, NONE, VertexId};
use super::mesh::Mesh;
use super::storage::MeshStorage;

impl<S: MeshStorage> Mesh<S> {
    /// Whether [`Mesh::flip_edge`] would accept `e`, without changing anything.
    ///
    /// Refused: a dead edge; a boundary edge; equal wing vertices; wing vertices already
    /// joined by an edge (this also rules out tetrahedra and interior valence-3 endpoints);
    /// an endpoint whose valence would drop below 3.
    ///
    /// # Errors
    ///
    /// The first refusal, as a [`FlipError`]; nothing is changed.
    pub fn can_flip_edge(&self, e: EdgeId) -> Result<(), FlipError> {
        if !self.e_live(e.0) {
            return Err(FlipError::Dead);
        }
        let (h, t) = (e.0 << 1, (e.0 << 1) | 1);
        if self.face_raw(h) == NONE || self.face_raw(t) == NONE {
            return Err(FlipError::Boundary);
        }
        let (a, b) = (self.tail_raw(h), self.head_raw(h));
        let c = self.head_raw(self.next_raw(h));
        let d = self.head_raw(self.next_raw(t));
        if c == d {
            return Err(FlipError::WingsCoincide);
        }
        if self.find_halfedge(VertexId(c), VertexId(d)).is_some() {
            return Err(FlipError::DuplicateEdge);
        }
        for v in [a, b] {
            if self.valence(VertexId(v)) < 4 {
                return Err(FlipError::DegreeTooLow(VertexId(v)));
            }
        }
        Ok(())
    }

    /// Flips interior edge `e` inside the quad formed by its two triangles: the edge `a–b`
    /// with triangles `(a, b, c)` and `(b, a, d)` becomes `d–c` with triangles `(c, a, d)` and
    /// `(d, b, c)`. Afterwards halfedge `2e` runs `d → c`; the two faces keep their handles.
    /// No new elements; capacity is irrelevant. Refusals as [`Mesh::can_flip_edge`], with
    /// the mesh unchanged.
    ///
    /// # Errors
    ///
    /// As [`Mesh::can_flip_edge`]; the mesh is unchanged.
    pub fn flip_edge(&mut self, e: EdgeId) -> Result<(), FlipError> {
        self.can_flip_edge(e)?;
        let (h, t) = (e.0 << 1, (e.0 << 1) | 1);
        let (hn, hp) = (self.next_raw(h), self.prev_raw(h));
        let (tn, tp) = (self.next_raw(t), self.prev_raw(t));
        let (f0, f1) = (self.face_raw(h), self.face_raw(t));
        let (a, b) = (self.tail_raw(h), self.head_raw(h));
        let (c, d) = (self.head_raw(hn), self.head_raw(tn));
        // f0 = (c, a, d): hp (c→a), tn (a→d), h (d→c).
        self.link(hp, tn);
        self.link(tn, h);
        self.link(h, hp);
        // f1 = (d, b, c): tp (d→b), hn (b→c), t (c→d).
        self.link(t, tp);
        self.link(tp, hn);
        self.link(hn, t);
        self.set_head(h, c);
        self.set_head(t, d);
        self.set_face(tn, f0);
        self.set_face(hn, f1);
        self.set_fh(f0, h);
        self.set_fh(f1, t);
        if self.out_raw(a) == h {
            self.set_out(a, tn);
        }
        if self.out_raw(b) == t {
            self.set_out(b, hn);
        }
        Ok(())
    }
}
