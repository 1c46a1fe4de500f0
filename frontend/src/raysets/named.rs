//! The named ray sets of `halfray bench bvh` and `halfray crosscheck`: the same names and
//! generators in both. Each set is a pure function of the mesh's bounding box, a ray count, a
//! seed and (for the sets that start on the surface) the closest hits of the `primary` rays;
//! the two commands pass different counts and seeds, so their rays differ (`bench bvh`: a
//! `--width`² count for the camera sets and a fixed seed; `crosscheck`: `--rays` for every set,
//! seeded per mesh and set; docs/benchmarks.md, "The ray sets").
//!
//! | set | rays | query timed |
//! |---|---|---|
//! | `primary` | a camera framing the box ([`Camera::framing`]) of side `⌈√count⌉` pixels, pixel centres in scanline order, the first `count` | closest hit |
//! | `primary-tiles` | the same pixels, in [`TILE`]` × `[`TILE`] tiles (tiles in scanline order, pixels in scanline order within a tile) | closest hit |
//! | `primary-stride` | every [`STRIDE`]-th pixel, in scanline order, of a camera of side `⌈√(count·STRIDE)⌉`: semi-coherent | closest hit |
//! | `random` | [`random_rays`]: origins on a sphere twice the bounding sphere, aimed at uniform points in the box | closest hit |
//! | `shadow` | from each hit of the `primary` rays towards a point light ([`light_position`]), [`spawn_ray_to`] | any hit |
//! | `ao` | from each hit of the `primary` rays, a cosine-distributed direction in the hemisphere facing the camera, `t_max` = [`AO_RADIUS`] × the box diagonal | any hit |
//!
//! `shadow` and `ao` have one ray per `primary` ray that hits, so fewer than `count` where the
//! camera sees background. Their hit points come from the watertight intersector through the
//! 8-wide BVH ([`watertight_hits`]) whatever intersector is being measured, so every
//! intersector and Embree get the same rays.

use super::{Camera, Rng, random_rays};
use crate::accel::{VecBvh8, closest_simd};
use crate::obj::ObjMesh;
use glam::{DVec3, Vec3};
use halfray_core::triangle::Watertight;
use halfray_core::{Hit, Ray, spawn_ray, spawn_ray_to};

/// Side of the square tiles of `primary-tiles`, pixels (the tile of a packet tracer's 8×8).
pub const TILE: usize = 8;
/// Pixel stride of `primary-stride`: every 10th pixel of a larger image in scanline order, the
/// timed sample `crosscheck` used to take, which breaks row coherence.
pub const STRIDE: usize = 10;
/// Direction from the box centre to the point light of `shadow` (normalised on use): above,
/// to the left and in front, away from the camera's [`super::CAMERA_VIEW_DIR`].
pub const LIGHT_DIR: [f64; 3] = [-0.5, 1.0, 0.3];
/// Distance of the point light from the box centre, in bounding-sphere radii (outside the box).
pub const LIGHT_DISTANCE: f64 = 3.0;
/// Length of the `ao` rays as a fraction of the box diagonal (unitless): short rays, the
/// ambient-occlusion radius of a renderer.
pub const AO_RADIUS: f64 = 0.05;

/// The query a set is timed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit (`rtcIntersect1` on Embree's side).
    Closest,
    /// Any hit (`rtcOccluded1` on Embree's side).
    Any,
}

/// A named ray set (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RaySet {
    /// Camera rays in scanline order.
    Primary,
    /// Camera rays in 8×8 tiles.
    PrimaryTiles,
    /// Camera rays subsampled with a stride.
    PrimaryStride,
    /// Uniform random rays.
    Random,
    /// Shadow rays from the camera's hit points towards a point light (any hit).
    Shadow,
    /// Short ambient-occlusion rays from the camera's hit points (any hit).
    Ao,
}

impl Query {
    /// `closest` or `any`, as reports name it.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Query::Closest => "closest",
            Query::Any => "any",
        }
    }
}

impl RaySet {
    /// Every set, in report order.
    pub const ALL: [RaySet; 6] = [
        RaySet::Primary,
        RaySet::PrimaryTiles,
        RaySet::PrimaryStride,
        RaySet::Random,
        RaySet::Shadow,
        RaySet::Ao,
    ];

