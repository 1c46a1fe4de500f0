//! The arena: [`Mesh`], its storage and counts. Record access (`records`), allocation with
//! intrusive free lists (`alloc`), navigation (`navigate`) and [`Mesh::compact`] (`compact`)
//! are in the submodules.

mod alloc;
mod compact;
mod navigate;
mod records;

use core::fmt;

use super::error::{CapacityError, ElementKind};
use super::handles::{EdgeId, FaceId, NONE, VertexId};
use super::storage::{
    Counts, EdgeRec, FaceRec, InlineStorage, MAX_ELEMENTS, MeshStorage, SliceStorage, VertexRec,
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
    #[must_use]
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
    #[must_use]
    pub fn capacity(&self) -> Counts {
        let c = self.s.capacity();
        Counts {
            vertices: c.vertices.min(MAX_ELEMENTS),
            edges: c.edges.min(MAX_ELEMENTS),
            faces: c.faces.min(MAX_ELEMENTS),
        }
    }

    /// Live element counts.
    #[must_use]
    pub fn len(&self) -> Counts {
        self.live
    }

    /// `true` when the mesh has no vertex (and therefore nothing else).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.live.vertices == 0 && self.live.edges == 0 && self.live.faces == 0
    }

    /// Slots in use (live plus tombstoned): the high-water marks. Handles index below these.
    #[must_use]
    pub fn slots(&self) -> Counts {
        Counts {
            vertices: self.s.vertices().len(),
            edges: self.s.edges().len(),
            faces: self.s.faces().len(),
        }
    }

    /// Free slots of each kind (tombstones plus unused capacity).
    #[must_use]
    pub fn available(&self) -> Counts {
        let c = self.capacity();
        Counts {
            vertices: c.vertices.saturating_sub(self.live.vertices),
            edges: c.edges.saturating_sub(self.live.edges),
            faces: c.faces.saturating_sub(self.live.faces),
        }
    }

    /// `true` when no slot is tombstoned (handles are dense `0..len`).
    #[must_use]
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
                    storage: crate::error::Storage::MeshSlots(kind),
                    needed: n,
                    available: av,
                });
            }
        }
        Ok(())
    }
}
