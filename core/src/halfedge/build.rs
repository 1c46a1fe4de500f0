//! Building a mesh from an indexed triangle list, without a heap.

use glam::Vec3;

use super::error::{BuildError, CapacityError, ElementKind};
use super::handles::{FaceId, NONE, VertexId};
use super::mesh::Mesh;
use super::storage::MeshStorage;
use crate::error::{InputElement, NonFiniteError, Storage};

/// `u32`s of scratch that [`Mesh::build`] needs for `faces` triangles: 6 per triangle
/// (3 for the sorted triangle sides, 3 for the side → halfedge map).
#[must_use]
pub const fn build_scratch_len(faces: usize) -> usize {
    faces.saturating_mul(6)
}

/// Directed side `s` (= 3·face + corner) of the triangle list: `(tail, head)`.
#[inline]
fn side(tris: &[[u32; 3]], s: usize) -> (u32, u32) {
    match tris.get(s / 3) {
        Some(t) => {
            let k = s % 3;
            (t[k], t[(k + 1) % 3])
        }
        None => (NONE, NONE),
    }
}

/// Undirected sort key of side `s`.
#[inline]
fn key(tris: &[[u32; 3]], s: usize) -> u64 {
    let (a, b) = side(tris, s);
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    ((lo as u64) << 32) | hi as u64
}

/// The triangle that brings an edge's user count above two: the third-lowest triangle index
/// among `sides` (the sides of one undirected edge, so of distinct triangles). With fewer
/// than three sides, the highest triangle present; 0 for none.
fn third_user(sides: &[u32]) -> u32 {
    let mut low = [u32::MAX; 3];
    for &s in sides {
        let mut f = s / 3;
        for l in &mut low {
            if f < *l {
                core::mem::swap(&mut f, l);
            }
        }
    }
    low.iter()
        .rev()
        .find(|&&l| l != u32::MAX)
        .copied()
        .unwrap_or(0)
}

impl<S: MeshStorage> Mesh<S> {
    /// Replaces the mesh with the triangles `triangles` over `positions`.
    ///
    /// * `positions`: one point per vertex, all finite. Vertex `i` gets handle `VertexId(i)`.
    /// * `triangles`: counter-clockwise vertex index triples; triangle `i` becomes face
    ///   `FaceId(i)` and [`Mesh::face_vertices`] returns it unchanged.
    /// * `scratch`: at least [`build_scratch_len`]`(triangles.len())` `u32`s, contents ignored.
    ///   Twins are matched by sorting triangle sides in it (O(F log F)).
    ///
    /// Vertices that no triangle uses are accepted and become isolated vertices (no
    /// halfedge). Edges are numbered in order of their sorted `(min, max)` vertex pair.
    ///
    /// # Errors
    /// Checked in this order, each naming the first offending element: the vertex and face
    /// capacity, the scratch size, a non-finite position, an out-of-range or repeated index;
    /// then one pass over the edges in order of their sorted `(min, max)` vertex pair, which
    /// stops at the first edge used by more than two triangles or used twice in one direction
    /// (inconsistent orientation), whichever of the two that edge shows; then the edge
    /// capacity (the edge count is known only after that pass); then a non-manifold (bowtie)
    /// vertex: one pinched at the boundary first (the first met in halfedge order), then one
    /// whose triangles close into more than one fan, so the vertex named is not always the
    /// lowest-numbered offender. On any error the mesh is left empty.
    pub fn build(
        &mut self,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        scratch: &mut [u32],
    ) -> Result<(), BuildError> {
        self.clear();
        let r = self.build_inner(positions, triangles, scratch);
        if r.is_err() {
            self.clear();
        }
        r
    }

    fn build_inner(
        &mut self,
        positions: &[Vec3],
        tris: &[[u32; 3]],
        scratch: &mut [u32],
    ) -> Result<(), BuildError> {
        let (nv, nf) = (positions.len(), tris.len());
        let cap = self.capacity();
        let too_many = |kind, needed, available| {
            BuildError::Capacity(CapacityError {
                storage: Storage::MeshSlots(kind),
                needed,
                available,
            })
        };
        if nv > cap.vertices {
            return Err(too_many(ElementKind::Vertex, nv, cap.vertices));
        }
        if nf > cap.faces {
            return Err(too_many(ElementKind::Face, nf, cap.faces));
        }
        let ns = nf * 3;
        let needed = build_scratch_len(nf);
        CapacityError::check(Storage::MeshBuildScratch, needed, scratch.len())
            .map_err(BuildError::Capacity)?;
        if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
            return Err(BuildError::NonFinite(NonFiniteError {
                element: InputElement::Vertex,
                index,
            }));
        }
        for (f, t) in tris.iter().enumerate() {
            let face = FaceId(f as u32);
            if let Some(&index) = t.iter().find(|&&i| i as usize >= nv) {
                return Err(BuildError::IndexOutOfRange { face, index });
            }
            if t[0] == t[1] || t[0] == t[2] {
                return Err(BuildError::RepeatedIndex {
                    face,
                    vertex: VertexId(t[0]),
                });
            }
            if t[1] == t[2] {
                return Err(BuildError::RepeatedIndex {
                    face,
                    vertex: VertexId(t[1]),
                });
            }
        }

