//! The cull across rays against each ray's own cull, lane by lane.

use super::*;
use crate::test_util::{Lcg, mixed_f32};
use crate::triangle::WatertightRay;
use glam::Vec3;

/// A direction with the awkward cases of the axis choice mixed in: ties between the
/// dominant components, zero components, a negative dominant one, tiny and huge lengths.
fn direction(r: &mut Lcg, s: &mut u64) -> Vec3 {
    let mut d = r.v(2.0);
    match (r.f() * 8.0) as u32 {
        0 => d.y = d.x,
        1 => d.z = -d.y.abs().max(d.x.abs()),
        2 => d.x = 0.0,
        3 => d = Vec3::new(0.0, 0.0, d.z),
        4 => d *= 1e-30,
        5 => d *= 1e30,
        6 => d = Vec3::new(mixed_f32(s, 0.3, 3.0), mixed_f32(s, 0.3, 3.0), d.z),
        _ => {}
    }
    d
}

/// Every lane of [`ShearedRays::certain_misses`] equals [`WatertightRay::certain_misses`] of
/// its ray (prepared by [`WatertightRay::of_valid`]), bit for bit, on valid rays in every
/// octant and axis order against groups of triangles that the rays cross, pass near and
/// miss: slivers, zero-area and NaN lanes, vertices at the origin, coordinates with
/// infinities, zeros and subnormals mixed in; half the cases a camera's rays, half rays from
/// anywhere. Both verdicts must occur often, so the comparison is not of empty masks.
#[test]
fn the_cull_across_rays_is_each_ray_s_own() {
    let mut r = Lcg(17);
    let mut s = 5u64;
    let (mut missed, mut kept) = (0usize, 0usize);
    for case in 0..6_000 {
        let centre = r.v(8.0);
        // Odd cases: a camera's rays (one origin, nearby directions: mostly one axis order
        // in every lane); even ones: rays from anywhere (mixed axis orders).
        let eye = centre + r.v(20.0);
        let rays: [Ray; RAY_LANES] = core::array::from_fn(|_| {
            let origin = if case % 2 == 1 {
                eye
            } else {
                centre + r.v(20.0)
            };
            let aim = centre + r.v(2.0);
            let d = if case % 3 == 0 {
                direction(&mut r, &mut s)
            } else {
                aim - origin
            };
            Ray::new(origin, d)
        });
        let mut lanes = TriangleLanes::EMPTY;
        for (lane, ray) in rays.iter().enumerate().take(LANES) {
            let mut tri = [0; 3].map(|_| (centre + r.v(3.0)).to_array());
            match (r.f() * 10.0) as u32 {
                0 => tri[2] = tri[0],
                1 => tri[1] = ray.origin.to_array(),
                2 => tri[0] = [0; 3].map(|_| mixed_f32(&mut s, 0.5, 4.0)),
                3 => continue,
                _ => {}
            }
            lanes.set(lane, &tri);
        }
        let across = ShearedRays::new(&rays).certain_misses(&lanes);
        for (i, ray) in rays.iter().enumerate() {
            if !ray.is_valid() {
                continue;
            }
            let own = WatertightRay::of_valid(ray).certain_misses(ray.origin, &lanes);
            assert_eq!(across[i], own, "case {case}, ray {i}: {ray:?} {lanes:?}");
            missed += own.count_ones() as usize;
            kept += (LANES as u32 - own.count_ones()) as usize;
        }
    }
    assert!(
        missed > 100_000 && kept > 20_000,
        "{missed} missed, {kept} kept"
    );
}
