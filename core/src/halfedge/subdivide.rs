//! Loop subdivision, one level per call, into a second mesh.

use glam::{DVec3, Vec3};

use super::error::{CapacityError, ElementKind, SubdivideError};
use super::handles::{NONE, VertexId};
use super::mesh::Mesh;
use super::storage::MeshStorage;

/// Which vertex weight β(n) the Loop scheme uses for an interior vertex of valence `n`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LoopWeights {
    /// Warren: β = 3/16 for n = 3, 3/(8n) for n > 3. Needs no trigonometry. The default.
    #[default]
    Warren,
    /// Loop 1987: β = (5/8 − (3/8 + cos(2π/n)/4)²)/n.
    Loop,
}

/// β(n) of the chosen weighting, as used by [`Mesh::subdivide_loop`]: the new interior
/// vertex is `(1 − n·β)·x + β·Σ neighbours`. The two weightings agree at n = 3 and n = 6
/// only. Valences below 3 (possible only in degenerate closed meshes) use the n = 3 value;
/// `n = 0` gives 0.
#[must_use]
pub fn loop_beta(n: usize, weights: LoopWeights) -> f32 {
    match (n, weights) {
        (0, _) => 0.0,
        (1..=3, _) => 3.0 / 16.0,
        (_, LoopWeights::Warren) => 3.0 / (8.0 * n as f32),
        (_, LoopWeights::Loop) => {
            let c = 0.375 + 0.25 * libm::cos(2.0 * core::f64::consts::PI / n as f64);
            ((0.625 - c * c) / n as f64) as f32
        }
    }
}

/// Child halfedges of old halfedge `h` (tail → midpoint, midpoint → head). Old edge `e`
/// becomes edges `2e` (old tail of `2e` – midpoint) and `2e + 1` (midpoint – old head).
#[inline]
fn children(h: u32) -> (u32, u32) {
    let e = h >> 1;
    if h & 1 == 0 {
        (4 * e, 4 * e + 2)
    } else {
        (4 * e + 3, 4 * e + 1)
    }
}

impl<S: MeshStorage> Mesh<S> {
    /// Loop-subdivided position of old vertex `v` (the "even" rule): interior vertex of
    /// valence n: `(1 − nβ)·x + β·Σ neighbours`; boundary vertex: `3/4·x + 1/8·(b₀ + b₁)`
    /// over its two neighbours along boundary edges; isolated vertex: unchanged.
    #[must_use]
    pub fn loop_vertex_position(&self, v: VertexId, weights: LoopWeights) -> Option<Vec3> {
        if !self.v_live(v.0) {
            return None;
        }
        let x = self.pos_raw(v.0);
        let out = self.out_raw(v.0);
        if out == NONE {
            return Some(x);
        }
        // Every rule in `f64`, rounded to `f32` once: a sum of neighbours near the largest
        // `f32` coordinates does not overflow (the result, a convex combination for β ≤ 1/n,
        // is as large as they are).
        if self.face_raw(out) == NONE {
            let b0 = self.pos_raw(self.head_raw(out)).as_dvec3();
            let b1 = self.pos_raw(self.tail_raw(self.prev_raw(out))).as_dvec3();
            return Some((0.75 * x.as_dvec3() + 0.125 * (b0 + b1)).as_vec3());
        }
        let (mut sum, mut n) = (DVec3::ZERO, 0usize);
        for w in self.vertex_neighbors(v) {
            sum += self.pos_raw(w.0).as_dvec3();
            n += 1;
        }
        let beta = f64::from(loop_beta(n, weights));
        Some(((1.0 - n as f64 * beta) * x.as_dvec3() + beta * sum).as_vec3())
    }

    /// Loop-subdivided position of the new vertex on edge `e` (the "odd" rule): interior
    /// edge `a–b` with opposite vertices `c`, `d`: `3/8·(a + b) + 1/8·(c + d)`; boundary edge:
    /// the midpoint. Computed in `f64` and rounded to `f32` once, as
    /// [`Mesh::loop_vertex_position`]: a convex combination of finite positions is finite.
    #[must_use]
    pub fn loop_edge_position(&self, e: super::EdgeId) -> Option<Vec3> {
        if !self.e_live(e.0) {
            return None;
        }
        let (h, t) = (e.halfedge(0).0, e.halfedge(1).0);
        let (a, b) = (
            self.pos_raw(self.tail_raw(h)),
            self.pos_raw(self.head_raw(h)),
        );
        if self.face_raw(h) == NONE || self.face_raw(t) == NONE {
            return Some(super::split::midpoint(a, b));
        }
        let (a, b) = (a.as_dvec3(), b.as_dvec3());
        let c = self.pos_raw(self.head_raw(self.next_raw(h))).as_dvec3();
        let d = self.pos_raw(self.head_raw(self.next_raw(t))).as_dvec3();
        Some((0.375 * (a + b) + 0.125 * (c + d)).as_vec3())
    }

