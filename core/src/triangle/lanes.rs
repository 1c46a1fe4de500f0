//! Several triangles side by side (structure of arrays), so that a test can reject many of
//! them with one pass of vector instructions ([`super::TriangleIntersector::certain_misses`]).

/// Triangles per [`TriangleLanes`]: 4, one SSE / NEON register per coordinate (and half an
/// AVX2 one; BVH leaves hold about three triangles, so wider lanes would mostly be empty).
pub const LANES: usize = 4;

/// [`LANES`] triangles, lane by lane: `v[vertex][axis][lane]`. An unused lane holds NaN
/// coordinates (never hit by any test).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct TriangleLanes {
    /// The coordinates: vertex (`v0`, `v1`, `v2`), axis, lane.
    pub v: [[[f32; LANES]; 3]; 3],
}

impl TriangleLanes {
    /// Every lane unused (NaN).
    pub const EMPTY: Self = Self {
        v: [[[f32::NAN; LANES]; 3]; 3],
    };

    /// The first [`LANES`] triangles of `tris` (vertex, then axis), in order, the other lanes
    /// unused; triangles after the first [`LANES`] are ignored.
    #[must_use]
    pub fn from_triangles(tris: &[[[f32; 3]; 3]]) -> Self {
        let mut lanes = Self::EMPTY;
        for (lane, tri) in tris.iter().take(LANES).enumerate() {
            lanes.set(lane, tri);
        }
        lanes
    }

    /// Lane `lane`'s triangle (vertex, then axis); `None` for `lane ≥ LANES`.
    #[inline(always)]
    #[must_use]
    pub fn get(&self, lane: usize) -> Option<[[f32; 3]; 3]> {
        (lane < LANES).then(|| self.v.map(|p| p.map(|axis| axis[lane & (LANES - 1)])))
    }

    /// Writes `tri` into lane `lane` (nothing for `lane ≥ LANES`).
    #[inline]
    pub fn set(&mut self, lane: usize, tri: &[[f32; 3]; 3]) {
        if lane < LANES {
            for (vertex, p) in tri.iter().enumerate() {
                for (axis, &c) in p.iter().enumerate() {
                    self.v[vertex][axis][lane] = c;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_transpose_and_round_trip() {
        let a = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]];
        let b = [[-1.0, -2.0, -3.0], [-4.0, -5.0, -6.0], [-7.0, -8.0, -9.0]];
        let l = TriangleLanes::from_triangles(&[a, b]);
        assert_eq!(l.v[1][2][0], 6.0);
        assert_eq!(l.v[2][0][1], -7.0);
        assert!(l.v[0][0][2].is_nan() && l.v[2][2][3].is_nan());
        assert_eq!(l.get(0), Some(a));
        assert_eq!(l.get(1), Some(b));
        assert!(l.get(3).is_some_and(|t| t[1][1].is_nan()));
        assert_eq!(l.get(4), None);
        let l = TriangleLanes::from_triangles(&[a, a, a, a, b]);
        assert_eq!(l.get(3), Some(a));
    }
}
