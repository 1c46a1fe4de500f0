//! Export back to an indexed triangle list.

use glam::Vec3;

use super::error::ExportError;
use super::mesh::Mesh;
use super::storage::MeshStorage;

impl<S: MeshStorage> Mesh<S> {
    /// Writes the mesh as an indexed triangle list into caller buffers and returns
    /// `(positions written, triangles written)`.
    ///
    /// * Positions: one per vertex **slot** (`slots().vertices`), so triangle indices are
    ///   exactly the `VertexId`s. Tombstoned slots are written as unreferenced `(0, 0, 0)`
    ///   entries; call [`Mesh::compact`] first for a list without them. Isolated vertices
    ///   are written like any other.
    /// * Triangles: one per live face in face-slot order, corners as
    ///   [`Mesh::face_vertices`] (counter-clockwise). A freshly built mesh round-trips to its
    ///   input exactly.
    ///
    /// # Errors
    /// [`ExportError::BufferTooSmall`] (nothing written) if either buffer is too short.
    pub fn export(
        &self,
        positions: &mut [Vec3],
        triangles: &mut [[u32; 3]],
    ) -> Result<(usize, usize), ExportError> {
        let np = self.s.vertices().len();
        let nt = self.live.faces;
        if positions.len() < np || triangles.len() < nt {
            return Err(ExportError::BufferTooSmall {
                positions: np,
                triangles: nt,
            });
        }
        for (out, r) in positions.iter_mut().zip(self.s.vertices()) {
            *out = if self.v_live_rec(r) {
                r.pos
            } else {
                Vec3::ZERO
            };
        }
        let mut t = triangles.iter_mut();
        for f in 0..self.s.faces().len() as u32 {
            if let Some(vs) = self.face_vertices(super::FaceId(f))
                && let Some(out) = t.next()
            {
                *out = vs.map(|v| v.0);
            }
        }
        Ok((np, nt))
    }

    #[inline]
    fn v_live_rec(&self, r: &super::storage::VertexRec) -> bool {
        r.out == super::handles::NONE || r.out < super::storage::DEAD_BIT
    }
}