        let (order, map) = scratch.split_at_mut(ns);
        for (i, o) in order.iter_mut().enumerate() {
            *o = i as u32;
        }
        order.sort_unstable_by_key(|&s| key(tris, s as usize));

        // Pass 1: edge multiplicity and orientation, and the edge count.
        let mut ne = 0usize;
        let mut i = 0usize;
        while i < ns {
            let s1 = order.get(i).map_or(0, |&s| s as usize);
            let k = key(tris, s1);
            let mut j = i + 1;
            while j < ns && order.get(j).is_some_and(|&s| key(tris, s as usize) == k) {
                j += 1;
            }
            let (lo, hi) = ((k >> 32) as u32, k as u32);
            if j - i > 2 {
                return Err(BuildError::NonManifoldEdge {
                    a: VertexId(lo),
                    b: VertexId(hi),
                    face: FaceId(third_user(order.get(i..j).unwrap_or(&[]))),
                });
            }
            if j - i == 2 {
                let s2 = order.get(i + 1).map_or(0, |&s| s as usize);
                let (a, b) = side(tris, s1);
                if side(tris, s2) == (a, b) {
                    return Err(BuildError::InconsistentOrientation {
                        a: VertexId(a),
                        b: VertexId(b),
                        face: FaceId((s1.max(s2) / 3) as u32),
                    });
                }
            }
            ne += 1;
            i = j;
        }
        if ne > cap.edges {
            return Err(too_many(ElementKind::Edge, ne, cap.edges));
        }

        // Pass 2: write vertices, faces and edges.
        for &p in positions {
            self.alloc_vertex(p);
        }
        for _ in 0..nf {
            self.alloc_face();
        }
        let mut i = 0usize;
        while i < ns {
            let s1 = order.get(i).map_or(0, |&s| s as usize);
            let paired = i + 1 < ns
                && order
                    .get(i + 1)
                    .is_some_and(|&s| key(tris, s as usize) == key(tris, s1));
            let e = self.alloc_edge();
            let (h0, h1) = (e << 1, (e << 1) | 1);
            let (a, b) = side(tris, s1);
            if let Some(m) = map.get_mut(s1) {
                *m = h0;
            }
            self.set_head(h0, b);
            self.set_face(h0, (s1 / 3) as u32);
            self.set_head(h1, a);
            if paired {
                let s2 = order.get(i + 1).map_or(0, |&s| s as usize);
                if let Some(m) = map.get_mut(s2) {
                    *m = h1;
                }
                self.set_face(h1, (s2 / 3) as u32);
                i += 2;
            } else {
                self.set_face(h1, NONE);
                i += 1;
            }
        }

        // Face cycles and a (provisional) outgoing halfedge per referenced vertex.
        for (f, t) in tris.iter().enumerate() {
            let h = [0, 1, 2].map(|k| map.get(3 * f + k).copied().unwrap_or(NONE));
            for k in 0..3 {
                self.link(h[k], h[(k + 1) % 3]);
                self.set_out(t[k], h[k]);
            }
            self.set_fh(f as u32, h[0]);
        }

        // Boundary halfedges: each vertex gets its unique outgoing boundary halfedge.
        let nh = (ne * 2) as u32;
        for b in (1..nh).step_by(2) {
            if self.face_raw(b) != NONE {
                continue;
            }
            let v = self.tail_raw(b);
            if self.face_raw(self.out_raw(v)) == NONE {
                return Err(BuildError::NonManifoldVertex {
                    vertex: VertexId(v),
                });
            }
            self.set_out(v, b);
        }
        for b in (1..nh).step_by(2) {
            if self.face_raw(b) != NONE {
                continue;
            }
            let w = self.head_raw(b);
            let n = self.out_raw(w);
            if self.face_raw(n) != NONE {
                return Err(BuildError::NonManifoldVertex {
                    vertex: VertexId(w),
                });
            }
            self.link(b, n);
        }

        // Fan check: the rotation orbit of each vertex's halfedge must cover all of its
        // outgoing halfedges. Mark orbits in a bitset reusing the sorted-sides scratch.
        let bits = order;
        let words = (nh as usize).div_ceil(32);
        for w in bits.iter_mut().take(words) {
            *w = 0;
        }
        for v in 0..nv as u32 {
            let start = self.out_raw(v);
            if start == NONE {
                continue;
            }
            let mut h = start;
            for _ in 0..nh {
                if let Some(w) = bits.get_mut((h / 32) as usize) {
                    *w |= 1 << (h % 32);
                }
                h = self.rot_ccw(h);
                if h == start {
                    break;
                }
            }
        }
        for h in 0..nh {
            let marked = bits
                .get((h / 32) as usize)
                .is_some_and(|w| w & (1 << (h % 32)) != 0);
            if !marked {
                return Err(BuildError::NonManifoldVertex {
                    vertex: VertexId(self.tail_raw(h)),
                });
            }
        }
        Ok(())
    }
}
