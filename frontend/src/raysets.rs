//! Deterministic ray sets shared by the benchmarks, the cross-check and the tests.
//!
//! * [`Camera`]: a pinhole camera framing an axis-aligned box; [`Camera::ray`] gives the primary
//!   ray through the centre `(i + ½, j + ½)` of pixel `(i, j)` (row `j = 0` at the top).
//! * [`random_rays`]: incoherent rays, origins uniform on a sphere of twice the bounding-sphere
//!   radius around the box, aimed at uniform random points inside the box.
//!
//! * [`named`]: the named ray sets of `bench bvh` and `crosscheck` built from these.
//!
//! All are pure functions of their inputs (and seed): the same rays on every machine. The
//! arithmetic is done in `f64` and rounded once to `f32`; besides IEEE 754's correctly rounded
//! operations (`+ − × ÷`, `sqrt`) it calls only the `libm` crate's functions (`sin`, `cos`,
//! `tan`, `log`, `exp`: pure Rust, the same bits on every platform), never std's, which call the
//! platform's C library and differ between them. The same holds for the generated meshes
//! ([`crate::mesh_tools::generate`]) and the cross-check's aimed sets
//! ([`crate::crosscheck::sets`]); `tests::no_platform_maths_in_the_generators` keeps std's out
//! of these files, and golden fingerprints next to each hold its output to the bit.

pub mod named;

use glam::{DVec3, Vec3};
use halfray_core::Ray;

/// FNV-1a, 64 bits (Fowler, Noll, Vo): the cross-check's seed of a set or file name
/// ([`crate::crosscheck::sets::mesh_seed`]) and the tests' fingerprints of generated data.
#[must_use]
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

/// The tests' fingerprint of generated data: [`fnv1a`] of `words`' little-endian bytes (an
/// `f32` enters as its bits).
#[cfg(test)]
pub(crate) fn fingerprint(words: impl IntoIterator<Item = u32>) -> u64 {
    fnv1a(words.into_iter().flat_map(u32::to_le_bytes))
}

/// The bits of `ray`'s origin, direction, `t_min` and `t_max`, for [`fingerprint`].
#[cfg(test)]
pub(crate) fn ray_bits(ray: &Ray) -> impl Iterator<Item = u32> {
    ray.origin
        .to_array()
        .into_iter()
        .chain(ray.direction.to_array())
        .chain([ray.t_min, ray.t_max])
        .map(f32::to_bits)
}

/// SplitMix64 (Steele, Lea, Flood 2014): small, fast, deterministic, no dependency.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` (53 random bits).
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }

    /// Log-uniform in `[lo, hi)` (both positive).
    pub fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        libm::exp(libm::log(lo) + (libm::log(hi) - libm::log(lo)) * self.f64())
    }

    /// `true` with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.f64() < p
    }

    /// A random `f32` with a full random mantissa, uniform-ish in `[lo, hi)`.
    pub fn f32_in(&mut self, lo: f32, hi: f32) -> f32 {
        self.range(f64::from(lo), f64::from(hi)) as f32
    }

    /// Uniform index in `0..n` (0 when `n = 0`).
    pub fn below(&mut self, n: usize) -> usize {
        ((u128::from(self.next_u64()) * n as u128) >> 64) as usize
    }

    /// Uniform direction on the unit sphere.
    pub fn unit_vector(&mut self) -> DVec3 {
        let z = 2.0 * self.f64() - 1.0;
        let phi = std::f64::consts::TAU * self.f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * libm::cos(phi), r * libm::sin(phi), z)
    }
}

/// Vertical field of view of [`Camera::framing`], degrees.
pub const CAMERA_FOV_DEG: f64 = 45.0;

/// Direction from the box centre to the eye of [`Camera::framing`] (normalised on use): above,
/// to the right and in front (`+z`), so that no face of an axis-aligned box is seen edge-on.
pub const CAMERA_VIEW_DIR: [f64; 3] = [0.3, 0.4, 1.0];

/// A pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Unit view direction.
    pub forward: DVec3,
    /// Unit right vector.
    pub right: DVec3,
    /// Unit up vector.
    pub up: DVec3,
    /// `tan(fov/2)`.
    pub half_height: f64,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
}

impl Camera {
    /// A camera looking at the box `[lo, hi]` from [`CAMERA_VIEW_DIR`], far enough that the
    /// bounding sphere fits the vertical [`CAMERA_FOV_DEG`] field of view, for a `width ×
    /// height` image. A degenerate box is treated as a unit-radius sphere at its centre.
    #[must_use]
    pub fn framing(lo: Vec3, hi: Vec3, width: usize, height: usize) -> Self {
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let center = (lo + hi) * 0.5;
        let mut radius = (hi - lo).length() * 0.5;
        if !(radius > 0.0 && radius.is_finite()) {
            radius = 1.0;
        }
        let fov = CAMERA_FOV_DEG.to_radians();
        let dist = radius / libm::sin(fov * 0.5);
        let eye = center + DVec3::from_array(CAMERA_VIEW_DIR).normalize() * dist;
        let forward = (center - eye).normalize();
        let right = forward.cross(DVec3::Y).normalize();
        let up = right.cross(forward);
        Self {
            eye,
            forward,
            right,
            up,
            half_height: libm::tan(fov * 0.5),
            width: width.max(1),
            height: height.max(1),
        }
    }

