//! Fixed-capacity half-edge triangle meshes: no heap, no panics.
//!
//! * [`Mesh`] over [`MeshStorage`]: [`HalfedgeMesh<V, E, F>`] keeps const-generic
//!   `heapless::Vec` arenas inline; [`SliceMesh`] uses caller-provided slices (the path for
//!   large meshes, which would overflow the stack inline). Bytes per element: vertex 16,
//!   halfedge 16, edge 32 (its two halfedges; twins are implicit, `twin(h) = h ^ 1`), face 4;
//!   see [`storage`].
//! * Typed `Copy` handles [`VertexId`], [`EdgeId`], [`FaceId`], [`HalfedgeId`] (u32 slots).
//! * [`Mesh::build`] from positions + triangles (twins matched by sorting in caller
//!   scratch), [`Mesh::export`] back, [`Mesh::validate`] for every invariant.
//! * Traversal ([`traverse`]), uniform Laplacian [`Mesh::diffuse`], [`Mesh::flip_edge`],
//!   [`Mesh::split_edge`], [`Mesh::collapse_edge`], [`Mesh::subdivide_loop`],
//!   [`Mesh::compact`].
//!
//! Conventions (boundary halfedges, outgoing vertex halfedges, isolated vertices) are
//! documented on [`Mesh`]. Every mutating operation checks legality and capacity first and
//! leaves the mesh bit-for-bit unchanged when it refuses, except [`Mesh::build`], which
//! replaces the whole mesh and leaves it empty on any error.
//!
//! ```
//! use halfray_core::halfedge::{HalfedgeMesh, build_scratch_len};
//! use halfray_core::Vec3;
//! let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
//! let t = [[0, 1, 2]];
//! let mut m = HalfedgeMesh::<3, 3, 1>::new();
//! let mut scratch = [0u32; build_scratch_len(1)];
//! m.build(&p, &t, &mut scratch).unwrap();
//! assert!(m.validate().is_ok());
//! assert_eq!(m.len().edges, 3);
//! ```

mod build;
mod collapse;
mod error;
mod export;
mod flip;
mod handles;
mod mesh;
pub mod normals;
mod smooth;
mod split;
pub mod storage;
mod subdivide;
pub mod traverse;
mod validate;

#[cfg(test)]
mod tests;

pub use build::build_scratch_len;
pub use collapse::CollapseAt;
pub use error::{
    BuildError, CapacityError, CollapseError, Culprit, DiffuseError, ElementKind, ExportError,
    FlipError, InvariantError, PositionError, SplitError, SubdivideError,
};
pub use handles::{EdgeId, FaceId, HalfedgeId, VertexId};
pub use mesh::{HalfedgeMesh, Mesh, Moved, SliceMesh};
pub use smooth::DiffuseBoundary;
pub use storage::{
    Counts, EdgeRec, FaceRec, HalfedgeRec, InlineStorage, MAX_ELEMENTS, MeshStorage, SliceStorage,
    VertexRec,
};
pub use subdivide::{LoopWeights, loop_beta};
