//! Embree's packet API: `rtcIntersect8` and `rtcIntersect16`, closest hits of 8 or 16 rays per
//! call, and `rtcOccluded8` and `rtcOccluded16`, occlusion, for timing Embree's own ray batches
//! beside `rtcIntersect1` and `rtcOccluded1`.
//!
//! The packets have the Embree 4.4 layout of `RTCRayHit8` / `RTCRayHit16` (structure of
//! arrays: the `RTCRayN` fields, then the `RTCHitN` fields, `instPrimID` included, see
//! [`super::layout`]), aligned to 64 bytes (Embree needs 32 for 8 rays, 64 for 16), followed by
//! guard words. The valid mask (`-1` per traced lane) is aligned the same way. Rays Embree
//! cannot handle ([`ray_is_valid`]) and the lanes past a short last packet are masked off.

use super::{EmbreeHit, EmbreeScene, GUARD_WORDS, INVALID_ID, SENTINEL, ray_is_valid};
use halfray_core::Ray;

/// `RTCRayHitN` of Embree 4.4 (`RTC_MAX_INSTANCE_LEVEL_COUNT = 1`, instance arrays) for `N`
/// rays, followed by guard words.
#[repr(C, align(64))]
pub(crate) struct RayHitN<const N: usize> {
    org_x: [f32; N],
    org_y: [f32; N],
    org_z: [f32; N],
    tnear: [f32; N],
    dir_x: [f32; N],
    dir_y: [f32; N],
    dir_z: [f32; N],
    time: [f32; N],
    tfar: [f32; N],
    mask: [u32; N],
    id: [u32; N],
    flags: [u32; N],
    ng_x: [f32; N],
    ng_y: [f32; N],
    ng_z: [f32; N],
    u: [f32; N],
    v: [f32; N],
    prim_id: [u32; N],
    geom_id: [u32; N],
    inst_id: [u32; N],
    inst_prim_id: [u32; N],
    guard: [u32; GUARD_WORDS],
}

/// The valid mask of a packet: `-1` for a lane to trace, `0` for one to skip.
#[repr(C, align(64))]
struct Valid<const N: usize>([i32; N]);

// Compile-time proof of the layout (the C structs: 12 ray arrays, then 9 hit arrays).
const _: () = {
    use std::mem::{align_of, offset_of};
    assert!(offset_of!(RayHitN<8>, ng_x) == 12 * 32 && offset_of!(RayHitN<8>, guard) == 21 * 32);
    assert!(offset_of!(RayHitN<16>, ng_x) == 12 * 64);
    assert!(offset_of!(RayHitN<16>, guard) == 21 * 64);
    assert!(align_of::<RayHitN<8>>() >= 32 && align_of::<RayHitN<16>>() >= 64);
    assert!(align_of::<Valid<16>>() >= 64);
};

impl<const N: usize> RayHitN<N> {
    /// A packet of `rays` (at most `N`; the rest of the lanes masked off), every hit ID
    /// invalid, with its valid mask.
    fn new(rays: &[Ray]) -> (Box<Self>, Valid<N>) {
        let mut valid = Valid([0; N]);
        let mut p = Box::new(Self {
            org_x: [0.0; N],
            org_y: [0.0; N],
            org_z: [0.0; N],
            tnear: [0.0; N],
            dir_x: [0.0; N],
            dir_y: [0.0; N],
            dir_z: [1.0; N],
            time: [0.0; N],
            tfar: [0.0; N],
            mask: [u32::MAX; N],
            id: [0; N],
            flags: [0; N],
            ng_x: [0.0; N],
            ng_y: [0.0; N],
            ng_z: [0.0; N],
            u: [0.0; N],
            v: [0.0; N],
            prim_id: [INVALID_ID; N],
            geom_id: [INVALID_ID; N],
            inst_id: [INVALID_ID; N],
            inst_prim_id: [INVALID_ID; N],
            guard: [SENTINEL; GUARD_WORDS],
        });
        p.fill(rays, &mut valid);
        (p, valid)
    }

