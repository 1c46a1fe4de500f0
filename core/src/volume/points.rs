//! The point sets a bounding volume is fitted to: a slice of points or the vertices a
//! triangle mesh references.

use super::VolumeError;
use crate::error::{InputElement, NonFiniteError};
use crate::mesh::TriangleMesh;
use glam::{DVec3, Vec3};

/// Relative padding of every fitted size (radius, half-extent), applied in `f64` before the
/// size is rounded **up** to `f32`: `gamma_f64(8)`, unitless.
///
/// Why: a fit measures each point against the volume it is about to store (the centre,
/// axes and endpoints already rounded to `f32`) in `f64`. Every such measurement is a
/// subtraction of two `f32` values, at most three products and sums, and a square root:
/// at most 8 roundings, relative error `≤ gamma_f64(8)` of the sum of the absolute values of
/// its terms (which is what the padding is applied to). Padding by that bound and rounding
/// up to `f32` (`next_up` when the nearest `f32` is below) makes the stored volume contain
/// every input point **exactly** (checked in `f64` by the tests). Cost: nothing visible in
/// `f32` (`gamma_f64(8)` ≈ 8.9e-16).
pub const FIT_PAD_REL: f64 = crate::float::gamma_f64(8);

/// A set of points a volume can be fitted to, visited in a fixed order. Implemented for a
/// slice of points and for [`TriangleMesh`] (every corner of every triangle: a vertex shared
/// by `k` triangles counts `k` times, which weights the PCA fits by use; unreferenced
/// positions are ignored).
pub trait PointSet {
    /// Number of points (for a mesh, `3 × triangles`).
    fn point_count(&self) -> usize;
    /// Point `index`; `None` when it is out of range or (mesh) refers to a missing vertex.
    fn point(&self, index: usize) -> Option<Vec3>;
    /// The first defect of the set, checked before any fit: no points, a non-finite
    /// coordinate, a vertex index out of range.
    ///
    /// # Errors
    ///
    /// [`VolumeError::Empty`], [`VolumeError::NonFinite`],
    /// [`VolumeError::VertexIndexOutOfRange`].
    fn validate(&self) -> Result<(), VolumeError> {
        if self.point_count() == 0 {
            return Err(VolumeError::Empty);
        }
        for index in 0..self.point_count() {
            match self.point(index) {
                None => {
                    return Err(VolumeError::VertexIndexOutOfRange {
                        triangle: index / 3,
                    });
                }
                Some(p) if !p.is_finite() => {
                    return Err(VolumeError::NonFinite(NonFiniteError::new(
                        InputElement::Point,
                        index,
                    )));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }
}

impl PointSet for [Vec3] {
    #[inline]
    fn point_count(&self) -> usize {
        self.len()
    }
    #[inline]
    fn point(&self, index: usize) -> Option<Vec3> {
        self.get(index).copied()
    }
}

impl PointSet for TriangleMesh<'_> {
    #[inline]
    fn point_count(&self) -> usize {
        self.triangles.len().saturating_mul(3)
    }
    #[inline]
    fn point(&self, index: usize) -> Option<Vec3> {
        let t = self.triangles.get(index / 3)?;
        let v = *t.get(index % 3)?;
        self.positions.get(v as usize).copied()
    }
}

/// The points of a validated set in `f64` (exact: every `f32` is an `f64`); a missing point
/// (impossible after [`PointSet::validate`]) is skipped.
pub(crate) fn points_f64<P: PointSet + ?Sized>(set: &P) -> impl Iterator<Item = DVec3> + '_ {
    (0..set.point_count()).filter_map(move |i| set.point(i).map(|p| p.as_dvec3()))
}

/// The mean and the covariance matrix (row-major, symmetric) of a validated, non-empty set,
/// in `f64`, the covariance about the mean (two passes, so no cancellation).
pub(crate) fn mean_and_covariance<P: PointSet + ?Sized>(set: &P) -> (DVec3, [[f64; 3]; 3]) {
    let n = set.point_count().max(1) as f64;
    let mean = points_f64(set).fold(DVec3::ZERO, |a, p| a + p / n);
    let mut c = [[0.0; 3]; 3];
    for p in points_f64(set) {
        let d = (p - mean).to_array();
        for (i, row) in c.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += d[i] * d[j] / n;
            }
        }
    }
    (mean, c)
}

/// `x` padded by [`FIT_PAD_REL`] of `scale` and rounded up to the nearest `f32` at or above
/// it; `None` when that is not finite (the volume would not fit in `f32`).
pub(crate) fn round_up_padded(x: f64, scale: f64) -> Option<f32> {
    let padded = x + FIT_PAD_REL * scale;
    let r = padded as f32;
    let r = if (r as f64) < padded { r.next_up() } else { r };
    if r.is_finite() {
        Some(r.max(0.0))
    } else {
        None
    }
}
