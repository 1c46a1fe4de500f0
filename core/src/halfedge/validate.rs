//! [`Mesh::validate`]: every structural invariant, checked without allocation.

use super::error::{ElementKind, InvariantError as IE};
use super::handles::{EdgeId, FaceId, HalfedgeId, NONE, VertexId};
use super::mesh::Mesh;
use super::storage::{DEAD_BIT, FREE_END, MeshStorage};

impl<S: MeshStorage> Mesh<S> {
    /// Checks every invariant and returns the first one broken, naming the element.
    ///
    /// In order: free lists and live counts; halfedge pairs both live or both dead; every
    /// link of a live halfedge points at a live element; `prev(next(h)) = h = next(prev(h))`;
    /// no self-loops; `head(h) = tail(next(h))`; faces are 3-cycles whose halfedges name the
    /// face and contain the face's stored halfedge; boundary halfedges form closed loops and
    /// every edge has at least one face; every live vertex has a finite position, its stored
    /// halfedge starts at it, its fan closes, has at most one boundary halfedge (manifold), a
    /// boundary vertex stores its boundary halfedge, no two of its edges share the other
    /// endpoint; and the vertex fans together cover every live halfedge exactly once.
    ///
    /// Cost O(H + Σ valence²). Every walk is bounded by the slot count (the walks around
    /// vertices by the halfedge checks run before them), so corrupt data cannot hang it.
    ///
    /// # Errors
    ///
    /// The first invariant broken, as an [`IE`] naming the element.
    pub fn validate(&self) -> Result<(), IE> {
        self.check_free_lists()?;
        let ne = self.s.edges().len() as u32;
        for e in 0..ne {
            let (a, b) = (self.head_raw(e << 1), self.head_raw((e << 1) | 1));
            if (a == NONE) != (b == NONE) {
                return Err(IE::HalfedgePair(EdgeId(e)));
            }
        }
        for h in 0..ne * 2 {
            if self.h_live(h) {
                self.check_halfedge(h)?;
            }
        }
        for f in 0..self.s.faces().len() as u32 {
            if self.f_live(f) {
                let h = self.fh(f);
                if !self.h_live(h) || self.face_raw(h) != f {
                    return Err(IE::FaceHalfedge(FaceId(f)));
                }
            }
        }
        let mut covered = 0usize;
        for v in 0..self.s.vertices().len() as u32 {
            if self.v_live(v) {
                covered += self.check_vertex(v)?;
            }
        }
        // The fans are disjoint cycles of live halfedges (disjoint: each keeps its vertex as
        // tail; see `check_vertex`), so they cover every live halfedge exactly once if and
        // only if every live halfedge is in its tail's fan. Their sizes adding up to the live
        // count shows it at once; otherwise some halfedge is missing and the search names
        // its tail. (It always finds one: a count without a missing halfedge cannot happen,
        // so no other error follows it.)
        if covered != self.live.halfedges() {
            for h in 0..ne * 2 {
                if self.h_live(h) && !self.fan_contains(self.tail_raw(h), h) {
                    return Err(IE::VertexFan(VertexId(self.tail_raw(h))));
                }
            }
        }
        Ok(())
    }

    fn check_free_lists(&self) -> Result<(), IE> {
        let slots = self.slots();
        // Vertices.
        let live_v = (0..slots.vertices as u32)
            .filter(|&v| self.v_live(v))
            .count();
        let mut n = 0usize;
        let mut v = self.free_v;
        while v != NONE {
            let out = self.out_raw(v);
            if n > slots.vertices
                || v as usize >= slots.vertices
                || out & DEAD_BIT == 0
                || out == NONE
            {
                return Err(IE::FreeList(ElementKind::Vertex));
            }
            n += 1;
            let link = out & !DEAD_BIT;
            v = if link == FREE_END { NONE } else { link };
        }
        if live_v != self.live.vertices || live_v + n != slots.vertices {
            return Err(IE::FreeList(ElementKind::Vertex));
        }
        // Edges.
        let live_e = (0..slots.edges as u32).filter(|&e| self.e_live(e)).count();
        let (mut n, mut e) = (0usize, self.free_e);
        while e != NONE {
            if n > slots.edges || e as usize >= slots.edges || self.e_live(e) {
                return Err(IE::FreeList(ElementKind::Edge));
            }
            n += 1;
            e = self.next_raw(e << 1);
        }
        if live_e != self.live.edges || live_e + n != slots.edges {
            return Err(IE::FreeList(ElementKind::Edge));
        }
        // Faces.
        let live_f = (0..slots.faces as u32).filter(|&f| self.f_live(f)).count();
        let (mut n, mut f) = (0usize, self.free_f);
        while f != NONE {
            let r = self.fh(f);
            if n > slots.faces || f as usize >= slots.faces || r & DEAD_BIT == 0 {
                return Err(IE::FreeList(ElementKind::Face));
            }
            n += 1;
            let link = r & !DEAD_BIT;
            f = if link == FREE_END { NONE } else { link };
        }
        if live_f != self.live.faces || live_f + n != slots.faces {
            return Err(IE::FreeList(ElementKind::Face));
        }
        Ok(())
    }

