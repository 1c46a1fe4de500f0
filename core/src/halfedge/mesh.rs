//! The arena: [`Mesh`], element allocation with intrusive free lists, navigation accessors
//! and [`Mesh::compact`].

use core::fmt;

use glam::Vec3;

use super::error::{CapacityError, ElementKind, PositionError};
use super::handles::{EdgeId, FaceId, HalfedgeId, NONE, VertexId};
use super::storage::{
    Counts, DEAD_BIT, EdgeRec, FREE_END, FaceRec, HalfedgeRec, InlineStorage, MAX_ELEMENTS,
    MeshStorage, SliceStorage, VertexRec,
};

/// A triangle half-edge mesh over fixed-capacity storage `S`.
///
/// # Conventions (invariants checked by [`Mesh::validate`])
/// * A halfedge runs tail → head; its face, if any, lies on its left; faces are triangles,
///   counter-clockwise seen from the front.
/// * Halfedges come in twin pairs `2e`, `2e + 1` (edge `e`).
/// * A vertex stores one **outgoing** halfedge. **Boundary convention:** a boundary vertex
///   stores its (unique) outgoing *boundary* halfedge, so `is_boundary_vertex` is O(1).
/// * A boundary halfedge has no face; boundary halfedges are linked by `next`/`prev` into
///   closed boundary loops that run clockwise (opposite to the faces).
/// * An isolated vertex (no incident edge, e.g. an unreferenced input vertex) has no
///   halfedge; it is kept, exported, and left alone by every operation.
/// * Every vertex is manifold: its outgoing halfedges form a single fan.
///
/// Deleted elements are tombstoned and reused through intrusive free lists; [`Mesh::compact`]
/// renumbers densely. Handles are slot indices: they stay valid across every operation except
/// `compact` and `clear`/`build`.
#[derive(Clone)]
pub struct Mesh<S: MeshStorage> {
    pub(crate) s: S,
    pub(crate) live: Counts,
    pub(crate) free_v: u32,
    pub(crate) free_e: u32,
    pub(crate) free_f: u32,
}

/// A mesh with inline const-generic capacity: `V` vertices, `E` edges (2E halfedges),
/// `F` faces. See [`InlineStorage`] for the stack-size caveat.
pub type HalfedgeMesh<const V: usize, const E: usize, const F: usize> =
    Mesh<InlineStorage<V, E, F>>;

/// A mesh over caller-provided slices (any size, nothing on the stack).
pub type SliceMesh<'a> = Mesh<SliceStorage<'a>>;

/// One element moved by [`Mesh::compact`] (`from` slot → `to` slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moved {
    /// A vertex moved.
    Vertex {
        /// Old slot.
        from: VertexId,
        /// New slot.
        to: VertexId,
    },
    /// An edge (with both halfedges) moved.
    Edge {
        /// Old slot.
        from: EdgeId,
        /// New slot.
        to: EdgeId,
    },
    /// A face moved.
    Face {
        /// Old slot.
        from: FaceId,
        /// New slot.
        to: FaceId,
    },
}

impl<const V: usize, const E: usize, const F: usize> Mesh<InlineStorage<V, E, F>> {
    /// An empty mesh with inline storage (`const`: usable for a `static`).
    pub const fn new() -> Self {
        Self {
            s: InlineStorage::new(),
            live: Counts {
                vertices: 0,
                edges: 0,
                faces: 0,
            },
            free_v: NONE,
            free_e: NONE,
            free_f: NONE,
        }
    }
}

impl<const V: usize, const E: usize, const F: usize> Default for Mesh<InlineStorage<V, E, F>> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a> Mesh<SliceStorage<'a>> {
    /// An empty mesh over caller buffers; their lengths are the capacities.
    pub fn from_slices(
        vertices: &'a mut [VertexRec],
        edges: &'a mut [EdgeRec],
        faces: &'a mut [FaceRec],
    ) -> Self {
        Self::with_storage(SliceStorage::new(vertices, edges, faces))
    }
}

impl<S: MeshStorage> fmt::Debug for Mesh<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Mesh")
            .field("live", &self.live)
            .field("slots", &self.slots())
            .field("capacity", &self.capacity())
            .finish()
    }
}