    /// The set's name on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            RaySet::Primary => "primary",
            RaySet::PrimaryTiles => "primary-tiles",
            RaySet::PrimaryStride => "primary-stride",
            RaySet::Random => "random",
            RaySet::Shadow => "shadow",
            RaySet::Ao => "ao",
        }
    }

    /// The set called `name`, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The query the set is timed with.
    #[must_use]
    pub fn query(self) -> Query {
        match self {
            RaySet::Shadow | RaySet::Ao => Query::Any,
            _ => Query::Closest,
        }
    }

    /// The set's rays for the box `[lo, hi]` (see the module docs): `count` rays, or one per
    /// hit of the `count` `primary` rays for `shadow` and `ao`, found with `hits`. `seed` drives
    /// `random` and `ao`. A degenerate box is framed as a unit sphere ([`Camera::framing`]).
    pub fn generate(
        self,
        lo: Vec3,
        hi: Vec3,
        count: usize,
        seed: u64,
        hits: &dyn Fn(&Ray) -> Option<Hit>,
    ) -> Vec<Ray> {
        let side = |n: usize| (n as f64).sqrt().ceil().max(1.0) as usize;
        match self {
            RaySet::Primary => {
                let s = side(count);
                let cam = Camera::framing(lo, hi, s, s);
                (0..count).map(|k| cam.ray(k % s, k / s)).collect()
            }
            RaySet::PrimaryTiles => {
                let s = side(count);
                let cam = Camera::framing(lo, hi, s, s);
                let mut out = Vec::with_capacity(count);
                for ty in (0..s).step_by(TILE) {
                    for tx in (0..s).step_by(TILE) {
                        for j in ty..(ty + TILE).min(s) {
                            for i in tx..(tx + TILE).min(s) {
                                if j * s + i < count {
                                    out.push(cam.ray(i, j));
                                }
                            }
                        }
                    }
                }
                out
            }
            RaySet::PrimaryStride => {
                let s = side(count.saturating_mul(STRIDE));
                let cam = Camera::framing(lo, hi, s, s);
                (0..count)
                    .map(|k| {
                        let p = k * STRIDE;
                        cam.ray(p % s, p / s)
                    })
                    .collect()
            }
            RaySet::Random => random_rays(lo, hi, count, seed),
            RaySet::Shadow => {
                let light = light_position(lo, hi);
                camera_hits(lo, hi, count, hits)
                    .map(|(h, _)| spawn_ray_to(&h, light))
                    .collect()
            }
            RaySet::Ao => {
                let mut rng = Rng::new(seed);
                let reach = (AO_RADIUS * diagonal(lo, hi)) as f32;
                camera_hits(lo, hi, count, hits)
                    .filter_map(|(h, incoming)| {
                        let w = cosine_direction(&mut rng, h.normal, incoming)?;
                        let mut ray = spawn_ray(&h, w);
                        ray.t_max = reach;
                        Some(ray)
                    })
                    .collect()
            }
        }
    }
}

impl std::fmt::Display for RaySet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The point light of `shadow`: [`LIGHT_DISTANCE`] bounding-sphere radii from the centre of
/// `[lo, hi]` along [`LIGHT_DIR`] (a degenerate box counts as radius 1).
#[must_use]
pub fn light_position(lo: Vec3, hi: Vec3) -> Vec3 {
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let center = (lo + hi) * 0.5;
    let r = radius(lo, hi);
    (center + DVec3::from_array(LIGHT_DIR).normalize() * (LIGHT_DISTANCE * r)).as_vec3()
}

fn radius(lo: DVec3, hi: DVec3) -> f64 {
    let r = (hi - lo).length() * 0.5;
    if r > 0.0 && r.is_finite() { r } else { 1.0 }
}

fn diagonal(lo: Vec3, hi: Vec3) -> f64 {
    2.0 * radius(lo.as_dvec3(), hi.as_dvec3())
}

/// The hits of the `count` `primary` rays (with the ray's direction), in scanline order.
fn camera_hits<'a>(
    lo: Vec3,
    hi: Vec3,
    count: usize,
    hits: &'a dyn Fn(&Ray) -> Option<Hit>,
) -> impl Iterator<Item = (Hit, Vec3)> + 'a {
    RaySet::Primary
        .generate(lo, hi, count, 0, hits)
        .into_iter()
        .filter_map(move |r| hits(&r).map(|h| (h, r.direction)))
}

