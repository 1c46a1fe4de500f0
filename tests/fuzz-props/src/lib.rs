//! Property checks behind the `halfray` fuzz targets (crate `halfray-fuzz-props`).
//!
//! Every fuzz target in `fuzz/fuzz_targets/` is a one-line call into this crate, and the stable
//! test `tests/tests/fuzz_replay.rs` uses it to replay the checked-in corpora
//! (`fuzz/corpus/<target>/`) and regression inputs (`fuzz/regressions/<target>/`) with a plain
//! `cargo test`. It depends only on `halfray-core`, `halfray` (frontend) and `glam`.
//!
//! Each check **panics** with a message naming the input (decimal and bit patterns) when a
//! property is broken; that is what libFuzzer records as a crash.
//!
//! Inputs are raw bytes decoded into `f32` bit patterns (`f32::from_bits(u32::from_le_bytes)`),
//! so NaN, ±∞, ±0, subnormals and huge values all occur; missing bytes read as zero. The byte
//! layout of every target is documented on its function, and [`seeds`] builds the hard-case
//! seed corpus from readable values.

use std::path::Path;

use glam::{DVec3, Vec3};
use halfray_core::aabb::{Aabb, SlabRay};
use halfray_core::float::{F32_UNIT_ROUNDOFF, F64_UNIT_ROUNDOFF, gamma};
use halfray_core::ray::Ray;
use halfray_core::tolerance::BARYCENTRIC_SLACK;
use halfray_core::triangle::{F64Reference, TriangleHit, TriangleVariant};

/// Every target this file implements, by fuzz-target (and corpus directory) name.
pub const TARGETS: &[&str] = &[
    "ray_triangle",
    "ray_box",
    "ray_sphere",
    "ray_quadric",
    "obj_file",
    "scene_file",
    "bvh",
    "bvh_load",
    "halfedge_ops",
    "grid",
    "kdtree",
    "overlap",
];

/// What [`run`] found out about an input that passed its target's checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The input reached at least one of the target's decisive checks: an answer judged
    /// against the target's oracle or contract (a hit or a miss the oracle decides, a refusal
    /// of an input the contract refuses).
    Checked,
    /// Every check the input met let either answer stand (undecidable near an edge, outside
    /// the oracle's domain, a text the target does not read): it passed without being judged.
    Unjudged,
}

thread_local! {
    /// How many decisive checks this thread has reached ([`reached`]).
    static REACHED: core::cell::Cell<u64> = const { core::cell::Cell::new(0) };
}

/// Records that a property reached one of its decisive checks on the current input (see
/// [`Outcome::Checked`]); [`run`] reports it. The fuzz targets ignore it.
pub(crate) fn reached() {
    REACHED.with(|r| r.set(r.get() + 1));
}

/// Runs target `name` on `data`: whether the input reached a decisive check, `None` when no
/// such target exists. A broken property panics, as under the fuzzer.
pub fn run(name: &str, data: &[u8]) -> Option<Outcome> {
    let before = REACHED.with(|r| r.get());
    match name {
        "ray_triangle" => ray_triangle(data),
        "ray_box" => ray_box(data),
        "ray_sphere" => sphere::ray_sphere(data),
        "ray_quadric" => quadric::ray_quadric(data),
        "obj_file" => obj_file(data),
        "scene_file" => scene::scene_file(data),
        "bvh" => bvh::bvh(data),
        "bvh_load" => bvh_load::bvh_load(data),
        "halfedge_ops" => halfedge::halfedge_ops(data),
        "grid" => grid::grid(data),
        "kdtree" => kdtree::kdtree(data),
        "overlap" => overlap::overlap(data),
        _ => return None,
    }
    Some(if REACHED.with(|r| r.get()) > before {
        Outcome::Checked
    } else {
        Outcome::Unjudged
    })
}

// ---------------------------------------------------------------------------------------------
// Byte decoding and encoding
// ---------------------------------------------------------------------------------------------

/// Reads little-endian values from fuzz bytes; past the end every byte reads as 0.
#[derive(Clone, Debug)]
pub struct Input<'a> {
    data: &'a [u8],
}

