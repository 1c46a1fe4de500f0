//! Several triangles side by side (structure of arrays), so that a test can reject many of
//! them with one pass of vector instructions ([`super::TriangleIntersector::certain_misses`]).

/// Triangles per [`TriangleLanes`]: 4, one SSE / NEON register per coordinate (and half an
/// AVX2 one; BVH leaves hold about three triangles, so wider lanes would mostly be empty).
pub const LANES: usize = 4;

/// The lane mask of two groups side by side: `first`'s lanes in bits 0–3, `second`'s in bits
/// 4–7 (each mask's bits above lane 3 must be clear).
#[inline(always)]
#[must_use]
pub const fn pair_mask(first: u32, second: u32) -> u32 {
    first | second << LANES
}

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
        if lane >= LANES {
            return None;
        }
        // Written out: `array::map` is not always inlined, and this is on the hit path.
        let l = lane & (LANES - 1);
        let v = &self.v;
        Some([
            [v[0][0][l], v[0][1][l], v[0][2][l]],
            [v[1][0][l], v[1][1][l], v[1][2][l]],
            [v[2][0][l], v[2][1][l], v[2][2][l]],
        ])
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

/// [`TriangleLanes::EMPTY`]: every lane unused.
impl Default for TriangleLanes {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::Ray;
    use crate::sealed::Inside;
    use crate::triangle::{
        MollerTrumbore, TriangleIntersector, Watertight, WatertightF32, WatertightRay,
    };
    use glam::Vec3;

    /// `TriangleLanes::default()` is `EMPTY`: every coordinate of every lane NaN, so every
    /// lane unused (never hit, never culled wrongly).
    #[test]
    fn default_lanes_are_empty() {
        let d = TriangleLanes::default();
        assert!(d.v.as_flattened().as_flattened().iter().all(|c| c.is_nan()));
        for lane in 0..LANES {
            assert!(
                d.get(lane)
                    .unwrap()
                    .as_flattened()
                    .iter()
                    .all(|c| c.is_nan())
            );
        }
        let bits = |l: &TriangleLanes| l.v.map(|a| a.map(|b| b.map(f32::to_bits)));
        assert_eq!(bits(&d), bits(&TriangleLanes::EMPTY));
    }