    /// The primary ray through the centre of pixel `(i, j)` (`i` to the right, `j` down),
    /// over `(0, ∞]`, direction not normalised.
    #[must_use]
    pub fn ray(&self, i: usize, j: usize) -> Ray {
        let aspect = self.width as f64 / self.height as f64;
        let sx = (2.0 * (i as f64 + 0.5) / self.width as f64 - 1.0) * self.half_height * aspect;
        let sy = (1.0 - 2.0 * (j as f64 + 0.5) / self.height as f64) * self.half_height;
        let d = self.forward + self.right * sx + self.up * sy;
        Ray::new(self.eye.as_vec3(), d.as_vec3())
    }

    /// All `width × height` primary rays, row by row from the top.
    #[must_use]
    pub fn rays(&self) -> Vec<Ray> {
        let mut out = Vec::with_capacity(self.width * self.height);
        for j in 0..self.height {
            for i in 0..self.width {
                out.push(self.ray(i, j));
            }
        }
        out
    }
}

/// `count` incoherent rays for the box `[lo, hi]`: origin uniform on the sphere of radius
/// `2 × (half the diagonal)` around the centre, direction towards a uniform point in the box
/// (so `t = 1` at that point). Deterministic for a given `seed`.
#[must_use]
pub fn random_rays(lo: Vec3, hi: Vec3, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let center = (lo + hi) * 0.5;
    let mut radius = (hi - lo).length() * 0.5;
    if !(radius > 0.0 && radius.is_finite()) {
        radius = 1.0;
    }
    (0..count)
        .map(|_| {
            let o = (center + rng.unit_vector() * (2.0 * radius)).as_vec3();
            let u = DVec3::new(rng.f64(), rng.f64(), rng.f64());
            let p = (lo + (hi - lo) * u).as_vec3();
            Ray::new(o, p - o)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generator is SplitMix64 (Steele, Lea and Flood, OOPSLA 2014; Vigna's
    /// `splitmix64.c`): from state 0 its first output is `0xE220A8397B1DCDAF`, the reference
    /// implementation's. `Rng::new` XORs the seed with the increment, so that seed gives
    /// state 0.
    #[test]
    fn the_generator_is_splitmix64() {
        let mut rng = Rng::new(0x9E37_79B9_7F4A_7C15);
        assert_eq!(rng.next_u64(), 0xE220_A839_7B1D_CDAF);
    }

    /// std's transcendental functions call the platform's C library, whose results differ
    /// between glibc, musl, macOS and Windows; the generators call the `libm` crate's (the
    /// module docs). None of std's in their sources: a golden fingerprint catches one only on a
    /// platform whose C library rounds differently from `libm` on its arguments, this scan on
    /// every one. (`sqrt` is IEEE 754's correctly rounded square root everywhere: allowed.)
    #[test]
    fn no_platform_maths_in_the_generators() {
        let sources = [
            ("raysets.rs", include_str!("raysets.rs")),
            ("raysets/named.rs", include_str!("raysets/named.rs")),
            (
                "mesh_tools/generate.rs",
                include_str!("mesh_tools/generate.rs"),
            ),
            ("crosscheck/sets.rs", include_str!("crosscheck/sets.rs")),
        ];
        let functions = [
            "sin", "cos", "tan", "sin_cos", "asin", "acos", "atan", "atan2", "sinh", "cosh",
            "tanh", "asinh", "acosh", "atanh", "exp", "exp2", "exp_m1", "ln", "ln_1p", "log",
            "log2", "log10", "powf", "powi", "cbrt", "hypot",
        ];
        for (file, text) in sources {
            for f in functions {
                for call in [format!(".{f}("), format!("f64::{f}"), format!("f32::{f}")] {
                    assert!(
                        !text.contains(&call),
                        "{file} calls std's `{call}`: take libm::{f} (or a product for powi)"
                    );
                }
            }
        }
    }

    #[test]
    fn camera_centre_pixel_looks_at_the_box_centre() {
        let cam = Camera::framing(Vec3::splat(-1.0), Vec3::splat(1.0), 2, 2);
        // The four pixel centres are symmetric around the view axis.
        let d: Vec<Vec3> = cam.rays().iter().map(|r| r.direction).collect();
        let mean = (d[0] + d[1] + d[2] + d[3]) * 0.25;
        let f = cam.forward.as_vec3();
        assert!((mean.normalize() - f).length() < 1e-6, "{mean:?} {f:?}");
        assert!(
            cam.ray(0, 0).direction.dot(cam.up.as_vec3()) > 0.0,
            "row 0 is the top"
        );
    }

    #[test]
    fn random_rays_are_deterministic_and_aim_into_the_box() {
        let (lo, hi) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 4.0));
        let a = random_rays(lo, hi, 1000, 7);
        assert_eq!(a, random_rays(lo, hi, 1000, 7));
        assert_ne!(a, random_rays(lo, hi, 1000, 8));
        let b = halfray_core::Aabb::new(lo, hi);
        for r in &a {
            assert!(r.is_valid());
            let p = r.at(1.0);
            assert!(
                b.contains_point(p) || (p - p.clamp(lo, hi)).length() < 1e-5,
                "{p:?}"
            );
        }
    }
}