/// Bit-for-bit state comparison: counts, free lists and every used record slot. Two meshes
/// with different storage types compare equal when their contents are identical.
impl<S: MeshStorage, T: MeshStorage> PartialEq<Mesh<T>> for Mesh<S> {
    fn eq(&self, o: &Mesh<T>) -> bool {
        self.live == o.live
            && self.free_v == o.free_v
            && self.free_e == o.free_e
            && self.free_f == o.free_f
            && self.s.vertices() == o.s.vertices()
            && self.s.edges() == o.s.edges()
            && self.s.faces() == o.s.faces()
    }
}

impl<S: MeshStorage> Mesh<S> {
    /// An empty mesh over the given storage (its previous contents are discarded).
    pub fn with_storage(mut s: S) -> Self {
        s.truncate(Counts::default());
        Self {
            s,
            live: Counts::default(),
            free_v: NONE,
            free_e: NONE,
            free_f: NONE,
        }
    }

    /// Removes everything; capacity is unchanged.
    pub fn clear(&mut self) {
        self.s.truncate(Counts::default());
        self.live = Counts::default();
        self.free_v = NONE;
        self.free_e = NONE;
        self.free_f = NONE;
    }

    /// Maximum number of each element (the storage capacity, clamped to [`MAX_ELEMENTS`]).
    pub fn capacity(&self) -> Counts {
        let c = self.s.capacity();
        Counts {
            vertices: c.vertices.min(MAX_ELEMENTS),
            edges: c.edges.min(MAX_ELEMENTS),
            faces: c.faces.min(MAX_ELEMENTS),
        }
    }

    /// Live element counts.
    pub fn len(&self) -> Counts {
        self.live
    }

    /// `true` when the mesh has no vertex (and therefore nothing else).
    pub fn is_empty(&self) -> bool {
        self.live.vertices == 0 && self.live.edges == 0 && self.live.faces == 0
    }

    /// Slots in use (live plus tombstoned): the high-water marks. Handles index below these.
    pub fn slots(&self) -> Counts {
        Counts {
            vertices: self.s.vertices().len(),
            edges: self.s.edges().len(),
            faces: self.s.faces().len(),
        }
    }

    /// Free slots of each kind (tombstones plus unused capacity).
    pub fn available(&self) -> Counts {
        let c = self.capacity();
        Counts {
            vertices: c.vertices.saturating_sub(self.live.vertices),
            edges: c.edges.saturating_sub(self.live.edges),
            faces: c.faces.saturating_sub(self.live.faces),
        }
    }

    /// `true` when no slot is tombstoned (handles are dense `0..len`).
    pub fn is_compact(&self) -> bool {
        self.slots() == self.live
    }

    /// Checks that `need` more elements fit, before any mutation.
    pub(crate) fn check_room(&self, need: Counts) -> Result<(), CapacityError> {
        let a = self.available();
        for (kind, n, av) in [
            (ElementKind::Vertex, need.vertices, a.vertices),
            (ElementKind::Edge, need.edges, a.edges),
            (ElementKind::Face, need.faces, a.faces),
        ] {
            if n > av {
                return Err(CapacityError {
                    kind,
                    needed: n,
                    available: av,
                });
            }
        }
        Ok(())
    }

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

    // ----- public navigation -----

    /// `true` if `v` is a live vertex of this mesh.
    pub fn contains_vertex(&self, v: VertexId) -> bool {
        self.v_live(v.0)
    }
    /// `true` if `e` is a live edge.
    pub fn contains_edge(&self, e: EdgeId) -> bool {
        self.e_live(e.0)
    }
    /// `true` if `h` is a live halfedge.
    pub fn contains_halfedge(&self, h: HalfedgeId) -> bool {
        self.h_live(h.0)
    }
    /// `true` if `f` is a live face.
    pub fn contains_face(&self, f: FaceId) -> bool {
        self.f_live(f.0)
    }

    /// Position of `v`; `None` for a dead or out-of-range vertex.
    pub fn position(&self, v: VertexId) -> Option<Vec3> {
        self.v_live(v.0).then(|| self.pos_raw(v.0))
    }

    /// Moves `v` to `p`. Refuses non-finite positions (the mesh stays unchanged).
    ///
    /// # Errors
    ///
    /// [`PositionError::Dead`] for a dead or out-of-range vertex, [`PositionError::NonFinite`]
    /// for a non-finite `p`; the mesh is unchanged.
    pub fn set_position(&mut self, v: VertexId, p: Vec3) -> Result<(), PositionError> {
        if !self.v_live(v.0) {
            return Err(PositionError::Dead);
        }
        if !p.is_finite() {
            return Err(PositionError::NonFinite);
        }
        self.set_pos(v.0, p);
        Ok(())
    }