    /// Loads `rays` into the lanes (the hit IDs reset), masking off the invalid ones and the
    /// lanes past `rays.len()`.
    fn fill(&mut self, rays: &[Ray], valid: &mut Valid<N>) {
        for i in 0..N {
            let r = rays.get(i);
            let (o, d) = r.map_or(([0.0; 3], [0.0, 0.0, 1.0]), |r| {
                (r.origin.to_array(), r.direction.to_array())
            });
            let (t0, t1) = r.map_or((0.0, 0.0), |r| (r.t_min, r.t_max));
            let ok = r.is_some() && ray_is_valid(o, d, t0, t1);
            valid.0[i] = if ok { -1 } else { 0 };
            [self.org_x[i], self.org_y[i], self.org_z[i]] = o;
            [self.dir_x[i], self.dir_y[i], self.dir_z[i]] = d;
            (self.tnear[i], self.tfar[i]) = (t0, t1);
            self.geom_id[i] = INVALID_ID;
            self.prim_id[i] = INVALID_ID;
        }
    }

    /// Lane `i`'s hit after the call.
    fn hit(&self, i: usize) -> Option<EmbreeHit> {
        (self.geom_id[i] != INVALID_ID).then(|| EmbreeHit {
            t: self.tfar[i],
            u: self.u[i],
            v: self.v[i],
            prim_id: self.prim_id[i],
            ng: [self.ng_x[i], self.ng_y[i], self.ng_z[i]],
        })
    }
}

impl EmbreeScene {
    /// Closest hits of `rays` by Embree's packet API, `N` (8: `rtcIntersect8`, 16:
    /// `rtcIntersect16`) consecutive rays per call: `found(i, hit)` for every `rays[i]`, in
    /// order. Rays Embree cannot handle ([`ray_is_valid`]) are not traced and give `None`.
    ///
    /// # Panics
    ///
    /// At compile time for another `N`.
    pub fn intersect_packets<const N: usize>(
        &self,
        rays: &[Ray],
        mut found: impl FnMut(usize, Option<EmbreeHit>),
    ) {
        const { assert!(N == 8 || N == 16, "Embree packets are of 8 or 16 rays") };
        let (mut packet, mut valid) = RayHitN::<N>::new(&[]);
        for (k, chunk) in rays.chunks(N).enumerate() {
            packet.fill(chunk, &mut valid);
            let rayhit = (&raw mut *packet).cast::<std::ffi::c_void>();
            // SAFETY: `self.raw` is a live committed scene. `valid` holds `N` ints and `packet`
            // an `RTCRayHitN` of the 4.4 layout (checked at compile time above), both fully
            // initialised and 64-byte aligned (Embree needs 32 bytes for 8 rays, 64 for 16),
            // followed by our guard words: the library reads the valid lanes' rays and writes
            // only their `tfar` and hit fields. Null arguments select the default
            // `RTCIntersectArguments`.
            unsafe {
                if N == 8 {
                    super::ffi::rtc_intersect8(valid.0.as_ptr(), self.raw, rayhit);
                } else {
                    super::ffi::rtc_intersect16(valid.0.as_ptr(), self.raw, rayhit);
                }
            }
            debug_assert!(
                packet.guard.iter().all(|&w| w == SENTINEL),
                "rtcIntersect{N} wrote past the 4.4 RTCRayHit{N}"
            );
            for i in 0..chunk.len() {
                found(k * N + i, packet.hit(i));
            }
        }
    }
}

