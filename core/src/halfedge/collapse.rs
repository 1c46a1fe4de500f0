//! Edge collapse.

use glam::{DVec3, Vec3};

use super::error::CollapseError as CE;
use super::handles::{HalfedgeId, NONE, VertexId};
use super::mesh::Mesh;
use super::storage::MeshStorage;

/// Where the surviving vertex of [`Mesh::collapse_edge`] ends up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CollapseAt {
    /// At the head (the survivor stays put).
    Head,
    /// At the tail (the removed vertex's position).
    Tail,
    /// At the midpoint of the edge: `(p₀ + p₁)/2` in `f64`, rounded to `f32`, so that each
    /// coordinate lies between the endpoints' (subnormal ones too).
    Midpoint,
    /// At an arbitrary finite point.
    Point(Vec3),
}

impl<S: MeshStorage> Mesh<S> {
    /// Whether [`Mesh::collapse_edge`] would accept collapsing `h`, and the target position.
    ///
    /// Rules, checked in this order (the first failure is returned):
    /// 1. `Dead`: `h` is not live; `NonFinitePosition`: the target is not finite.
    /// 2. `WingsCoincide`: both sides have faces with the same opposite vertex.
    /// 3. `Ear(f)`: a face on the edge has its two other edges on the boundary.
    /// 4. `InteriorEdgeJoinsBoundaries`: the edge is interior but both endpoints are on the
    ///    boundary (the collapse would pinch the surface).
    /// 5. `LinkCondition(w)`: `w` is adjacent to both endpoints but is not a wing vertex.
    /// 6. `WingValence(w)`: an interior wing vertex has valence 3 (it would drop to 2; this
    ///    is what refuses every edge of a tetrahedron).
    /// 7. `FoldOver(f)`: with the survivor at the target, a remaining face around either
    ///    endpoint would get a normal pointing against (or perpendicular to) its old one: the
    ///    sign of `old·new` for the unnormalised normals `(b − a) × (c − a)`, evaluated in
    ///    `f64` on the `f32` positions (no overflow for any finite positions; the rounding,
    ///    relative `~1e-15` of `|b − a|·|c − a|` per normal, can decide either way only for
    ///    normals that close to perpendicular or faces that close to degenerate: the decision
    ///    is the exact sign's whenever `|old·new| > 10⁻¹²·|b − a||c − a|·|b′ − a′||c′ − a′|`,
    ///    the domain the `halfedge_ops` fuzz oracle checks); faces whose old normal is zero
    ///    (degenerate) are skipped.
    ///
    /// # Errors
    ///
    /// The first rule broken, as a [`CE`] variant (the list above); nothing is changed.
    pub fn can_collapse_edge(&self, h: HalfedgeId, at: CollapseAt) -> Result<Vec3, CE> {
        if !self.h_live(h.0) {
            return Err(CE::Dead);
        }
        let (h, t) = (h.0, h.0 ^ 1);
        let (v0, v1) = (self.tail_raw(h), self.head_raw(h));
        let (p0, p1) = (self.pos_raw(v0), self.pos_raw(v1));
        let target = match at {
            CollapseAt::Head => p1,
            CollapseAt::Tail => p0,
            CollapseAt::Midpoint => super::split::midpoint(p0, p1),
            CollapseAt::Point(p) => p,
        };
        if !target.is_finite() {
            return Err(CE::NonFinitePosition);
        }
        let (f0, f1) = (self.face_raw(h), self.face_raw(t));
        let vl = if f0 != NONE {
            self.head_raw(self.next_raw(h))
        } else {
            NONE
        };
        let vr = if f1 != NONE {
            self.head_raw(self.next_raw(t))
        } else {
            NONE
        };
        // A valid mesh has a face on at least one side of every edge (`validate`'s
        // `IsolatedEdge`), so equal wings are the apexes of two faces, never two `NONE`s.
        if vl == vr {
            return Err(CE::WingsCoincide);
        }
        for (x, f) in [(h, f0), (t, f1)] {
            if f != NONE {
                let (n, p) = (self.next_raw(x), self.prev_raw(x));
                let twin = |x: u32| HalfedgeId(x).twin().0;
                if self.face_raw(twin(n)) == NONE && self.face_raw(twin(p)) == NONE {
                    return Err(CE::Ear(super::FaceId(f)));
                }
            }
        }
        let bv = |v: u32| self.is_boundary_vertex(VertexId(v));
        if f0 != NONE && f1 != NONE && bv(v0) && bv(v1) {
            return Err(CE::InteriorEdgeJoinsBoundaries);
        }
        for w in self.vertex_neighbors(VertexId(v0)) {
            if w.0 != v1 && w.0 != vl && w.0 != vr && self.find_halfedge(VertexId(v1), w).is_some()
            {
                return Err(CE::LinkCondition(w));
            }
        }
        for w in [vl, vr] {
            if w != NONE && !bv(w) && self.valence(VertexId(w)) <= 3 {
                return Err(CE::WingValence(VertexId(w)));
            }
        }
        for (v, other) in [(v0, v1), (v1, v0)] {
            for f in self.vertex_faces(VertexId(v)) {
                if f.0 == f0 || f.0 == f1 {
                    continue;
                }
                let [a, b, c] = self.face_positions_raw(f.0).map(Vec3::as_dvec3);
                let old = (b - a).cross(c - a);
                let vs = self.face_vertices(f).unwrap_or([VertexId(NONE); 3]);
                let moved = vs.map(|x| {
                    if x.0 == v || x.0 == other {
                        target.as_dvec3()
                    } else {
                        self.pos_raw(x.0).as_dvec3()
                    }
                });
                let new = (moved[1] - moved[0]).cross(moved[2] - moved[0]);
                if old != DVec3::ZERO && old.dot(new) <= 0.0 {
                    return Err(CE::FoldOver(f));
                }
            }
        }
        Ok(target)
    }