impl<'a> Input<'a> {
    /// A reader over `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Self { data }
    }

    /// `true` when every byte has been read.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// One byte (0 past the end).
    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    /// A little-endian `u16`.
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }

    /// A little-endian `u32`.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// An `f32` from its little-endian bit pattern (any pattern: NaN payloads included).
    pub fn f32(&mut self) -> f32 {
        f32::from_bits(self.u32())
    }

    /// Three `f32`s.
    pub fn vec3(&mut self) -> Vec3 {
        let x = self.f32();
        let y = self.f32();
        let z = self.f32();
        Vec3::new(x, y, z)
    }

    /// A small "quantized" coordinate: a signed byte divided by 4 (exact dyadic values in
    /// `[-32, 31.75]`), so that shared vertices, coplanar faces and exact edge points occur.
    pub fn q(&mut self) -> f32 {
        f32::from(self.u8() as i8) * 0.25
    }

    /// Three quantized coordinates.
    pub fn qvec3(&mut self) -> Vec3 {
        let x = self.q();
        let y = self.q();
        let z = self.q();
        Vec3::new(x, y, z)
    }
}

/// Builds fuzz inputs (the inverse of [`Input`]), for seeds and regression tests.
#[derive(Clone, Debug, Default)]
pub struct Enc(pub Vec<u8>);

impl Enc {
    /// An empty input.
    pub fn new() -> Self {
        Self(Vec::new())
    }
    /// Appends a byte.
    pub fn u8(mut self, b: u8) -> Self {
        self.0.push(b);
        self
    }
    /// Appends a little-endian `u16`.
    pub fn u16(mut self, x: u16) -> Self {
        self.0.extend_from_slice(&x.to_le_bytes());
        self
    }
    /// Appends an `f32`'s bits.
    pub fn f32(mut self, x: f32) -> Self {
        self.0.extend_from_slice(&x.to_bits().to_le_bytes());
        self
    }
    /// Appends three `f32`s.
    pub fn vec3(self, v: Vec3) -> Self {
        self.f32(v.x).f32(v.y).f32(v.z)
    }
    /// Appends a quantized coordinate (`4·x` must be an integer in `-128..=127`).
    pub fn q(self, x: f32) -> Self {
        self.u8(((x * 4.0) as i8) as u8)
    }
    /// Appends three quantized coordinates.
    pub fn qvec3(self, v: Vec3) -> Self {
        self.q(v.x).q(v.y).q(v.z)
    }
    /// Appends a [`RayHeader`]: flags, origin, direction floats and interval.
    pub fn ray_header(self, fl: u8, o: Vec3, d: Vec3, t: (f32, f32)) -> Self {
        self.u8(fl).vec3(o).vec3(d).f32(t.0).f32(t.1)
    }
    /// Appends raw bytes.
    pub fn bytes(mut self, b: &[u8]) -> Self {
        self.0.extend_from_slice(b);
        self
    }
    /// The bytes.
    pub fn done(self) -> Vec<u8> {
        self.0
    }
}

fn fmt_f32(x: f32) -> String {
    format!("{x:e} ({:#010x})", x.to_bits())
}

fn fmt_vec3(v: Vec3) -> String {
    format!("[{}, {}, {}]", fmt_f32(v.x), fmt_f32(v.y), fmt_f32(v.z))
}

/// A ray, printed exactly (value and bits of every field).
pub fn fmt_ray(r: &Ray) -> String {
    format!(
        "Ray {{ origin: {}, direction: {}, t_min: {}, t_max: {} }}",
        fmt_vec3(r.origin),
        fmt_vec3(r.direction),
        fmt_f32(r.t_min),
        fmt_f32(r.t_max)
    )
}

// ---------------------------------------------------------------------------------------------
// ray_triangle
// ---------------------------------------------------------------------------------------------

/// Flag bits of the first byte of a `ray_triangle` / `ray_box` input.
pub mod flags {
    /// `ray_triangle`: the direction is `target − origin` with
    /// `target = v0 + u·(v1 − v0) + w·(v2 − v0)`, `(u, w)` = the first two direction floats
    /// (so `u, w ∈ {0, ½, 1}` aim at vertices and edge midpoints). `ray_box`: the direction is
    /// `min + (u, v, w)·(max − min) − origin`, aiming at box corners, edges and faces.
    pub const AIM: u8 = 1;
    /// The interval is `(0, +∞]`; the two interval floats are ignored.
    pub const DEFAULT_INTERVAL: u8 = 2;
    /// `ray_box`: the box is `[min(a, b), max(a, b)]` instead of `[a, b]`.
    pub const ORDERED: u8 = 4;
}

