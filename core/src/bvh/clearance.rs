//! The clearance query: how far a body (a drone's mesh) can move along each vertex normal
//! before it meets the scene (a hangar's walls).

use super::node::BvhNode;
use super::primitive::TriangleMesh;
use super::{Bvh, BvhError};
use crate::float::sqrt;
use crate::ray::Ray;
use crate::triangle::TriangleIntersector;
use glam::Vec3;

impl<N, I> Bvh<N, I>
where
    N: AsRef<[BvhNode]>,
    I: AsRef<[u32]>,
{
    /// For each point `points[i]` casts the ray `points[i] + t·normals[i]`, `t ∈ (0, ∞]`,
    /// against the tree and writes the distance to the nearest hit — `t·|normals[i]|`, in world
    /// units, so normals need not be unit length — into `out[i]` (`+∞` when nothing is hit or
    /// the ray is invalid, e.g. a zero or NaN normal). Returns the minimum over all points
    /// (`+∞` for none).
    ///
    /// `intersect(prim, ray)` returns the hit `t` of one primitive in `(t_min, t_max]`.
    /// Typical use: area-weighted vertex normals of the moving body (from the half-edge mesh)
    /// against a BVH of the environment; the body itself is not in the tree.
    ///
    /// # Errors
    ///
    /// Nothing written: [`BvhError::LengthMismatch`] when `normals` or `out` do not
    /// have `points.len()` entries.
    pub fn clearance(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        out: &mut [f32],
        mut intersect: impl FnMut(u32, &Ray) -> Option<f32>,
    ) -> Result<f32, BvhError> {
        self.clearance_with(points, normals, out, |bvh, ray| {
            bvh.closest_hit(ray, |p, r| intersect(p, r).map(|t| (t, t)), None)
                .map(|(_, t)| t)
        })
    }

    /// [`Bvh::clearance`] against a triangle mesh with the intersector `isect`.
    ///
    /// # Errors
    ///
    /// As [`Bvh::clearance`]: [`BvhError::LengthMismatch`], nothing written.
    pub fn clearance_triangles<T: TriangleIntersector>(
        &self,
        mesh: &TriangleMesh<'_>,
        isect: &T,
        points: &[Vec3],
        normals: &[Vec3],
        out: &mut [f32],
    ) -> Result<f32, BvhError> {
        self.clearance_with(points, normals, out, |bvh, ray| {
            bvh.closest_hit_triangles(mesh, isect, ray, None)
                .map(|(_, h)| h.t)
        })
    }

    fn clearance_with(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        out: &mut [f32],
        mut cast: impl FnMut(&Self, &Ray) -> Option<f32>,
    ) -> Result<f32, BvhError> {
        clearance_loop(points, normals, out, |ray| cast(self, ray))
    }
}

/// The clearance loop shared by the binary and the wide tree: `cast` gives the hit `t` of the
/// ray `points[i] + t·normals[i]`; writes `t·|normals[i]|` (or `+∞`) into `out[i]` and returns
/// the minimum. Errors (nothing written): [`BvhError::LengthMismatch`].
pub(super) fn clearance_loop(
    points: &[Vec3],
    normals: &[Vec3],
    out: &mut [f32],
    mut cast: impl FnMut(&Ray) -> Option<f32>,
) -> Result<f32, BvhError> {
    for len in [normals.len(), out.len()] {
        if len != points.len() {
            return Err(BvhError::LengthMismatch {
                expected: points.len(),
                found: len,
            });
        }
    }
    let mut min = f32::INFINITY;
    for ((&p, &n), o) in points.iter().zip(normals).zip(out.iter_mut()) {
        let dist = match cast(&Ray::new(p, n)) {
            Some(t) => t * sqrt(n.length_squared()),
            None => f32::INFINITY,
        };
        *o = dist;
        min = min.min(dist);
    }
    Ok(min)
}