impl EmbreeScene {
    /// Occlusion of `rays` by Embree's packet API, `N` (8: `rtcOccluded8`, 16:
    /// `rtcOccluded16`) consecutive rays per call: `found(i, occluded)` for every `rays[i]`, in
    /// order. Rays Embree cannot handle ([`ray_is_valid`]) are not traced and give `false`.
    ///
    /// # Panics
    ///
    /// At compile time for another `N`.
    pub fn occluded_packets<const N: usize>(
        &self,
        rays: &[Ray],
        mut found: impl FnMut(usize, bool),
    ) {
        const { assert!(N == 8 || N == 16, "Embree packets are of 8 or 16 rays") };
        let (mut packet, mut valid) = RayHitN::<N>::new(&[]);
        for (k, chunk) in rays.chunks(N).enumerate() {
            packet.fill(chunk, &mut valid);
            let ray = (&raw mut *packet).cast::<std::ffi::c_void>();
            // SAFETY: `self.raw` is a live committed scene. `valid` holds `N` ints and `packet`
            // begins with an `RTCRayN` of the 4.4 layout (the ray arrays of `RTCRayHitN`,
            // checked at compile time above), both fully initialised and 64-byte aligned: the
            // library reads the valid lanes' rays and writes only their `tfar`.
            unsafe {
                if N == 8 {
                    super::ffi::rtc_occluded8(valid.0.as_ptr(), self.raw, ray);
                } else {
                    super::ffi::rtc_occluded16(valid.0.as_ptr(), self.raw, ray);
                }
            }
            debug_assert!(
                packet.guard.iter().all(|&w| w == SENTINEL),
                "rtcOccluded{N} wrote past the 4.4 RTCRayHit{N}"
            );
            for (i, &v) in valid.0.iter().enumerate().take(chunk.len()) {
                // Embree sets an occluded lane's `tfar` to −∞.
                found(k * N + i, v != 0 && packet.tfar[i] == f32::NEG_INFINITY);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::EmbreeDevice;
    use super::*;
    use halfray_core::Vec3;

    /// Relative difference allowed between the `t` of a packet kernel and of `rtcIntersect1`
    /// for one hit: Embree's kernels for one ray and for packets round differently (a few
    /// ulps of `t`; 1e-5 is about 80 ulps).
    const T_AGREEMENT: f32 = 1e-5;

    /// Packets of 8 and 16 give `rtcIntersect1`'s answers ray for ray (same scene, same rays:
    /// camera rays over a grid of triangles, with invalid rays and a short last packet).
    #[test]
    fn packets_answer_as_single_rays() {
        let Ok(device) = EmbreeDevice::new() else {
            panic!("no Embree device");
        };
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for y in 0..20u32 {
            for x in 0..20u32 {
                let b = positions.len() as u32;
                let p = |dx: f32, dy: f32| [x as f32 + dx - 10.0, y as f32 + dy - 10.0, 5.0];
                positions.extend([p(0.0, 0.0), p(0.9, 0.0), p(0.0, 0.9)]);
                triangles.push([b, b + 1, b + 2]);
            }
        }
        for robust in [false, true] {
            let scene = EmbreeScene::new(&device, &positions, &triangles, robust).unwrap();
            let mut rays: Vec<Ray> = (0..999)
                .map(|k| {
                    let d = Vec3::new(
                        (k % 37) as f32 / 37.0 - 0.5,
                        (k / 37) as f32 / 27.0 - 0.5,
                        0.3,
                    );
                    Ray::new(Vec3::ZERO, d)
                })
                .collect();
            rays[10] = Ray::new(Vec3::splat(f32::NAN), Vec3::Z);
            rays[11].t_min = -1.0;
            let single: Vec<_> = rays.iter().map(|r| scene.intersect_ray(r)).collect();
            assert!(single.iter().filter(|h| h.is_some()).count() > 300);
            for n in [8, 16] {
                let mut got: Vec<Option<Option<EmbreeHit>>> = vec![None; rays.len()];
                let mut store = |i: usize, h: Option<EmbreeHit>| got[i] = Some(h);
                if n == 8 {
                    scene.intersect_packets::<8>(&rays, &mut store);
                } else {
                    scene.intersect_packets::<16>(&rays, &mut store);
                }
                for (i, (g, s)) in got.iter().zip(&single).enumerate() {
                    let g = g.expect("every ray answered");
                    assert_eq!(g.map(|h| h.prim_id), s.map(|h| h.prim_id), "{n}: ray {i}");
                    if let (Some(g), Some(s)) = (g, s) {
                        assert!((g.t - s.t).abs() <= T_AGREEMENT * s.t, "{n}: ray {i}");
                    }
                }
                // Occlusion by packets is `rtcOccluded1`'s, ray for ray.
                let mut occluded: Vec<Option<bool>> = vec![None; rays.len()];
                let mut store = |i: usize, o: bool| occluded[i] = Some(o);
                if n == 8 {
                    scene.occluded_packets::<8>(&rays, &mut store);
                } else {
                    scene.occluded_packets::<16>(&rays, &mut store);
                }
                for (i, (o, r)) in occluded.iter().zip(&rays).enumerate() {
                    assert_eq!(*o, Some(scene.occluded_ray(r)), "{n}: occluded, ray {i}");
                }
            }
        }
    }
}
