//! Several triangles side by side (structure of arrays), so that a test can reject many of
//! them with one pass of vector instructions ([`super::TriangleIntersector::certain_misses`]).

/// Triangles per [`TriangleLanes`]: 4, one SSE / NEON register per coordinate (and half an
/// AVX2 one; BVH leaves hold about three triangles, so wider lanes would mostly be empty).
pub const LANES: usize = 4;

/// Up to [`LANES`] triangles, lane by lane: `v[vertex][axis][lane]`. Lanes at and after
/// `count` hold NaN and mean nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleLanes {
    /// The coordinates: vertex (`v0`, `v1`, `v2`), axis, lane.
    pub v: [[[f32; LANES]; 3]; 3],
    /// Lanes in use, `0..=LANES`.
    pub count: usize,
}

impl TriangleLanes {
    /// The first [`LANES`] triangles of `tris` (vertex, then axis), in order; the rest are
    /// ignored.
    #[inline(always)]
    #[must_use]
    pub fn gather<'a>(tris: impl IntoIterator<Item = &'a [[f32; 3]; 3]>) -> Self {
        let mut v = [[[f32::NAN; LANES]; 3]; 3];
        let mut count = 0;
        for (lane, tri) in tris.into_iter().take(LANES).enumerate() {
            for (vertex, p) in tri.iter().enumerate() {
                for (axis, &c) in p.iter().enumerate() {
                    v[vertex][axis][lane] = c;
                }
            }
            count = lane + 1;
        }
        Self { v, count }
    }

    /// Bit `i` set for every lane `i < count`.
    #[inline(always)]
    #[must_use]
    pub fn used(&self) -> u32 {
        (1u32 << self.count.min(LANES)) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gather_transposes_and_counts() {
        let a = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]];
        let b = [[-1.0, -2.0, -3.0], [-4.0, -5.0, -6.0], [-7.0, -8.0, -9.0]];
        let l = TriangleLanes::gather([&a, &b]);
        assert_eq!(l.count, 2);
        assert_eq!(l.used(), 0b11);
        assert_eq!(l.v[1][2][0], 6.0);
        assert_eq!(l.v[2][0][1], -7.0);
        assert!(l.v[0][0][2].is_nan());
        let five = [a; 5];
        let l = TriangleLanes::gather(five.iter());
        assert_eq!((l.count, l.used()), (4, 0b1111));
        assert_eq!(TriangleLanes::gather([]).used(), 0);
    }
}