    /// The stored outgoing halfedge of `v` (a boundary halfedge for a boundary vertex);
    /// `None` for an isolated or dead vertex.
    pub fn vertex_halfedge(&self, v: VertexId) -> Option<HalfedgeId> {
        let h = self.out_raw(v.0);
        (self.v_live(v.0) && h != NONE).then_some(HalfedgeId(h))
    }

    /// One halfedge of face `f` (the one from its first to its second vertex, see
    /// [`Mesh::face_vertices`]); `None` for a dead face.
    pub fn face_halfedge(&self, f: FaceId) -> Option<HalfedgeId> {
        self.f_live(f.0).then(|| HalfedgeId(self.fh(f.0)))
    }

    /// Next halfedge around the face (or boundary loop); `None` for a dead halfedge.
    pub fn next(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        self.h_live(h.0).then(|| HalfedgeId(self.next_raw(h.0)))
    }
    /// Previous halfedge around the face (or boundary loop).
    pub fn prev(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        self.h_live(h.0).then(|| HalfedgeId(self.prev_raw(h.0)))
    }
    /// Twin halfedge, if `h` is live (the arithmetic form is [`HalfedgeId::twin`]).
    pub fn twin(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        self.h_live(h.0).then(|| h.twin())
    }
    /// The vertex `h` points to.
    pub fn head(&self, h: HalfedgeId) -> Option<VertexId> {
        self.h_live(h.0).then(|| VertexId(self.head_raw(h.0)))
    }
    /// The vertex `h` starts from.
    pub fn tail(&self, h: HalfedgeId) -> Option<VertexId> {
        self.h_live(h.0).then(|| VertexId(self.tail_raw(h.0)))
    }
    /// The face on the left of `h`; `None` for a boundary or dead halfedge.
    pub fn face(&self, h: HalfedgeId) -> Option<FaceId> {
        let f = self.face_raw(h.0);
        (self.h_live(h.0) && f != NONE).then_some(FaceId(f))
    }
    /// `true` for a live halfedge without a face.
    pub fn is_boundary_halfedge(&self, h: HalfedgeId) -> bool {
        self.h_live(h.0) && self.face_raw(h.0) == NONE
    }
    /// `true` for a live edge with a face on one side only.
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.e_live(e.0)
            && (self.face_raw(e.0 << 1) == NONE || self.face_raw((e.0 << 1) | 1) == NONE)
    }
    /// `true` for a live vertex on the boundary (O(1), by the boundary convention).
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        let h = self.out_raw(v.0);
        self.v_live(v.0) && h != NONE && self.face_raw(h) == NONE
    }
    /// `true` for a live vertex with no incident edge.
    pub fn is_isolated(&self, v: VertexId) -> bool {
        self.v_live(v.0) && self.out_raw(v.0) == NONE
    }
    /// Endpoints `[tail, head]` of halfedge `2e`.
    pub fn edge_vertices(&self, e: EdgeId) -> Option<[VertexId; 2]> {
        self.e_live(e.0).then(|| {
            [
                VertexId(self.tail_raw(e.0 << 1)),
                VertexId(self.head_raw(e.0 << 1)),
            ]
        })
    }
    /// The face's corners in counter-clockwise order, starting at the tail of its stored
    /// halfedge. For a freshly built mesh this is exactly the input triangle.
    pub fn face_vertices(&self, f: FaceId) -> Option<[VertexId; 3]> {
        if !self.f_live(f.0) {
            return None;
        }
        let h = self.fh(f.0);
        let n = self.next_raw(h);
        Some([
            VertexId(self.tail_raw(h)),
            VertexId(self.head_raw(h)),
            VertexId(self.head_raw(n)),
        ])
    }

    /// Corner positions of a live face (internal; dead faces give zeros).
    pub(crate) fn face_positions_raw(&self, f: u32) -> [Vec3; 3] {
        let h = self.fh(f);
        let n = self.next_raw(h);
        [
            self.pos_raw(self.tail_raw(h)),
            self.pos_raw(self.head_raw(h)),
            self.pos_raw(self.head_raw(n)),
        ]
    }

    /// Unnormalised normal `(b − a) × (c − a)` of a live face (twice its area, pointing to the
    /// front); `None` for a dead face.
    pub fn face_normal_unnormalized(&self, f: FaceId) -> Option<Vec3> {
        self.f_live(f.0).then(|| {
            let [a, b, c] = self.face_positions_raw(f.0);
            (b - a).cross(c - a)
        })
    }

    // ----- compaction -----

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