/// The ray part that opens a `ray_triangle` and a `ray_box` input: `flags: u8` ([`flags`]),
/// `origin: 3×f32`, `direction: 3×f32`, `t_min: f32`, `t_max: f32` (33 bytes); the target's
/// geometry follows it.
#[derive(Clone, Copy, Debug)]
pub struct RayHeader {
    /// The flag byte.
    pub flags: u8,
    /// The ray's origin.
    pub origin: Vec3,
    /// The direction floats: the direction itself, or with [`flags::AIM`] the parameters of
    /// the point aimed at.
    pub dir: Vec3,
    /// `(t_min, t_max)` as read (ignored with [`flags::DEFAULT_INTERVAL`]).
    pub interval: (f32, f32),
}

impl RayHeader {
    /// Reads a header.
    pub fn decode(i: &mut Input<'_>) -> Self {
        let flags = i.u8();
        let origin = i.vec3();
        let dir = i.vec3();
        let interval = (i.f32(), i.f32());
        Self {
            flags,
            origin,
            dir,
            interval,
        }
    }

    /// `true` when the flag bit `flag` is set.
    pub fn has(&self, flag: u8) -> bool {
        self.flags & flag != 0
    }

    /// The ray from the origin along `direction`, over the interval read, or `(0, +∞]` with
    /// [`flags::DEFAULT_INTERVAL`].
    pub fn ray(&self, direction: Vec3) -> Ray {
        let (t_min, t_max) = if self.has(flags::DEFAULT_INTERVAL) {
            (0.0, f32::INFINITY)
        } else {
            self.interval
        };
        Ray::with_interval(self.origin, direction, t_min, t_max)
    }
}

mod obj;
mod ray_box;
mod triangle;
mod watertight_bound;

pub use obj::*;
pub use ray_box::*;
pub use triangle::*;
pub use watertight_bound::*;

pub mod bvh;

pub mod tree_oracle;

pub mod bvh_load;

pub mod collapse_oracle;
pub mod diffuse_oracle;
pub mod halfedge;
pub mod loop_oracle;

// ---------------------------------------------------------------------------------------------
// Seeds
// ---------------------------------------------------------------------------------------------