    /// The lane cull against the scalar tests (the oracle is each variant's own one-triangle
    /// `intersect`, which the cull must never contradict): rays aimed at vertices, at points
    /// of edges and at random points, around quads split on their diagonal (so lanes share
    /// edges), plus NaN and huge lanes, for every variant with a cull. Every lane the cull
    /// reports must be a scalar miss, and the cull must report most misses (else it is not
    /// doing its job).
    #[test]
    fn lane_cull_reports_only_scalar_misses() {
        use crate::test_util::{lcg, unit_vec};
        let mut s = 0x5eed_u64;
        const NAMES: [&str; 4] = [
            "watertight",
            "watertight-f32",
            "moller-trumbore",
            "moller-trumbore-noeps",
        ];
        let (mut culled, mut misses) = ([0usize; 4], [0usize; 4]);
        for case in 0..4000 {
            let scale = [1e-3f32, 1.0, 1e4][case % 3];
            let p =
                |s: &mut u64| Vec3::new(lcg(s) - 0.5, lcg(s) - 0.5, lcg(s) - 0.5) * (2.0 * scale);
            let (a, b, c, d) = (p(&mut s), p(&mut s), p(&mut s), p(&mut s));
            let mut tris = [[a, b, c], [a, c, d], [b, d, c], [a, b, d]];
            if case % 50 == 0 {
                tris[3] = [Vec3::NAN, b, c];
            }
            if case % 70 == 0 {
                tris[2] = [Vec3::splat(3e38), b, Vec3::new(-3e38, 1.0, 2.0)];
            }
            let target = match case % 4 {
                0 => a,
                1 => a + (c - a) * lcg(&mut s),
                2 => b + (d - b) * 0.5,
                _ => p(&mut s),
            };
            let origin = target - unit_vec(&mut s) * (3.0 * scale);
            let ray = Ray::new(origin, target - origin);
            let records = tris.map(|t| [t[0].to_array(), t[1].to_array(), t[2].to_array()]);
            let lanes = TriangleLanes::from_triangles(&records);
            let wt = WatertightRay::new(&ray).unwrap();
            two_group_cull_equals_two_culls(&wt, &ray, &lanes, &records);
            let variants = [
                (
                    Watertight.certain_misses(Inside(()), &wt, &ray, &lanes),
                    tris.map(|t| Watertight.intersect(&ray, &t).is_some()),
                ),
                (
                    WatertightF32.certain_misses(Inside(()), &wt, &ray, &lanes),
                    tris.map(|t| WatertightF32.intersect(&ray, &t).is_some()),
                ),
                (
                    MollerTrumbore::CLASSIC.certain_misses(Inside(()), &(), &ray, &lanes),
                    tris.map(|t| MollerTrumbore::CLASSIC.intersect(&ray, &t).is_some()),
                ),
                (
                    MollerTrumbore::NO_EPSILON.certain_misses(Inside(()), &(), &ray, &lanes),
                    tris.map(|t| MollerTrumbore::NO_EPSILON.intersect(&ray, &t).is_some()),
                ),
            ];
            for (k, (mask, scalar)) in variants.iter().enumerate() {
                for (lane, &hit) in scalar.iter().enumerate() {
                    let reported = mask >> lane & 1 == 1;
                    assert!(
                        !(reported && hit),
                        "{}: case {case} lane {lane} culled a hit",
                        NAMES[k]
                    );
                    culled[k] += usize::from(reported);
                    misses[k] += usize::from(!hit);
                }
            }
        }
        for k in 0..4 {
            let (c, m) = (culled[k], misses[k]);
            assert!(c * 10 >= m * 9, "{}: culled {c} of {m} misses", NAMES[k]);
        }
    }

    /// The two-group cull ([`TriangleIntersector::certain_misses2`]) at every SIMD level this
    /// CPU has equals the one-group cull of each group (the second group: the same triangles
    /// in reverse lane order, with an unused lane), for the watertight family's own kernel and
    /// for the trait's default (Möller–Trumbore).
    fn two_group_cull_equals_two_culls(
        wt: &WatertightRay,
        ray: &Ray,
        first: &TriangleLanes,
        records: &[[[f32; 3]; 3]; 4],
    ) {
        use crate::simd_level::{Portable, SimdLevel};
        let reversed = [records[3], records[2], records[1]];
        let second = TriangleLanes::from_triangles(&reversed);
        fn check<L: SimdLevel + core::fmt::Debug>(
            level: L,
            wt: &WatertightRay,
            ray: &Ray,
            first: &TriangleLanes,
            second: &TriangleLanes,
        ) {
            let want = Watertight.certain_misses(Inside(()), wt, ray, first)
                | Watertight.certain_misses(Inside(()), wt, ray, second) << LANES;
            assert_eq!(
                Watertight.certain_misses2(Inside(()), level, wt, ray, first, second),
                want,
                "{level:?} {ray:?}"
            );
            let mt = MollerTrumbore::NO_EPSILON;
            let want = mt.certain_misses(Inside(()), &(), ray, first)
                | mt.certain_misses(Inside(()), &(), ray, second) << 4;
            assert_eq!(
                mt.certain_misses2(Inside(()), level, &(), ray, first, second),
                want
            );
        }
        check(Portable, wt, ray, first, &second);
        #[cfg(target_arch = "x86_64")]
        if let Some(level) = crate::test_util::avx2_or_skip(
            "triangle::lanes::tests::lane_cull_reports_only_scalar_misses",
        ) {
            check(level, wt, ray, first, &second);
        }
    }

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