    /// Collapses the edge of `h`: its tail `v0` is removed and its head `v1` survives at the
    /// position chosen by `at`. The (one or two) triangles on the edge disappear, each
    /// merging its two other edges into one. Returns the surviving vertex. Removed elements
    /// are tombstoned (one vertex, one to three edges, one or two faces).
    ///
    /// # Errors
    /// Any rule of [`Mesh::can_collapse_edge`]; the mesh is then unchanged.
    pub fn collapse_edge(&mut self, h: HalfedgeId, at: CollapseAt) -> Result<VertexId, CE> {
        let target = self.can_collapse_edge(h, at)?;
        let (h, t) = (h.0, h.0 ^ 1);
        let (v0, v1) = (self.tail_raw(h), self.head_raw(h));
        let (f0, f1) = (self.face_raw(h), self.face_raw(t));
        let (hn, hp) = (self.next_raw(h), self.prev_raw(h));

        // Every halfedge into v0 now ends at v1.
        let start = self.out_raw(v0);
        let mut o = start;
        for _ in 0..self.walk_bound() {
            self.set_head(o ^ 1, v1);
            o = self.rot_ccw(o);
            if o == start {
                break;
            }
        }

        // Upper side (h).
        let mut vl = NONE;
        if f0 != NONE {
            // hn: v1→vl and hp: vl→v1 collapse into one edge: hp takes the place of a.
            vl = self.head_raw(hn);
            let a = hn ^ 1;
            self.replace_halfedge(a, hp);
            if self.out_raw(vl) == a {
                self.set_out(vl, hp);
            }
            self.free_edge(hn >> 1);
            self.free_face(f0);
        } else {
            self.link(hp, hn);
        }

        // Lower side (t), read after the upper side was relinked.
        let (tn, tp) = (self.next_raw(t), self.prev_raw(t));
        let mut vr = NONE;
        if f1 != NONE {
            // tn: v1→vr and tp: vr→v1 collapse: tn takes the place of d = twin(tp).
            vr = self.head_raw(tn);
            let d = tp ^ 1;
            self.replace_halfedge(d, tn);
            if self.out_raw(vr) == tp {
                self.set_out(vr, tn ^ 1);
            }
            self.free_edge(tp >> 1);
            self.free_face(f1);
        } else {
            self.link(tp, tn);
        }

        self.free_edge(h >> 1);
        self.free_vertex(v0);
        // A live outgoing halfedge of v1 (twin(hp) survives on a faced upper side, `tn` on
        // the lower side otherwise), then the boundary convention.
        self.set_out(v1, if f0 != NONE { hp ^ 1 } else { tn });
        self.set_pos(v1, target);
        for v in [v1, vl, vr] {
            if v != NONE {
                self.adjust_out(v);
            }
        }
        Ok(VertexId(v1))
    }

    /// Puts halfedge `by` in the place of `old` in `old`'s face or boundary loop (same
    /// endpoints); `old` is left unlinked.
    fn replace_halfedge(&mut self, old: u32, by: u32) {
        let r = self.hr(old);
        self.set_face(by, r.face);
        self.link(r.prev, by);
        self.link(by, r.next);
        if r.face != NONE && self.fh(r.face) == old {
            self.set_fh(r.face, by);
        }
    }
}