/// A cosine-distributed unit direction around `normal` turned to face against `incoming`
/// (the side the camera sees); `None` for a zero normal.
fn cosine_direction(rng: &mut Rng, normal: Vec3, incoming: Vec3) -> Option<Vec3> {
    let mut n = normal.as_dvec3().normalize_or_zero();
    if n == DVec3::ZERO {
        return None;
    }
    if n.dot(incoming.as_dvec3()) > 0.0 {
        n = -n;
    }
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    let (r1, phi) = (rng.f64(), std::f64::consts::TAU * rng.f64());
    let s = r1.sqrt();
    let w = t * (s * libm::cos(phi)) + b * (s * libm::sin(phi)) + n * (1.0 - r1).sqrt();
    Some(w.as_vec3())
}

/// No hits at all: for callers that generate only sets that do not start on the surface
/// (`shadow` and `ao` come out empty with it).
#[must_use]
pub fn no_hits(_: &Ray) -> Option<Hit> {
    None
}

/// Closest hits of the watertight intersector through `bvh` (built over `mesh`) as full
/// [`Hit`]s: the surface points `shadow` and `ao` start from.
pub fn watertight_hits<'a>(
    bvh: &'a VecBvh8,
    mesh: &'a ObjMesh,
) -> impl Fn(&Ray) -> Option<Hit> + 'a {
    let tris = halfray_core::mesh::TriangleMesh::new(&mesh.positions, &mesh.triangles);
    move |r| {
        closest_simd(bvh, &tris, &Watertight, r, None)
            .map(|(p, h)| h.to_hit(&mesh.triangle(p as usize)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square `[-1, 1]²` in the plane `z = 0`, facing `+z` (towards the camera).
    fn floor() -> ObjMesh {
        let positions = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        ObjMesh {
            positions,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    /// The plane `z = 0` as an oracle independent of the BVH: where a ray crosses it.
    fn plane_hit(r: &Ray) -> Option<Hit> {
        let t = -r.origin.z / r.direction.z;
        let p = r.origin + r.direction * t;
        (t > r.t_min && t <= r.t_max && p.x.abs() <= 1.0 && p.y.abs() <= 1.0).then(|| Hit {
            t,
            point: p,
            point_error: Vec3::splat(1e-6),
            normal: Vec3::Z,
            uv: glam::Vec2::ZERO,
            front_face: r.direction.z < 0.0,
        })
    }

    #[test]
    fn names_round_trip_and_only_shadow_and_ao_are_any_hit() {
        for s in RaySet::ALL {
            assert_eq!(RaySet::from_name(s.name()), Some(s));
            assert_eq!(
                s.query() == Query::Any,
                matches!(s, RaySet::Shadow | RaySet::Ao)
            );
        }
        assert_eq!(RaySet::from_name("edges"), None);
    }

    #[test]
    fn tiles_are_the_scanline_pixels_reordered_in_8x8_blocks() {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        // 20 × 20 pixels, the last row cut short: 390 rays.
        let scan = RaySet::Primary.generate(lo, hi, 390, 0, &plane_hit);
        let tiles = RaySet::PrimaryTiles.generate(lo, hi, 390, 0, &plane_hit);
        assert_eq!(scan.len(), 390);
        let key = |r: &Ray| r.direction.to_array().map(f32::to_bits);
        let mut a: Vec<_> = scan.iter().map(key).collect();
        let mut b: Vec<_> = tiles.iter().map(key).collect();
        assert_ne!(a, b, "reordered");
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "the same rays");
        // The first tile is pixels (0..8, 0..8) of the 20-wide image; the ninth ray is (0, 1).
        let cam = Camera::framing(lo, hi, 20, 20);
        assert_eq!(tiles[8], cam.ray(0, 1));
        assert_eq!(tiles[63], cam.ray(7, 7));
        assert_eq!(tiles[64], cam.ray(8, 0));
    }

    #[test]
    fn stride_takes_every_tenth_pixel_of_a_larger_image() {
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let rays = RaySet::PrimaryStride.generate(lo, hi, 100, 0, &plane_hit);
        // ⌈√1000⌉ = 32 pixels a side; ray k is pixel 10·k in scanline order.
        let cam = Camera::framing(lo, hi, 32, 32);
        assert_eq!(rays.len(), 100);
        assert_eq!(rays[0], cam.ray(0, 0));
        assert_eq!(rays[4], cam.ray(8, 1));
        assert_eq!(rays[99], cam.ray(990 % 32, 990 / 32));
    }

    #[test]
    fn shadow_rays_end_at_the_light_and_ao_rays_are_short_and_leave_the_visible_side() {
        let mesh = floor();
        let (lo, hi) = mesh.bounds().unwrap();
        let count = 400;
        let primary = RaySet::Primary.generate(lo, hi, count, 0, &plane_hit);
        let seen = primary.iter().filter(|r| plane_hit(r).is_some()).count();
        assert!(seen > 50 && seen < count, "{seen}");
        let light = light_position(lo, hi);
        let shadow = RaySet::Shadow.generate(lo, hi, count, 3, &plane_hit);
        assert_eq!(shadow.len(), seen);
        for r in &shadow {
            assert!(r.origin.z > 0.0, "offset above the floor: {r:?}");
            assert!(
                (r.at(1.0) - light).length() < 1e-4 * light.length(),
                "{r:?}"
            );
            assert!(r.t_max < 1.0 && r.t_max > 0.999);
        }
        let ao = RaySet::Ao.generate(lo, hi, count, 3, &plane_hit);
        assert_eq!(ao.len(), seen);
        let reach = (AO_RADIUS * diagonal(lo, hi)) as f32;
        for r in &ao {
            assert!((r.direction.length() - 1.0).abs() < 1e-5);
            assert!(r.direction.z > 0.0, "towards the camera's side: {r:?}");
            assert_eq!(r.t_max, reach);
        }
        assert_eq!(ao, RaySet::Ao.generate(lo, hi, count, 3, &plane_hit));
        assert_ne!(ao, RaySet::Ao.generate(lo, hi, count, 4, &plane_hit));
    }

    #[test]
    fn watertight_hits_find_the_floor_where_the_plane_oracle_does() {
        let mesh = floor();
        let accel = crate::accel::MeshAccel::new(mesh.clone()).unwrap();
        let hits = watertight_hits(accel.bvh(), &accel.mesh);
        let (lo, hi) = mesh.bounds().unwrap();
        for r in RaySet::Primary.generate(lo, hi, 256, 0, &plane_hit) {
            let (a, b) = (hits(&r), plane_hit(&r));
            assert_eq!(a.is_some(), b.is_some(), "{r:?}");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.point - b.point).length() < 1e-5);
                assert_eq!(a.normal, Vec3::Z);
            }
        }
    }

    /// The cross-machine determinism check of the six sets: their fingerprints
    /// ([`crate::raysets::fingerprint`] of every ray's bits, in order) over the generated
    /// `sphere` of size 6, seed 1, 400 rays each (`shadow` and `ao` from the camera's hits
    /// through [`watertight_hits`]), seed 5. The sets call `libm`'s functions, pure Rust, so
    /// these are the values on every platform (and std's on x86-64 glibc before the switch).
    #[test]
    fn the_sets_keep_their_fingerprints() {
        let mesh = crate::mesh_tools::generate::fingerprint_sphere();
        let accel = crate::accel::MeshAccel::new(mesh).unwrap();
        let hits = watertight_hits(accel.bvh(), &accel.mesh);
        let (lo, hi) = accel.mesh.bounds().unwrap();
        let want = [
            0x258b_efe7_7cf6_d2fc,
            0xdbfd_6ec1_707d_9198,
            0xd395_bb95_8616_982c,
            0xc72e_27bc_5e7b_d588,
            0xf672_83d2_56c3_7077,
            0x5187_fe00_9d32_20b5,
        ];
        let got = RaySet::ALL.map(|set| {
            let rays = set.generate(lo, hi, 400, 5, &hits);
            crate::raysets::fingerprint(rays.iter().flat_map(crate::raysets::ray_bits))
        });
        assert_eq!(got, want, "{:#018x?}", got);
    }
}
