//! Uniform Laplacian smoothing ("diffuse").

use glam::{DVec3, Vec3};

use super::error::DiffuseError;
use super::handles::{NONE, VertexId};
use super::mesh::Mesh;
use super::storage::MeshStorage;

/// What [`Mesh::diffuse`] does with boundary vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DiffuseBoundary {
    /// Boundary vertices move like interior ones, towards the mean of all their neighbours
    /// (the plain formula; open surfaces shrink at their rims).
    #[default]
    Free,
    /// Boundary vertices stay where they are (pmp's smoothing default).
    Fixed,
}

impl<S: MeshStorage> Mesh<S> {
    /// Uniform Laplacian `L(v) = (1/n)·Σ x_j − x_v` over the `n` neighbours of `v`, from the
    /// current positions. `Some(0)` for an isolated vertex, `None` for a dead one. Summed and
    /// divided in `f64`, rounded to `f32` once: the sum of many neighbours near the largest
    /// `f32` coordinates does not overflow; the result (a centroid less a position) is finite
    /// whenever every coordinate involved is at most `f32::MAX / 2` in magnitude.
    #[must_use]
    pub fn laplacian(&self, v: VertexId) -> Option<Vec3> {
        if !self.v_live(v.0) {
            return None;
        }
        let x = self.pos_raw(v.0);
        let (mut sum, mut n) = (DVec3::ZERO, 0u32);
        for w in self.vertex_neighbors(v) {
            sum += self.pos_raw(w.0).as_dvec3();
            n += 1;
        }
        Some(if n == 0 {
            Vec3::ZERO
        } else {
            (sum / f64::from(n) - x.as_dvec3()).as_vec3()
        })
    }

    /// Moves one vertex: `x' = x + k·L(v)` (units of `k`: dimensionless; `k = 1` moves the
    /// vertex to its neighbours' centroid). Returns the new position. Evaluated as written,
    /// `k·L` and then the sum in `f32`, with `L` rounded to `f32` once ([`Self::laplacian`]).
    ///
    /// # Errors
    /// `Dead` for a dead vertex; `NonFinite` (mesh unchanged) if `k` or the result is not
    /// finite, including when `L` or `k·L` exceeds `f32::MAX` though `x + k·L` would not.
    pub fn diffuse_vertex(&mut self, v: VertexId, k: f32) -> Result<Vec3, DiffuseError> {
        let l = self.laplacian(v).ok_or(DiffuseError::Dead)?;
        let p = self.pos_raw(v.0) + k * l;
        if !k.is_finite() || !p.is_finite() {
            return Err(DiffuseError::NonFinite);
        }
        self.set_pos(v.0, p);
        Ok(p)
    }

    /// One Jacobi smoothing step over the whole mesh: every vertex moves by `k·L(v)`, all
    /// computed from the old positions, each as [`Self::diffuse_vertex`] computes it.
    /// `scratch` needs `slots().vertices` entries (contents ignored). Isolated vertices stay
    /// put; boundary vertices per `boundary`.
    ///
    /// # Errors
    /// `ScratchTooSmall`, or `NonFinite` if `k` or any new position is not finite; the mesh is
    /// unchanged on error.
    pub fn diffuse(
        &mut self,
        k: f32,
        boundary: DiffuseBoundary,
        scratch: &mut [Vec3],
    ) -> Result<(), DiffuseError> {
        let n = self.s.vertices().len();
        if scratch.len() < n {
            return Err(DiffuseError::ScratchTooSmall { needed: n });
        }
        if !k.is_finite() {
            return Err(DiffuseError::NonFinite);
        }
        for (v, out) in scratch.iter_mut().enumerate().take(n) {
            let v = v as u32;
            let x = self.pos_raw(v);
            let fixed = boundary == DiffuseBoundary::Fixed
                && self.out_raw(v) != NONE
                && self.face_raw(self.out_raw(v)) == NONE;
            *out = if !self.v_live(v) || fixed {
                x
            } else {
                x + k * self.laplacian(VertexId(v)).unwrap_or(Vec3::ZERO)
            };
            if !out.is_finite() {
                return Err(DiffuseError::NonFinite);
            }
        }
        for (v, p) in scratch.iter().enumerate().take(n) {
            if self.v_live(v as u32) {
                self.set_pos(v as u32, *p);
            }
        }
        Ok(())
    }
}