    /// One level of Loop subdivision of this mesh, written into `out` (which is cleared).
    ///
    /// Topologically this is "split every edge at its midpoint, then flip every new edge
    /// that joins a new vertex to an old vertex", built directly. Positions are all computed
    /// from this mesh's (old) positions with [`Mesh::loop_vertex_position`] and
    /// [`Mesh::loop_edge_position`].
    ///
    /// **Numbering** (relied on by callers): old vertex `i` keeps index `i`; the new vertex on
    /// old edge `e` is `V + e` (edge-id order). Old edge `e` from `a` to `b` (its halfedge
    /// `2e`, [`Mesh::edge_vertices`]) becomes edge `2e` from `a` to `V + e` and edge `2e + 1`
    /// from `V + e` to `b`;
    /// old face `f` becomes faces `4f + k` (the corner at the head of its k-th halfedge,
    /// starting from its stored halfedge) and `4f + 3` (the middle triangle); the inner edges
    /// are `2E + 3f + k`. Counts: V' = V + E, E' = 2E + 3F, F' = 4F; a closed mesh stays
    /// closed and V − E + F is preserved.
    ///
    /// # Errors
    /// `NotCompact` if this mesh has tombstoned slots ([`Mesh::compact`] first);
    /// `Capacity` if `out` cannot hold the result; `CoincidentFaces` if two faces share all
    /// three vertices. `out` is unchanged on error. Every new position is a convex
    /// combination of old ones computed in `f64`, so it is finite (no overflow error).
    pub fn subdivide_loop<T: MeshStorage>(
        &self,
        out: &mut Mesh<T>,
        weights: LoopWeights,
    ) -> Result<(), SubdivideError> {
        if !self.is_compact() {
            return Err(SubdivideError::NotCompact);
        }
        let need = self.live.after_loop();
        let cap = out.capacity();
        for (kind, n, c) in [
            (ElementKind::Vertex, need.vertices, cap.vertices),
            (ElementKind::Edge, need.edges, cap.edges),
            (ElementKind::Face, need.faces, cap.faces),
        ] {
            if n > c {
                return Err(SubdivideError::Capacity(CapacityError {
                    storage: crate::error::Storage::MeshSlots(kind),
                    needed: n,
                    available: c,
                }));
            }
        }
        let (nv, ne, nf) = (
            self.live.vertices as u32,
            self.live.edges as u32,
            self.live.faces as u32,
        );
        for e in 0..ne {
            let (h, t) = (e << 1, (e << 1) | 1);
            if self.face_raw(h) != NONE
                && self.face_raw(t) != NONE
                && self.head_raw(self.next_raw(h)) == self.head_raw(self.next_raw(t))
            {
                // Found by the `halfedge_ops` fuzz target.
                return Err(SubdivideError::CoincidentFaces(super::EdgeId(e)));
            }
        }
        out.clear();
        for v in 0..nv {
            out.alloc_vertex(
                self.loop_vertex_position(VertexId(v), weights)
                    .unwrap_or(Vec3::ZERO),
            );
        }
        for e in 0..ne {
            out.alloc_vertex(
                self.loop_edge_position(super::EdgeId(e))
                    .unwrap_or(Vec3::ZERO),
            );
        }
        for _ in 0..need.edges {
            out.alloc_edge();
        }
        for _ in 0..need.faces {
            out.alloc_face();
        }
        // Split edges.
        for h in 0..ne * 2 {
            let (first, second) = children(h);
            out.set_head(first, nv + (h >> 1));
            out.set_head(second, self.head_raw(h));
            if self.face_raw(h) == NONE {
                out.set_face(first, NONE);
                out.set_face(second, NONE);
                out.link(first, second);
                out.link(second, children(self.next_raw(h)).0);
            }
        }
        // Four triangles per face.
        for f in 0..nf {
            let h0 = self.fh(f);
            let h1 = self.next_raw(h0);
            let hs = [h0, h1, self.next_raw(h1)];
            let mids = hs.map(|h| nv + (h >> 1));
            let inner = |k: usize| 2 * (2 * ne + 3 * f + k as u32);
            for k in 0..3 {
                let k1 = (k + 1) % 3;
                let (ic, im) = (inner(k), inner(k) + 1); // ic: m_{k+1} → m_k, im: m_k → m_{k+1}
                out.set_head(ic, mids[k]);
                out.set_head(im, mids[k1]);
                let a = children(hs[k]).1;
                let b = children(hs[k1]).0;
                let cf = 4 * f + k as u32;
                out.link(a, b);
                out.link(b, ic);
                out.link(ic, a);
                for x in [a, b, ic] {
                    out.set_face(x, cf);
                }
                out.set_fh(cf, a);
                out.link(im, inner(k1) + 1);
                out.set_face(im, 4 * f + 3);
            }
            out.set_fh(4 * f + 3, inner(0) + 1);
        }
        // Outgoing halfedges (boundary convention preserved).
        for v in 0..nv {
            let o = self.out_raw(v);
            out.set_out(v, if o == NONE { NONE } else { children(o).0 });
        }
        for e in 0..ne {
            let (h, t) = (e << 1, (e << 1) | 1);
            let o = if self.face_raw(t) == NONE {
                children(t).1
            } else {
                children(h).1
            };
            out.set_out(nv + e, o);
        }
        Ok(())
    }
}