    fn check_halfedge(&self, h: u32) -> Result<(), IE> {
        let id = HalfedgeId(h);
        let r = self.hr(h);
        if !self.h_live(r.next)
            || !self.h_live(r.prev)
            || !self.v_live(r.head)
            || (r.face != NONE && !self.f_live(r.face))
        {
            return Err(IE::DanglingLink(id));
        }
        if self.prev_raw(r.next) != h || self.next_raw(r.prev) != h {
            return Err(IE::NextPrev(id));
        }
        if r.head == self.tail_raw(h) {
            return Err(IE::SelfLoop(id));
        }
        if r.head != self.tail_raw(r.next) {
            return Err(IE::HeadTail(id));
        }
        if r.face == NONE {
            if self.face_raw(h ^ 1) == NONE {
                return Err(IE::IsolatedEdge(id.edge()));
            }
            if self.face_raw(r.next) != NONE {
                return Err(IE::BoundaryCycle(id));
            }
        } else {
            let n = r.next;
            let nn = self.next_raw(n);
            let fh = self.fh(r.face);
            if self.next_raw(nn) != h
                || self.face_raw(n) != r.face
                || self.face_raw(nn) != r.face
                || (fh != h && fh != n && fh != nn)
            {
                return Err(IE::FaceCycle(FaceId(r.face)));
            }
        }
        Ok(())
    }

    /// Checks vertex `v`'s record and fan; returns the fan size.
    fn check_vertex(&self, v: u32) -> Result<usize, IE> {
        let id = VertexId(v);
        if !self.pos_raw(v).is_finite() {
            return Err(IE::NonFinitePosition(id));
        }
        let start = self.out_raw(v);
        if start == NONE {
            return Ok(0);
        }
        if !self.h_live(start) || self.tail_raw(start) != v {
            return Err(IE::VertexHalfedge(id));
        }
        let bound = self.walk_bound();
        // No check inside the walk: once the halfedge checks (all run before any vertex
        // check) have passed, it is a cycle of live halfedges out of `v`, at most `bound`
        // long. Those checks make `next` and `prev` inverse permutations of the live
        // halfedges (every link live, `prev(next(h)) = h = next(prev(h))`), so `rot_ccw`
        // (the twin of `prev`, live with its edge) permutes them too: its orbit from the live
        // `start` returns to `start` within the live halfedge count, at most `bound`. It
        // keeps the tail: `head(prev(h)) = tail(next(prev(h))) = tail(h)` (the head–tail
        // check).
        let (mut h, mut n, mut boundary) = (start, 0usize, 0usize);
        loop {
            n += 1;
            if self.face_raw(h) == NONE {
                boundary += 1;
            }
            // Duplicate-edge check against the rest of the fan.
            let head = self.head_raw(h);
            let mut g = self.rot_ccw(h);
            let mut steps = 0;
            while g != start && steps < bound {
                if self.head_raw(g) == head {
                    return Err(IE::DuplicateEdge(id));
                }
                g = self.rot_ccw(g);
                steps += 1;
            }
            h = self.rot_ccw(h);
            if h == start {
                break;
            }
        }
        if boundary > 1 {
            return Err(IE::NonManifoldVertex(id));
        }
        if boundary == 1 && self.face_raw(start) != NONE {
            return Err(IE::BoundaryVertexConvention(id));
        }
        Ok(n)
    }

    /// `true` if walking `v`'s fan from its stored halfedge reaches `h`.
    pub(crate) fn fan_contains(&self, v: u32, h: u32) -> bool {
        let start = self.out_raw(v);
        if start == NONE {
            return false;
        }
        let mut g = start;
        for _ in 0..self.walk_bound() {
            if g == h {
                return true;
            }
            g = self.rot_ccw(g);
            if g == start {
                return false;
            }
        }
        false
    }
}