/// One seed input: `(target, file name, bytes)`.
pub type Seed = (&'static str, String, Vec<u8>);

/// Regression inputs written from code, checked in as `fuzz/regressions/<target>/<name>`
/// (crash files found by the fuzzers are copied there as they are). A name starting with
/// `open-` is a reported bug not fixed yet: the replay test requires it to **still fail**
/// and asks for the prefix to be dropped once it passes.
pub fn regressions() -> Vec<Seed> {
    let b = |name: &str, bytes: Vec<u8>| ("ray_box", name.to_string(), bytes);
    let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
    let df = flags::DEFAULT_INTERVAL;
    let dflt = (0.0, f32::INFINITY);
    let mut v = vec![
        // +0 direction component with the origin below the slab, and a subnormal component
        // whose reciprocal overflows: was Some((inf, inf)) for +0, None for -0 (the ray
        // misses); fixed by the division path and the "no entry at +∞" rule of the slab test.
        b(
            "zero-sign-subnormal-dir",
            encode_ray_box(
                df,
                Vec3::new(-1.0, 0.5, 0.5),
                Vec3::new(0.0, 0.0, 1e-40),
                dflt,
                lo,
                hi,
            ),
        ),
        b(
            "zero-sign-neg-subnormal-dir",
            encode_ray_box(
                df,
                Vec3::new(-1.0, 0.5, 0.5),
                Vec3::new(0.0, 0.0, -1e-40),
                dflt,
                lo,
                hi,
            ),
        ),
    ];
    overlap::regressions(&mut v);
    v
}

/// Seeds that pass their target unjudged ([`Outcome::Unjudged`]), `(target, file name,
/// why)`: each sits on purpose exactly on a boundary that its target's oracle leaves to either
/// answer, or outside the oracle's domain, as a starting point for the fuzzer's mutations.
/// For them only "no panic" and the checks every input gets hold. The replay test requires
/// every other seed to reach a decisive check, and each of these to still be unjudged (a
/// seed that starts being judged leaves the list).
#[rustfmt::skip]
pub const UNJUDGED_SEEDS: &[(&str, &str, &str)] = &[
    ("ray_triangle", "seed-in-plane", "ray in the plane: det = 0, either answer"),
    ("ray_triangle", "seed-parallel-ulp-above", "det within its error bound of 0"),
    ("ray_triangle", "seed-collinear", "zero-area triangle: det = 0"),
    ("ray_triangle", "seed-origin-on-triangle", "t = 0 = t_min, within the t bound"),
    ("ray_triangle", "seed-tmax-just-short", "t one ulp past t_max, within the t bound"),
    ("ray_box", "seed-flat-box", "empty-width interval (entry = exit)"),
    ("ray_box", "seed-entry-at-tmax", "entry exactly at t_max, within the oracle's slack"),
    ("ray_box", "seed-aim-corner", "through a corner: entry = exit"),
    ("ray_box", "seed-nan-box", "a NaN corner: no oracle"),
    ("ray_sphere", "seed-subnormal-radius", "radius below the oracle's domain"),
    ("ray_quadric", "seed-cylinder-along-axis", "linear ray polynomial (qa = 0)"),
    ("ray_quadric", "seed-cone-generator", "along a generator: qa = 0"),
    ("bvh_load", "seed-box-coordinate", "the corruption is refused: not judged"),
    ("bvh_load", "seed-leaf-start", "the corruption is refused: not judged"),
    ("bvh_load", "seed-repeated-index", "the corruption is refused: not judged"),
    ("bvh_load", "seed-vertex-moved", "the corruption is refused: not judged"),
    ("bvh_load", "seed-nodes-swapped", "the corruption is refused: not judged"),
    ("bvh_load", "seed-truncated", "the corruption is refused: not judged"),
    ("kdtree", "seed-huge-1e20", "beyond the exact domain, rays at vertices and edges"),
    ("overlap", "seed-spheres-touching", "touching: inside the band"),
    ("overlap", "seed-sphere-box-corner", "touching: inside the band"),
    ("overlap", "seed-capsules-parallel", "touching: inside the band"),
    ("overlap", "seed-capsule-sphere", "touching: inside the band"),
    ("overlap", "seed-spheres-huge", "radii beyond the oracle's domain (2⁹⁰)"),
    ("overlap", "seed-obb-tiny", "sizes below the oracle's domain (2⁻⁹⁰)"),
];

/// The hard-case seed corpus, checked in as `fuzz/corpus/<target>/seed-<name>` (the replay test
/// verifies the files match; `HALFRAY_WRITE_SEEDS=1` rewrites them).
pub fn seeds() -> Vec<Seed> {
    let mut s = Vec::new();
    triangle::seeds(&mut s);
    ray_box::seeds(&mut s);
    sphere::seeds(&mut s);
    quadric::seeds(&mut s);
    obj::seeds(&mut s);
    scene::seeds(&mut s);
    bvh::seeds(&mut s);
    bvh_load::seeds(&mut s);
    halfedge::seeds(&mut s);
    grid::seeds(&mut s);
    kdtree::seeds(&mut s);
    overlap::seeds(&mut s);
    s
}

/// How far from 1 the length of a curved-surface hit's normal may be (unitless): one `f32`
/// normalisation, `v / |v|` (the squared length carries `gamma(3)`, halved by the square root,
/// which rounds once more, and each quotient rounds once: about `5u` in all), or an `f64`
/// normal rounded to `f32` (`√3/2·2u`). Four ulps of 1 (`8u`).
pub const HIT_NORMAL_LEN_TOL: f32 = 4.0 * f32::EPSILON;

/// The contract every curved-surface hit shares: `t` in the ray's interval, a unit normal
/// (within [`HIT_NORMAL_LEN_TOL`]).
fn check_hit_basics(ray: &Ray, h: &halfray_core::hit::Hit, ctx: &dyn Fn() -> String) {
    assert!(
        ray.contains(h.t),
        "t = {:e} outside the interval\n{}",
        h.t,
        ctx()
    );
    assert!(
        (h.normal.length() - 1.0).abs() <= HIT_NORMAL_LEN_TOL,
        "normal not unit\n{}",
        ctx()
    );
}

pub mod sphere;

pub mod quadric;

pub mod scene;

pub mod grid;

pub mod kdtree;

pub mod overlap;
