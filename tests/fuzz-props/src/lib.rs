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
];

/// Runs target `name` on `data`; `false` when no such target exists.
pub fn run(name: &str, data: &[u8]) -> bool {
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
        _ => return false,
    }
    true
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

/// Decodes a `ray_triangle` input: `flags: u8` ([`flags`]), `origin: 3×f32`,
/// `direction: 3×f32`, `t_min: f32`, `t_max: f32`, `v0, v1, v2: 3×f32 each` (69 bytes).
pub fn decode_ray_triangle(data: &[u8]) -> (Ray, [Vec3; 3]) {
    let mut i = Input::new(data);
    let fl = i.u8();
    let origin = i.vec3();
    let dir = i.vec3();
    let (t_min, t_max) = (i.f32(), i.f32());
    let v = [i.vec3(), i.vec3(), i.vec3()];
    let direction = if fl & flags::AIM != 0 {
        v[0] + (v[1] - v[0]) * dir.x + (v[2] - v[0]) * dir.y - origin
    } else {
        dir
    };
    let (t_min, t_max) = if fl & flags::DEFAULT_INTERVAL != 0 {
        (0.0, f32::INFINITY)
    } else {
        (t_min, t_max)
    };
    (Ray::with_interval(origin, direction, t_min, t_max), v)
}

/// Encodes a `ray_triangle` input (see [`decode_ray_triangle`]).
pub fn encode_ray_triangle(fl: u8, o: Vec3, d: Vec3, t: (f32, f32), v: [Vec3; 3]) -> Vec<u8> {
    Enc::new()
        .u8(fl)
        .vec3(o)
        .vec3(d)
        .f32(t.0)
        .f32(t.1)
        .vec3(v[0])
        .vec3(v[1])
        .vec3(v[2])
        .done()
}

/// Fuzz target `ray_triangle`: [`check_ray_triangle`] on [`decode_ray_triangle`]`(data)`, and
/// again with the triangle's vertices rotated and with the winding reversed (same surface).
pub fn ray_triangle(data: &[u8]) {
    let (ray, v) = decode_ray_triangle(data);
    check_ray_triangle(&ray, &v);
    check_ray_triangle(&ray, &[v[1], v[2], v[0]]);
    check_ray_triangle(&ray, &[v[0], v[2], v[1]]);
}

fn tri_context(ray: &Ray, v: &[Vec3; 3]) -> String {
    format!(
        "{}\n  v0 = {}\n  v1 = {}\n  v2 = {}",
        fmt_ray(ray),
        fmt_vec3(v[0]),
        fmt_vec3(v[1]),
        fmt_vec3(v[2])
    )
}

/// The properties of every triangle variant on one ray and triangle:
///
/// 1. **Contract** (all inputs, all [`TriangleVariant`]s): an invalid ray, a non-finite vertex
///    or a triangle with two equal vertices never hits; a hit has `t` finite and in
///    `(t_min, t_max]`, barycentrics `b0 = 1 − b1 − b2`, `b1`, `b2` finite and within
///    [`BARYCENTRIC_SLACK`] of `[0, 1]`, `front_face` agreeing with the sign of `d·ng` when
///    that sign is clear (`|cos| > 10⁻³`), and [`TriangleHit::to_hit`]'s point within its own
///    error bound of `Σ bᵢ·vᵢ` (when nothing overflows).
/// 2. **Agreement with the f64 reference** (`watertight` and `watertight-f32`, in the domain
///    of [`WatertightBound`]): when every reference edge function is farther from zero than
///    its error bound (equivalently, every reference barycentric `|bᵢ|` exceeds
///    `errᵢ/|det|`) and the reference `t` is farther from `t_min` and `t_max` than the `t`
///    bound, the variant hits exactly when [`F64Reference::solve`] hits in the interval, and
///    then its `t` and barycentrics are within the bounds of the reference's.
pub fn check_ray_triangle(ray: &Ray, v: &[Vec3; 3]) {
    let valid = ray.is_valid();
    let finite = v.iter().all(|p| p.is_finite());
    let repeated = v[0] == v[1] || v[1] == v[2] || v[2] == v[0];
    let mut got = [None; TriangleVariant::ALL.len()];
    for (k, var) in TriangleVariant::ALL.into_iter().enumerate() {
        let h = var.intersect(ray, v);
        if let Some(h) = h {
            let ctx = || format!("variant {}: {h:?}\n{}", var.name(), tri_context(ray, v));
            assert!(valid, "invalid ray hit\n{}", ctx());
            assert!(finite, "triangle with a non-finite vertex hit\n{}", ctx());
            assert!(
                !repeated,
                "degenerate triangle (repeated vertex) hit\n{}",
                ctx()
            );
            // `watertight-f32` computes its edge functions and barycentrics in `f32` products,
            // sound only while no product underflows or overflows (its docs: triangles of
            // ≳ 1e19 or ≲ 1e-19 and underflowing projections are outside its domain); there
            // its barycentrics may leave [0, 1] by more than the slack (regression input
            // `ci-crash-c5997b10`: 4.8e30 and subnormal coordinates), so the range is
            // checked only inside that domain.
            let f32_domain = var != TriangleVariant::WatertightF32
                || (!projection_underflows(ray, v) && f32_products_in_range(ray, v));
            check_hit_contract(ray, v, &h, f32_domain, &ctx);
        }
        got[k] = h;
    }
    if !(valid && finite) {
        return;
    }
    let Some(bound) = WatertightBound::new(ray, v) else {
        return;
    };
    for (k, var) in TriangleVariant::ALL.into_iter().enumerate() {
        let eval = match var {
            TriangleVariant::Watertight => EdgeEval::ExactF64,
            TriangleVariant::WatertightF32 => EdgeEval::F32,
            _ => continue,
        };
        bound.check_agreement(var.name(), eval, ray, v, got[k]);
    }
}

/// `true` when every vertex coordinate relative to the ray origin is zero or within
/// `[1e-19, 1e19]` in magnitude: the range where `watertight-f32`'s `f32` products neither
/// overflow nor underflow (its documented domain).
pub fn f32_products_in_range(ray: &Ray, v: &[Vec3; 3]) -> bool {
    v.iter().all(|p| {
        (*p - ray.origin)
            .to_array()
            .iter()
            .all(|&c| c == 0.0 || (1.0e-19..=1.0e19).contains(&c.abs()))
    })
}

fn check_hit_contract(
    ray: &Ray,
    v: &[Vec3; 3],
    h: &TriangleHit,
    barycentric_domain: bool,
    ctx: &dyn Fn() -> String,
) {
    assert!(ray.contains(h.t), "t outside (t_min, t_max]\n{}", ctx());
    assert!(h.t.is_finite(), "non-finite t\n{}", ctx());
    let (b0, b1, b2) = (h.b0(), h.b1, h.b2);
    for (name, b) in [("b0", b0), ("b1", b1), ("b2", b2)] {
        assert!(b.is_finite(), "{name} = {b:e} is not finite\n{}", ctx());
        assert!(
            !barycentric_domain || (-BARYCENTRIC_SLACK..=1.0 + BARYCENTRIC_SLACK).contains(&b),
            "{name} = {b:e} is not within BARYCENTRIC_SLACK = {BARYCENTRIC_SLACK:e} of [0, 1]\n{}",
            ctx()
        );
    }
    // Orientation, for well-conditioned configurations only: the sign of d·n (f64, with a
    // rigorous bound on its own rounding, since the f64 differences of far-apart f32 values are
    // not exact) is clear, the angle is not grazing (|cos| > 1e-3), and the triangle is not a
    // sliver relative to its distance from the origin (|n| ≥ 1e-2·M², M = max |vᵢ − o|), so
    // that f32 rounding of any variant (≈ 6u·M²·|d|) cannot flip it.
    let u64 = F64_UNIT_ROUNDOFF;
    let e1 = v[1].as_dvec3() - v[0].as_dvec3();
    let e2 = v[2].as_dvec3() - v[0].as_dvec3();
    let n = e1.cross(e2);
    let (a, b) = (e1.abs(), e2.abs());
    let n_err = DVec3::new(
        a.y * b.z + a.z * b.y,
        a.z * b.x + a.x * b.z,
        a.x * b.y + a.y * b.x,
    ) * (4.0 * u64);
    let d = ray.direction.as_dvec3();
    let dn = d.dot(n);
    let dn_err = d.abs().dot(n_err) + 3.0 * u64 * d.abs().dot(n.abs()) + 1e-300;
    let o = ray.origin.as_dvec3();
    let m = v
        .iter()
        .map(|p| (p.as_dvec3() - o).length())
        .fold(0.0, f64::max);
    let tame = (1e-18..=1e18).contains(&m) && (1e-18..=1e18).contains(&d.length());
    if tame
        && dn.abs() > 2.0 * dn_err
        && dn.abs() > 1e-3 * d.length() * n.length()
        && n.length() >= 1e-2 * m * m
    {
        assert_eq!(
            h.front_face,
            dn < 0.0,
            "front_face disagrees with d·ng\n{}",
            ctx()
        );
    }
    // Hit-point reconstruction: |point − Σ bᵢvᵢ| ≤ point_error (+ subnormal slack).
    let hit = h.to_hit(v);
    if hit.point.is_finite() && hit.point_error.is_finite() {
        let exact = v[0].as_dvec3() * f64::from(b0)
            + v[1].as_dvec3() * f64::from(b1)
            + v[2].as_dvec3() * f64::from(b2);
        let err = (hit.point.as_dvec3() - exact).abs();
        let allowed = hit.point_error.as_dvec3() * (1.0 + 1e-6) + DVec3::splat(UNDERFLOW_ABS);
        assert!(
            err.cmple(allowed).all(),
            "Hit::point farther than point_error from Σ bᵢvᵢ: error {err:?}, bound {:?}\n{}",
            hit.point_error,
            ctx()
        );
    }
}

/// Relative error of one sheared `f32` coordinate of the watertight test,
/// `x' = fl(fl(p − o)_kx − fl(fl(d_kx/d_kz) · fl(p − o)_kz))`, with respect to the magnitude
/// `X = |(p − o)_kx| + |(d_kx/d_kz)·(p − o)_kz|`: the first term carries two roundings (the
/// subtraction `p − o` and the final subtraction), the second four (`p − o`, the shear
/// division, the product, the final subtraction), so `|x' − x| ≤ gamma(4)·X` (standard model,
/// no underflow; see [`UNDERFLOW_ABS`]). Same for `y'`.
pub const PROJ_REL: f64 = gamma(4) as f64;

/// Relative error of the scaled depth `z' = fl(fl(1/d_kz) · fl(p − o)_kz)`: three roundings,
/// relative to `Z = |(p − o)_kz / d_kz|`.
pub const DEPTH_REL: f64 = gamma(3) as f64;

/// Absolute error allowance per `f32` coordinate for gradual underflow: an operation whose
/// result is subnormal has an absolute error of at most `2⁻¹⁵⁰` instead of a relative one;
/// the four operations of a projection contribute at most `4·2⁻¹⁵⁰ < 2⁻¹⁴⁶` (the later
/// roundings scale it by at most `1 + gamma(4)`).
pub const UNDERFLOW_ABS: f64 = f32::MIN_POSITIVE as f64 / 1_048_576.0; // 2^-146

/// Relative allowance for the reference's own error (and this file's `f64` recomputation of
/// the same edge functions): the `f64` shear, products and sums carry a few roundings of
/// `2⁻⁵³ ≈ 1.1·10⁻¹⁶` each; `10⁻¹³` is a thousand times that.
pub const REF_REL: f64 = 1e-13;

/// Factor applied on top of the first-order bounds: covers the second-order terms dropped in
/// the derivations and the rounding of the bound's own `f64` evaluation.
pub const BOUND_SAFETY: f64 = 2.0;

/// Domain of the agreement check: every sheared magnitude `X`, `Y`, `Z` (see [`PROJ_REL`]) is
/// at most `2⁶⁰`, so no `f32` product of two of them (`watertight-f32` edge functions) and no
/// projection overflows. Beyond it (about 10¹⁸ from the ray origin) only the contract is
/// checked.
pub const DOMAIN_MAX: f64 = 1_152_921_504_606_846_976.0; // 2^60

/// Domain of the agreement check: the dominant direction component satisfies
/// `|d_kz| ≥ 2⁻¹⁰⁰`, so the `f32` shear `1/d_kz` is finite and normal.
pub const DOMAIN_MIN_DOMINANT_DIRECTION: f64 = 7.888_609_052_210_118e-31; // 2^-100

/// How a variant evaluates its edge functions from the sheared `f32` coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeEval {
    /// `watertight`: `f64` difference of exact `f64` products (one rounding, `2⁻⁵³` of the
    /// products), `det`, `t` and barycentrics in `f64`, rounded once to `f32`.
    ExactF64,
    /// `watertight-f32`: `f32` products and difference (`gamma(2)` of the products; signs are
    /// still exact by monotone rounding, zeros recomputed exactly), `det`, `t` and the
    /// barycentrics in `f32` (a further `gamma(3)`–`gamma(5)`).
    F32,
}

/// The error bound of the watertight test against the exact result, for one ray and triangle.
///
/// Derivation. With `(xᵢ, yᵢ, zᵢ)` the exact sheared coordinates of vertex `i` and
/// `(Xᵢ, Yᵢ, Zᵢ)` their magnitudes ([`PROJ_REL`], [`DEPTH_REL`]), the `f32` coordinates are
/// within `dXᵢ = PROJ_REL·Xᵢ + UNDERFLOW_ABS` (same for `y`, `z` with `DEPTH_REL`). An edge
/// function `e = x_p·y_q − y_p·x_q` evaluated on perturbed coordinates moves by at most
/// `D = (X_p + dX_p)·dY_q + Y_q·dX_p + (Y_p + dY_p)·dX_q + X_q·dY_p`; its evaluation adds
/// `eval·P` with `P = (X_p + dX_p)(Y_q + dY_q) + (Y_p + dY_p)(X_q + dX_q)`, and the reference
/// `REF_REL·P`. So `errᵢ = BOUND_SAFETY·(D + (eval + REF_REL)·P)`.
///
/// * If every exact `|eᵢ| > errᵢ`, the variant's edge signs equal the exact ones, so it is
///   inside exactly when the reference is (reference barycentric `|bᵢ| = |eᵢ/det|` farther
///   than `errᵢ/|det|` from an edge; `det = Σ eᵢ`).
/// * Then `t = Σ eᵢzᵢ / Σ eᵢ` moves by at most
///   `(Σ |eᵢ|·dZᵢ + Σ errᵢ·(|zᵢ| + dZᵢ) + |t|·Σ errᵢ) / (|det| − Σ errᵢ)`, plus the
///   evaluation of `t` and its rounding to `f32`; a barycentric `bᵢ = eᵢ/det` by at most
///   `(errᵢ + |bᵢ|·Σ errᵢ) / (|det| − Σ errᵢ)` plus its rounding.
///
/// Domain ([`WatertightBound::new`] returns `None` outside it): valid ray, finite vertices,
/// every `X, Y, Z ≤` [`DOMAIN_MAX`], `|d_kz| ≥` [`DOMAIN_MIN_DOMINANT_DIRECTION`]; for
/// `watertight-f32` also `2⁻¹⁰⁰ ≤ |det|`, `Σ |eᵢ·zᵢ| ≤ 2¹²⁰` (its `f32` `det`, `1/det` and
/// `t` neither underflow nor overflow), and for both `|t| ≤ 2¹²⁰`.
#[derive(Clone, Copy, Debug)]
pub struct WatertightBound {
    /// Exact-ish (`f64`) sheared coordinates `x, y, z` per vertex.
    pub x: [f64; 3],
    /// `y` per vertex.
    pub y: [f64; 3],
    /// `z` per vertex.
    pub z: [f64; 3],
    /// Magnitudes `X` per vertex.
    pub mx: [f64; 3],
    /// Magnitudes `Y` per vertex.
    pub my: [f64; 3],
    /// Magnitudes `Z` per vertex.
    pub mz: [f64; 3],
}

/// `true` when a quantity of the watertight projection of `v` (`p − o`, the shear products
/// `s·(p − o)_kz`, the sheared `x'`, `y'`) is a non-zero subnormal, or the shear `d_i/d_kz`
/// itself underflows: its rounding is then absolute, not relative, and the projected ray is no
/// longer the exact one up to `f32` rounding (the `Watertight` docs' domain limit).
pub fn projection_underflows(ray: &Ray, v: &[Vec3; 3]) -> bool {
    let d = ray.direction;
    let a = d.abs();
    let kz = a.max_position();
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    // Each quantity in f64 from the f32 values the test actually rounds: below the f32 normal
    // range (and not exactly zero), its f32 rounding is absolute, or it vanishes.
    let sub = |x: f64| x != 0.0 && x.abs() < f64::from(f32::MIN_POSITIVE);
    let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    let dk = f64::from(d[kz]);
    sub(f64::from(d[kx]) / dk)
        || sub(f64::from(d[ky]) / dk)
        || v.iter().any(|p| {
            let q = *p - ray.origin;
            let q64 = p.as_dvec3() - ray.origin.as_dvec3();
            let qz = f64::from(q[kz]);
            let (px, py, pz) = (f64::from(sx) * qz, f64::from(sy) * qz, f64::from(sz) * qz);
            let (px32, py32) = (sx * q[kz], sy * q[kz]);
            [
                q64.x,
                q64.y,
                q64.z,
                px,
                py,
                pz,
                f64::from(q[kx]) - f64::from(px32),
                f64::from(q[ky]) - f64::from(py32),
            ]
            .into_iter()
            .any(sub)
        })
}

/// The edge functions in the watertight test's order: `e0 = e(v2, v1)`, `e1 = e(v0, v2)`,
/// `e2 = e(v1, v0)` with `e(p, q) = x_p·y_q − y_p·x_q`; `bᵢ = eᵢ / Σ e`.
/// Smallest `|det|` (sum of the sheared edge functions) inside the `f32` variant's domain:
/// 2^-100 rounded down, where its `f32` products stay clear of the subnormal range.
pub const F32_DET_MIN: f64 = 7.9e-31;

/// Largest `Σ|eᵢ·zᵢ|` (and `|t|`) inside the `f32` variant's domain: 2^120 ≈ 1.33e36 rounded
/// down, so the scaled depth sum cannot overflow `f32` (max ≈ 2^128).
pub const F32_DEPTH_SUM_MAX: f64 = 1.3e36;

const EDGE_PAIRS: [(usize, usize); 3] = [(2, 1), (0, 2), (1, 0)];

impl WatertightBound {
    /// The sheared coordinates (same axis permutation as the watertight test: `kz` is the
    /// largest `|dᵢ|`, ties to the lower index), or `None` outside the domain.
    pub fn new(ray: &Ray, v: &[Vec3; 3]) -> Option<Self> {
        if !ray.is_valid() || !v.iter().all(|p| p.is_finite()) {
            return None;
        }
        let d = ray.direction.as_dvec3();
        let o = ray.origin.as_dvec3();
        let a = d.abs();
        let kz = a.max_position();
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        if a[kz] < DOMAIN_MIN_DOMINANT_DIRECTION {
            return None;
        }
        let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
        let mut b = Self {
            x: [0.0; 3],
            y: [0.0; 3],
            z: [0.0; 3],
            mx: [0.0; 3],
            my: [0.0; 3],
            mz: [0.0; 3],
        };
        for (i, vi) in v.iter().enumerate() {
            let p = vi.as_dvec3() - o;
            b.x[i] = p[kx] - sx * p[kz];
            b.y[i] = p[ky] - sy * p[kz];
            b.z[i] = sz * p[kz];
            b.mx[i] = p[kx].abs() + (sx * p[kz]).abs();
            b.my[i] = p[ky].abs() + (sy * p[kz]).abs();
            b.mz[i] = b.z[i].abs();
        }
        let max =
            b.mx.iter()
                .chain(&b.my)
                .chain(&b.mz)
                .fold(0.0f64, |m, &x| m.max(x));
        (max <= DOMAIN_MAX).then_some(b)
    }

    /// Edge functions `eᵢ` (`f64`, error `≤ REF_REL·P`).
    pub fn edges(&self) -> [f64; 3] {
        EDGE_PAIRS.map(|(p, q)| self.x[p] * self.y[q] - self.y[p] * self.x[q])
    }

    /// Error bounds `errᵢ` of the variant's edge functions (see the type's docs).
    pub fn edge_errors(&self, eval: EdgeEval) -> [f64; 3] {
        let (eval_rel, eval_abs) = match eval {
            EdgeEval::ExactF64 => (F64_UNIT_ROUNDOFF, 0.0),
            EdgeEval::F32 => (f64::from(gamma(2)), 2.0 * UNDERFLOW_ABS),
        };
        let dx = self.mx.map(|m| PROJ_REL * m + UNDERFLOW_ABS);
        let dy = self.my.map(|m| PROJ_REL * m + UNDERFLOW_ABS);
        EDGE_PAIRS.map(|(p, q)| {
            let d = (self.mx[p] + dx[p]) * dy[q]
                + self.my[q] * dx[p]
                + (self.my[p] + dy[p]) * dx[q]
                + self.mx[q] * dy[p];
            let prod = (self.mx[p] + dx[p]) * (self.my[q] + dy[q])
                + (self.my[p] + dy[p]) * (self.mx[q] + dx[q]);
            BOUND_SAFETY * (d + (eval_rel + REF_REL) * prod + eval_abs)
        })
    }

    /// Property 2 of [`check_ray_triangle`] for one variant's result `got`.
    pub fn check_agreement(
        &self,
        name: &str,
        eval: EdgeEval,
        ray: &Ray,
        v: &[Vec3; 3],
        got: Option<TriangleHit>,
    ) {
        if projection_underflows(ray, v) {
            return; // outside the documented domain of the sheared test
        }
        let e = self.edges();
        let err = self.edge_errors(eval);
        if (0..3).any(|i| e[i].abs().partial_cmp(&err[i]) != Some(core::cmp::Ordering::Greater)) {
            return; // within the error bound of an edge (or det = 0): either answer is right
        }
        let inside = e.iter().all(|&x| x > 0.0) || e.iter().all(|&x| x < 0.0);
        let reference = F64Reference::solve(ray, v);
        let ctx = || {
            format!(
                "variant {name}: got {got:?}\n  reference {reference:?}\n  edges {e:?}\n  \
                 edge error bounds {err:?}\n{}",
                tri_context(ray, v)
            )
        };
        if !inside {
            assert!(
                got.is_none(),
                "hit although the reference is outside by more than the bound\n{}",
                ctx()
            );
            return;
        }
        let Some((t_ref, b_ref)) = reference else {
            panic!(
                "F64Reference::solve reports no hit for a point clearly inside\n{}",
                ctx()
            );
        };
        let det: f64 = e.iter().sum();
        let sum_err: f64 = err.iter().sum();
        let denom = det.abs() - sum_err;
        let ez: f64 = (0..3).map(|i| (e[i] * self.z[i]).abs()).sum();
        if eval == EdgeEval::F32 && !(det.abs() >= F32_DET_MIN && ez <= F32_DEPTH_SUM_MAX) {
            return; // outside the f32 variant's domain (2^-100 ≤ |det|, Σ|e·z| ≤ 2^120)
        }
        if t_ref.is_nan() || t_ref.abs() > F32_DEPTH_SUM_MAX {
            return;
        }
        let dz = self.mz.map(|m| DEPTH_REL * m + UNDERFLOW_ABS);
        let mut dt = ((0..3)
            .map(|i| e[i].abs() * dz[i] + err[i] * (self.z[i].abs() + dz[i]))
            .sum::<f64>()
            + t_ref.abs() * sum_err)
            / denom;
        let (t_eval, b_eval) = match eval {
            EdgeEval::ExactF64 => (REF_REL, F64_UNIT_ROUNDOFF),
            EdgeEval::F32 => (f64::from(gamma(6)), f64::from(gamma(3))),
        };
        dt += t_eval * ez / det.abs();
        if eval == EdgeEval::F32 {
            // The f32 products eᵢ·zᵢ round absolutely (2⁻¹⁴⁹) when they are subnormal.
            dt += 3.0 * f64::from(f32::from_bits(1)) / det.abs();
        }
        dt += f64::from(F32_UNIT_ROUNDOFF) * t_ref.abs() + 1.5e-45;
        dt *= BOUND_SAFETY;
        let (t_min, t_max) = (f64::from(ray.t_min), f64::from(ray.t_max));
        if !((t_ref - t_min).abs() > dt && (t_ref - t_max).abs() > dt) {
            return; // within the t bound of an interval end: either answer is right
        }
        let expect_hit = t_ref > t_min && t_ref <= t_max;
        match got {
            None => assert!(
                !expect_hit,
                "missed: the reference hits at t = {t_ref:e} (bound {dt:e}) with every \
                 barycentric farther from an edge than the bound\n{}",
                ctx()
            ),
            Some(h) => {
                assert!(
                    expect_hit,
                    "hit although the reference t = {t_ref:e} is outside the interval by more \
                     than the bound {dt:e}\n{}",
                    ctx()
                );
                assert!(
                    (f64::from(h.t) - t_ref).abs() <= dt,
                    "t = {:e} differs from the reference {t_ref:e} by more than the bound \
                     {dt:e}\n{}",
                    h.t,
                    ctx()
                );
                for (i, b) in [(1, h.b1), (2, h.b2)] {
                    let db = BOUND_SAFETY
                        * ((err[i] + b_ref[i].abs() * sum_err) / denom
                            + b_eval * b_ref[i].abs()
                            + 1.5e-45);
                    assert!(
                        (f64::from(b) - b_ref[i]).abs() <= db,
                        "b{i} = {b:e} differs from the reference {:e} by more than the bound \
                         {db:e}\n{}",
                        b_ref[i],
                        ctx()
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// ray_box
// ---------------------------------------------------------------------------------------------

/// Decodes a `ray_box` input: `flags: u8` ([`flags`]), `origin: 3×f32`, `direction: 3×f32`,
/// `t_min: f32`, `t_max: f32`, `a: 3×f32`, `b: 3×f32` (the box `[a, b]`, or
/// `[min(a, b), max(a, b)]` with [`flags::ORDERED`]); 57 bytes.
pub fn decode_ray_box(data: &[u8]) -> (Ray, Aabb) {
    let mut i = Input::new(data);
    let fl = i.u8();
    let origin = i.vec3();
    let dir = i.vec3();
    let (t_min, t_max) = (i.f32(), i.f32());
    let (a, b) = (i.vec3(), i.vec3());
    let bx = if fl & flags::ORDERED != 0 {
        Aabb::new(a.min(b), a.max(b))
    } else {
        Aabb::new(a, b)
    };
    let direction = if fl & flags::AIM != 0 {
        bx.min + (bx.max - bx.min) * dir - origin
    } else {
        dir
    };
    let (t_min, t_max) = if fl & flags::DEFAULT_INTERVAL != 0 {
        (0.0, f32::INFINITY)
    } else {
        (t_min, t_max)
    };
    (Ray::with_interval(origin, direction, t_min, t_max), bx)
}

/// Encodes a `ray_box` input (see [`decode_ray_box`]).
pub fn encode_ray_box(fl: u8, o: Vec3, d: Vec3, t: (f32, f32), a: Vec3, b: Vec3) -> Vec<u8> {
    Enc::new()
        .u8(fl)
        .vec3(o)
        .vec3(d)
        .f32(t.0)
        .f32(t.1)
        .vec3(a)
        .vec3(b)
        .done()
}

/// Fuzz target `ray_box`: [`check_ray_box`] on [`decode_ray_box`]`(data)`.
pub fn ray_box(data: &[u8]) {
    let (ray, bx) = decode_ray_box(data);
    check_ray_box(&ray, &bx);
}

/// Relative error of the `f64` oracle's slab distances `(bound − o)/d`: the difference of two
/// `f32` values and the quotient are each rounded once in `f64` (`2·2⁻⁵³`), so the overlap
/// `exit − enter` is known to within `≈ 4.4·10⁻¹⁶·max(|enter|, |exit|)`. The slab test claims
/// to be exactly conservative (Ize's padding), so the only slack the miss check needs is the
/// oracle's; `10⁻¹²` is over a thousand times that.
pub const SLAB_ORACLE_REL: f64 = 1e-12;

/// How far (relative to the distances involved) the exact interval may be empty and the `f32`
/// slab test still report a hit: its near distances carry `gamma(3)` and its far distances
/// are padded by `2·gamma(3)` ([`halfray_core::aabb::SLAB_FAR_SCALE`]), about `5·10⁻⁷` in all;
/// `2⁻¹⁶ ≈ 1.5·10⁻⁵` leaves a wide margin. Checked only in the "tame" domain of
/// [`check_ray_box`].
pub const SLAB_FALSE_HIT_REL: f64 = 1.0 / 65_536.0;

/// The exact slab interval, computed in `f64`: `(enter, exit)`, empty when `enter > exit`.
/// A zero direction component constrains nothing when the origin lies in the closed slab and
/// empties the interval otherwise; for `d > 0` the near plane is `min`, for `d < 0` it is
/// `max`, so an inverted box (`min > max`) is empty.
pub fn exact_slab_interval(ray: &Ray, bx: &Aabb) -> (f64, f64) {
    let mut enter = f64::from(ray.t_min);
    let mut exit = f64::from(ray.t_max);
    for k in 0..3 {
        let o = f64::from(ray.origin[k]);
        let d = f64::from(ray.direction[k]);
        let (lo, hi) = (f64::from(bx.min[k]), f64::from(bx.max[k]));
        if d == 0.0 {
            if !(lo <= o && o <= hi) {
                return (f64::INFINITY, f64::NEG_INFINITY);
            }
            continue;
        }
        let (near, far) = if d > 0.0 { (lo, hi) } else { (hi, lo) };
        enter = enter.max((near - o) / d);
        exit = exit.min((far - o) / d);
    }
    (enter, exit)
}

fn opt_bits(r: Option<(f32, f32)>) -> Option<(u32, u32)> {
    r.map(|(a, b)| (a.to_bits(), b.to_bits()))
}

/// The properties of [`Aabb::intersect_ray`]:
///
/// 1. **Defined answers:** an invalid ray (NaN or infinite origin/direction, zero direction,
///    NaN or inverted interval) gives `None`; the result is deterministic; a hit has
///    `t_min ≤ t_enter ≤ t_exit ≤ t_max`; the plain (unpadded) slab test never hits where the
///    padded one misses. NaN *box* coordinates are allowed and only need a deterministic
///    answer (the BVH never builds such boxes).
/// 2. **±0:** flipping the sign of any zero direction component gives the bit-identical result
///    (module docs of [`halfray_core::aabb`]).
/// 3. **Never a false miss:** for a finite box, when the exact (`f64`) interval overlap
///    `exit − enter` exceeds `SLAB_ORACLE_REL·max(|enter|, |exit|)` (or is infinite), the test
///    hits. Domain: every `|bound − origin|` on an axis with non-zero direction is at most
///    `f32::MAX` (beyond it the `f32` distances cannot be represented).
/// 4. **No gross false hit:** in the tame domain (every non-zero `|dᵢ| ∈ [2⁻¹²⁰, 2¹²⁰]`,
///    every finite slab distance zero or of magnitude in `[2⁻¹²⁰, 2¹²⁰]`), when the exact
///    interval is empty because a zero-direction axis excludes the origin, or by a gap of more
///    than [`SLAB_FALSE_HIT_REL`] of the distances, the test misses.
pub fn check_ray_box(ray: &Ray, bx: &Aabb) {
    let got = bx.intersect_ray(ray);
    let ctx = || {
        format!(
            "got {got:?}\n{}\n  box min {}\n  box max {}",
            fmt_ray(ray),
            fmt_vec3(bx.min),
            fmt_vec3(bx.max)
        )
    };
    assert_eq!(
        opt_bits(got),
        opt_bits(bx.intersect_ray(ray)),
        "not deterministic\n{}",
        ctx()
    );
    if !ray.is_valid() {
        assert!(got.is_none(), "invalid ray hits a box\n{}", ctx());
        return;
    }
    if let Some((te, tx)) = got {
        assert!(
            ray.t_min <= te && te <= tx && tx <= ray.t_max,
            "returned interval not inside [t_min, t_max] or inverted\n{}",
            ctx()
        );
    }
    if let Some(slab) = SlabRay::new(ray)
        && bx
            .intersect_slab_plain(&slab, ray.t_min, ray.t_max)
            .is_some()
    {
        assert!(
            got.is_some(),
            "plain slab test hits, padded one misses\n{}",
            ctx()
        );
    }
    for k in 0..3 {
        if ray.direction[k] == 0.0 {
            let mut flipped = *ray;
            flipped.direction[k] = -ray.direction[k];
            let other = bx.intersect_ray(&flipped);
            assert_eq!(
                opt_bits(got),
                opt_bits(other),
                "result depends on the sign of the zero direction component {k}: \
                 flipped gives {other:?}\n{}",
                ctx()
            );
        }
    }
    if !bx.is_finite() {
        return;
    }
    let representable = (0..3).all(|k| {
        ray.direction[k] == 0.0
            || [bx.min[k], bx.max[k]]
                .iter()
                .all(|&b| (f64::from(b) - f64::from(ray.origin[k])).abs() <= f64::from(f32::MAX))
    });
    if !representable {
        return;
    }
    let (enter, exit) = exact_slab_interval(ray, bx);
    // An entry beyond f32::MAX rounds to +∞ (an exit below −f32::MAX to −∞), which is no hit
    // (module docs of the slab test).
    let must_hit = enter < exit
        && enter <= f64::from(f32::MAX)
        && exit >= -f64::from(f32::MAX)
        && (enter.is_infinite()
            || exit.is_infinite()
            || exit - enter > SLAB_ORACLE_REL * enter.abs().max(exit.abs()));
    if must_hit {
        assert!(
            got.is_some(),
            "missed a box the exact ray crosses: exact interval [{enter:e}, {exit:e}]\n{}",
            ctx()
        );
    }
    // Property 4, in the tame domain.
    const LO: f64 = 7.52316384526264e-37; // 2^-120
    const HI: f64 = 1.329227995784916e36; // 2^120
    let tame_dir = (0..3).all(|k| {
        let d = f64::from(ray.direction[k]).abs();
        d == 0.0 || (LO..=HI).contains(&d)
    });
    let tame_t = (0..3).all(|k| {
        let d = f64::from(ray.direction[k]);
        d == 0.0
            || [bx.min[k], bx.max[k]].iter().all(|&b| {
                let t = ((f64::from(b) - f64::from(ray.origin[k])) / d).abs();
                t == 0.0 || (LO..=HI).contains(&t)
            })
    });
    if tame_dir && tame_t {
        let excluded_by_zero_axis = enter == f64::INFINITY && exit == f64::NEG_INFINITY;
        let gap_exceeds = enter.is_finite()
            && exit.is_finite()
            && enter - exit > SLAB_FALSE_HIT_REL * enter.abs().max(exit.abs());
        if excluded_by_zero_axis || gap_exceeds {
            assert!(
                got.is_none(),
                "hit a box the exact ray misses: exact interval [{enter:e}, {exit:e}]\n{}",
                ctx()
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// obj_file
// ---------------------------------------------------------------------------------------------

/// The path handed to the OBJ parser; every error message must start with it.
pub const OBJ_PATH: &str = "fuzz/input.obj";

/// Fuzz target `obj_file`: the bytes as lossy UTF-8 text (and, when they are valid UTF-8,
/// as-is) through [`check_obj`].
pub fn obj_file(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    check_obj(&text);
}

/// Properties of `halfray::obj::parse_obj` on any text: never a panic; `Ok` has every
/// position finite and every triangle index in range, and writing it back in the canonical
/// form (`v x y z` with Rust's shortest round-trip floats, `f a b c` 1-based) and parsing
/// again gives the same mesh bit for bit; `Err`'s message starts with the path.
pub fn check_obj(text: &str) {
    let path = Path::new(OBJ_PATH);
    match halfray::obj::parse_obj(text, path) {
        Ok(m) => {
            let n = m.positions.len();
            for p in &m.positions {
                assert!(
                    p.is_finite(),
                    "non-finite position {p:?} accepted\n{text:?}"
                );
            }
            for t in &m.triangles {
                assert!(
                    t.iter().all(|&i| (i as usize) < n),
                    "triangle {t:?} indexes past {n} positions\n{text:?}"
                );
            }
            let mut canon = String::new();
            for p in &m.positions {
                canon.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
            }
            for t in &m.triangles {
                canon.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
            }
            let again = halfray::obj::parse_obj(&canon, path)
                .unwrap_or_else(|e| panic!("canonical re-write does not parse: {e}\n{canon}"));
            let bits = |m: &halfray::obj::ObjMesh| {
                m.positions
                    .iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&again),
                bits(&m),
                "positions do not round-trip\n{text:?}"
            );
            assert_eq!(again.triangles, m.triangles, "triangles do not round-trip");
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.starts_with(OBJ_PATH) && msg.len() > OBJ_PATH.len() + 2,
                "error message does not start with the path: {msg:?}\n{text:?}"
            );
        }
    }
}

pub mod bvh {
    //! The `bvh` target: small arbitrary triangle soups and rays, BVH against brute force.
    //!
    //! Layout: `flags: u8` (bit 0: quantized vertex coordinates ([`Input::q`]), else raw
    //! `f32`; bit 1: [`BuildOptions::exclude_non_finite`]; bit 2: leaves of one primitive),
    //! `vertex count: u8` (mod 25), `triangle count: u8` (mod 17), the vertices, the
    //! triangles (three `u8` vertex indices each, taken mod `vertex count + 2` so that some are
    //! out of range), then rays until the input ends (at most 8), each `flags: u8` (bit 0:
    //! quantized origin and direction; bit 1: aim at `p_i + s·(p_j − p_i)` for two vertex bytes
    //! and `s = byte mod 9 / 8`; bit 2: interval from two `f32`s, else `(0, +∞]`), origin,
    //! direction, then the aim or interval bytes.

    use super::{Enc, Input, fmt_ray, fmt_vec3};
    use glam::Vec3;
    use halfray_core::aabb::Aabb;
    use halfray_core::bvh::wide::{Bvh8, LeafGroup, WideNode, group_capacity};
    use halfray_core::bvh::{
        BuildOptions, Bvh, BvhError, BvhNode, PrimitiveSource, TriangleMesh, index_capacity,
        node_capacity,
    };
    use halfray_core::ray::Ray;
    use halfray_core::triangle::{MollerTrumbore, TriangleHit, TriangleIntersector, Watertight};

    /// The decoded input.
    #[derive(Clone, Debug)]
    pub struct Soup {
        /// Vertex positions.
        pub positions: Vec<Vec3>,
        /// Triangles (indices may be out of range).
        pub triangles: Vec<[u32; 3]>,
        /// Build options.
        pub options: BuildOptions,
        /// Rays.
        pub rays: Vec<Ray>,
    }

    /// Decodes a `bvh` input (see the module docs).
    pub fn decode(data: &[u8]) -> Soup {
        let mut i = Input::new(data);
        let fl = i.u8();
        let nv = usize::from(i.u8()) % 25;
        let nt = usize::from(i.u8()) % 17;
        let positions: Vec<Vec3> = (0..nv)
            .map(|_| if fl & 1 != 0 { i.qvec3() } else { i.vec3() })
            .collect();
        let m = nv as u32 + 2;
        let triangles = (0..nt)
            .map(|_| {
                [
                    u32::from(i.u8()) % m,
                    u32::from(i.u8()) % m,
                    u32::from(i.u8()) % m,
                ]
            })
            .collect();
        let options = BuildOptions {
            max_leaf_size: if fl & 4 != 0 { 1 } else { 4 },
            exclude_non_finite: fl & 2 != 0,
            ..BuildOptions::default()
        };
        let mut rays = Vec::new();
        while !i.is_empty() && rays.len() < 8 {
            let rf = i.u8();
            let (o, d) = if rf & 1 != 0 {
                (i.qvec3(), i.qvec3())
            } else {
                (i.vec3(), i.vec3())
            };
            let mut ray = Ray::new(o, d);
            if rf & 2 != 0 && !positions.is_empty() {
                let a = positions[usize::from(i.u8()) % nv];
                let b = positions[usize::from(i.u8()) % nv];
                let s = f32::from(i.u8() % 9) / 8.0;
                ray.direction = a + (b - a) * s - o;
            }
            if rf & 4 != 0 {
                ray.t_min = i.f32();
                ray.t_max = i.f32();
            }
            rays.push(ray);
        }
        Soup {
            positions,
            triangles,
            options,
            rays,
        }
    }

    /// Encodes a quantized soup with default options and `(origin, direction)` rays aimed by
    /// vertex pairs: `aims[k] = (origin, i, j, s8)` (aim at `p_i + s8/8·(p_j − p_i)`).
    pub fn encode_quantized(
        positions: &[Vec3],
        triangles: &[[u8; 3]],
        aims: &[(Vec3, u8, u8, u8)],
    ) -> Vec<u8> {
        let mut e = Enc::new()
            .u8(1)
            .u8(positions.len() as u8)
            .u8(triangles.len() as u8);
        for p in positions {
            e = e.qvec3(*p);
        }
        for t in triangles {
            e = e.u8(t[0]).u8(t[1]).u8(t[2]);
        }
        for &(o, a, b, s) in aims {
            e = e.u8(3).qvec3(o).qvec3(Vec3::ZERO).u8(a).u8(b).u8(s);
        }
        e.done()
    }

    /// Fuzz target `bvh`: [`check`] on [`decode`]`(data)`.
    pub fn bvh(data: &[u8]) {
        check(&decode(data));
    }

    /// `true` when every in-tree vertex lies within [`super::DOMAIN_MAX`] (2⁶⁰) of the origin
    /// in every coordinate, the range the watertight test documents (triangles up to ~1e20):
    /// beyond it the projected coordinates' products leave the range where the `f64` edge
    /// functions and the `t` forms keep their bounds.
    pub fn within_domain(mesh: &TriangleMesh<'_>, ray: &Ray, in_tree: &[bool]) -> bool {
        (0..in_tree.len())
            .filter(|&i| in_tree[i])
            .filter_map(|i| mesh.triangle(i))
            .all(|v| {
                v.iter().all(|p| {
                    (p.as_dvec3() - ray.origin.as_dvec3()).abs().max_element() <= super::DOMAIN_MAX
                })
            })
    }

    /// [`super::projection_underflows`] for any triangle in the tree.
    pub fn projection_underflows(mesh: &TriangleMesh<'_>, ray: &Ray, in_tree: &[bool]) -> bool {
        (0..in_tree.len())
            .filter(|&i| in_tree[i])
            .filter_map(|i| mesh.triangle(i))
            .any(|v| super::projection_underflows(ray, &v))
    }

    fn usable(b: &Aabb) -> bool {
        b.is_finite() && b.is_valid()
    }

    /// Brute force with the BVH's rule: the smallest `t` in the ray's interval, ties to the
    /// smaller primitive index, over the primitives in the tree.
    fn brute<T: TriangleIntersector>(
        mesh: &TriangleMesh<'_>,
        isect: &T,
        ray: &Ray,
        in_tree: &[bool],
    ) -> Option<(u32, TriangleHit)> {
        let mut best: Option<(u32, TriangleHit)> = None;
        for (i, &live) in in_tree.iter().enumerate() {
            let Some(v) = mesh.triangle(i).filter(|_| live) else {
                continue;
            };
            if let Some(h) = isect.intersect(ray, &v)
                && best.is_none_or(|(_, b)| h.t < b.t)
            {
                best = Some((i as u32, h));
            }
        }
        best
    }

    /// Properties of the BVH on one soup:
    ///
    /// 1. Building with exactly [`node_capacity`] / [`index_capacity`] storage succeeds, unless a
    ///    primitive has unusable bounds (non-finite vertex, out-of-range index) and
    ///    `exclude_non_finite` is off: then the error is `NonFinitePrimitive` naming the first.
    /// 2. One node or one index too few gives `NodeStorageTooSmall` / `IndexStorageTooSmall`
    ///    with the right counts, and the storage is left untouched.
    /// 3. Refitting over the same source leaves every node bit-for-bit unchanged.
    /// 4. For every ray and for `watertight` and `moller-trumbore`: the closest hit equals the
    ///    brute-force loop (same primitive, same hit record); any-hit agrees on hit/miss and its
    ///    primitive really is hit in the interval.
    /// 5. A box query (the box spanned by each ray's origin and origin + direction) reports
    ///    exactly the primitives whose bounds overlap it.
    pub fn check(s: &Soup) {
        let mesh = TriangleMesh::new(&s.positions, &s.triangles);
        let n = mesh.primitive_count();
        let ctx = || {
            format!(
                "options {:?}\n  positions {}\n  triangles {:?}",
                s.options,
                s.positions
                    .iter()
                    .map(|p| fmt_vec3(*p))
                    .collect::<Vec<_>>()
                    .join(", "),
                s.triangles
            )
        };
        let valid: Vec<bool> = (0..n).map(|i| usable(&mesh.primitive_bounds(i))).collect();
        let first_bad = valid.iter().position(|&ok| !ok);

        // 2. Too-small storage.
        if n > 0 {
            let sentinel = BvhNode::default();
            let nodes = vec![sentinel; node_capacity(n) - 1];
            let idx = vec![u32::MAX; index_capacity(n)];
            let r = Bvh::build(&mesh, nodes, idx, &s.options);
            match r {
                Err(BvhError::NodeStorageTooSmall { needed, available }) => {
                    assert_eq!(
                        (needed, available),
                        (node_capacity(n), node_capacity(n) - 1)
                    );
                }
                other => panic!("one node too few gave {other:?}\n{}", ctx()),
            }
            let mut nodes = vec![sentinel; node_capacity(n)];
            let mut idx = vec![u32::MAX; index_capacity(n) - 1];
            let r = Bvh::build(&mesh, &mut nodes[..], &mut idx[..], &s.options);
            match r {
                Err(BvhError::IndexStorageTooSmall { needed, available }) => {
                    assert_eq!((needed, available), (n, n - 1));
                }
                other => panic!("one index too few gave {other:?}\n{}", ctx()),
            }
            assert!(
                nodes.iter().all(|x| *x == sentinel) && idx.iter().all(|&x| x == u32::MAX),
                "refused build wrote into the storage\n{}",
                ctx()
            );
        }

        // 1. Build.
        let nodes = vec![BvhNode::default(); node_capacity(n)];
        let idx = vec![u32::MAX; index_capacity(n)];
        let mut bvh = match (Bvh::build(&mesh, nodes, idx, &s.options), first_bad) {
            (Ok(b), None) => b,
            (Ok(b), Some(_)) if s.options.exclude_non_finite => b,
            (Err(BvhError::NonFinitePrimitive { index }), Some(bad))
                if !s.options.exclude_non_finite =>
            {
                assert_eq!(
                    index,
                    bad,
                    "NonFinitePrimitive names the wrong primitive\n{}",
                    ctx()
                );
                return;
            }
            (r, _) => panic!(
                "build gave {:?} (first unusable primitive {first_bad:?})\n{}",
                r.err(),
                ctx()
            ),
        };
        let expected_count = valid.iter().filter(|&&ok| ok).count();
        assert_eq!(
            bvh.primitive_count(),
            expected_count,
            "primitive count\n{}",
            ctx()
        );
        let mut in_tree = vec![false; n];
        for &p in bvh.indices() {
            let p = p as usize;
            assert!(
                p < n && valid[p] && !in_tree[p],
                "bad index {p} in the tree\n{}",
                ctx()
            );
            in_tree[p] = true;
        }

        // 3. Refit over the same source.
        let before: Vec<BvhNode> = bvh.nodes().to_vec();
        assert_eq!(
            bvh.refit(&mesh),
            Ok(()),
            "refit over the same source\n{}",
            ctx()
        );
        assert_eq!(
            bvh.nodes(),
            &before[..],
            "refit changed the boxes\n{}",
            ctx()
        );

        // 6. The 8-wide tree collapsed from it: exactly sized storage builds, and every ray
        // below gives the binary tree's answers.
        let wide_nodes = Bvh8::<Vec<WideNode<8>>, Vec<LeafGroup>>::node_count_for(&bvh)
            .unwrap_or_else(|e| panic!("wide node count: {e}\n{}", ctx()));
        let wide = Bvh8::from_binary(
            &bvh,
            &mesh,
            vec![WideNode::<8>::EMPTY; wide_nodes],
            vec![LeafGroup::EMPTY; group_capacity(bvh.primitive_count())],
        )
        .unwrap_or_else(|e| panic!("wide collapse: {e}\n{}", ctx()));

        // 4, 5. Rays.
        for ray in &s.rays {
            let rctx = || format!("{}\n{}", fmt_ray(ray), ctx());
            check_ray(&bvh, &mesh, &Watertight, ray, &in_tree, true, &rctx);
            check_wide(&wide, &mesh, &Watertight, ray, &in_tree, true, &rctx);
            check_wide(
                &wide,
                &mesh,
                &MollerTrumbore::CLASSIC,
                ray,
                &in_tree,
                false,
                &rctx,
            );
            // Möller–Trumbore's inexact edge tests can report a hit slightly outside the
            // triangle, hence outside its box: only the weak form holds for it.
            check_ray(
                &bvh,
                &mesh,
                &MollerTrumbore::CLASSIC,
                ray,
                &in_tree,
                false,
                &rctx,
            );
            let q = Aabb::new(ray.origin, ray.origin).grow(ray.origin + ray.direction);
            let mut found = Vec::new();
            let reported = bvh.query_box(&mesh, &q, |p| {
                found.push(p);
                true
            });
            found.sort_unstable();
            let expect: Vec<u32> = (0..n)
                .filter(|&i| in_tree[i] && mesh.primitive_bounds(i).overlaps(&q))
                .map(|i| i as u32)
                .collect();
            assert_eq!(reported, found.len());
            assert_eq!(
                found,
                expect,
                "query_box({q:?}) differs from brute force\n{}",
                rctx()
            );
        }
    }

    /// [`check_ray`]'s properties for the 8-wide tree: closest hit equal to brute force in the
    /// same domain, a genuine hit no nearer than brute force's elsewhere; any-hit agreement.
    fn check_wide<T: TriangleIntersector>(
        wide: &Bvh8<Vec<WideNode<8>>, Vec<LeafGroup>>,
        mesh: &TriangleMesh<'_>,
        isect: &T,
        ray: &Ray,
        in_tree: &[bool],
        exact: bool,
        ctx: &dyn Fn() -> String,
    ) {
        let want = brute(mesh, isect, ray, in_tree);
        let got = wide.closest_hit_triangles(isect, ray, None);
        let any = wide.any_hit_triangles(isect, ray, None);
        for (p, h) in got.iter().chain(any.iter()) {
            let v = mesh.triangle(*p as usize).expect("hit primitive exists");
            assert_eq!(
                isect.intersect(ray, &v),
                Some(*h),
                "wide hit record\n{}",
                ctx()
            );
        }
        if !exact || !within_domain(mesh, ray, in_tree) || projection_underflows(mesh, ray, in_tree)
        {
            if let Some((_, h)) = got {
                let (_, w) = want.expect("brute force finds every BVH hit");
                assert!(w.t <= h.t, "wide: nearer than brute force\n{}", ctx());
            }
            return;
        }
        assert_eq!(
            got,
            want,
            "{}: wide BVH closest hit differs from brute force\n{}",
            isect.name(),
            ctx()
        );
        assert_eq!(
            any.is_some(),
            want.is_some(),
            "{}: wide any-hit {any:?} disagrees with brute force {want:?}\n{}",
            isect.name(),
            ctx()
        );
    }

    /// A BVH's closest and any hit on `ray` against brute force over `in_tree` (exactly,
    /// within the documented domain; elsewhere a genuine hit no nearer than brute force's).
    pub fn check_ray<N: AsRef<[BvhNode]>, I: AsRef<[u32]>, T: TriangleIntersector>(
        bvh: &Bvh<N, I>,
        mesh: &TriangleMesh<'_>,
        isect: &T,
        ray: &Ray,
        in_tree: &[bool],
        exact: bool,
        ctx: &dyn Fn() -> String,
    ) {
        let want = brute(mesh, isect, ray, in_tree);
        let got = bvh.closest_hit_triangles(mesh, isect, ray, None);
        if !exact || !within_domain(mesh, ray, in_tree) || projection_underflows(mesh, ray, in_tree)
        {
            // Outside the documented domain of exact agreement (`Watertight` docs): the
            // BVH's answer must still be a genuine hit of the intersector, no nearer than
            // brute force's.
            if let Some((p, h)) = got {
                let v = mesh.triangle(p as usize).expect("hit primitive exists");
                assert_eq!(isect.intersect(ray, &v), Some(h), "{}", ctx());
                let (_, w) = want.expect("brute force finds every BVH hit");
                assert!(w.t <= h.t, "{}", ctx());
            }
            return;
        }
        assert_eq!(
            got,
            want,
            "{}: BVH closest hit differs from brute force\n{}",
            isect.name(),
            ctx()
        );
        let any = bvh.any_hit_triangles(mesh, isect, ray, None);
        assert_eq!(
            any.is_some(),
            want.is_some(),
            "{}: any-hit {any:?} disagrees with brute force {want:?}\n{}",
            isect.name(),
            ctx()
        );
        if let Some((p, h)) = any {
            let v = mesh.triangle(p as usize).expect("any-hit primitive exists");
            assert_eq!(
                isect.intersect(ray, &v),
                Some(h),
                "any-hit record\n{}",
                ctx()
            );
            assert!(ray.contains(h.t));
        }
    }
}

pub mod bvh_load {
    //! The `bvh_load` target: a BVH built on a soup (the `bvh` target's layout), changed by a
    //! few byte-level corruptions, then given to [`Bvh::from_parts`] as a baked BVH would be.
    //!
    //! Layout: `mutations: u8` (mod 9), then per mutation `kind: u8`, `at: u16`, `value: u32`,
    //! then a `bvh` soup ([`super::bvh::decode`]). Kinds (mod 8): 0 a box coordinate
    //! (`at mod 6` picks it) set to `f32::from_bits(value)`; 1 a node's `start`, 2 its `count`
    //! set to `value`; 3 an index entry set to `value`; 4 a vertex coordinate set to
    //! `f32::from_bits(value)`; 5 the last node dropped; 6 the last index dropped; 7 two nodes
    //! swapped (`at`, `value`).

    use super::Input;
    use super::bvh::{Soup, check_ray, decode};
    use halfray_core::bvh::{Bvh, BvhNode, TriangleMesh, load_scratch_len};
    use halfray_core::triangle::Watertight;

    /// Fuzz target `bvh_load`: [`check`] on the decoded input.
    pub fn bvh_load(data: &[u8]) {
        let mut i = Input::new(data);
        let count = usize::from(i.u8()) % 9;
        let mutations: Vec<(u8, u16, u32)> =
            (0..count).map(|_| (i.u8(), i.u16(), i.u32())).collect();
        let rest = data.get(1 + 7 * count..).unwrap_or(&[]);
        check(&decode(rest), &mutations);
    }

    /// Properties:
    ///
    /// 1. Loading never panics; every refusal is a typed error.
    /// 2. A tree the builder made over a mesh with only usable triangles loads unchanged.
    /// 3. Whatever loads answers every ray like brute force over all triangles (closest hit
    ///    exactly within the watertight test's documented domain, any-hit agreeing), so a
    ///    corruption is either refused or harmless.
    pub fn check(s: &Soup, mutations: &[(u8, u16, u32)]) {
        let mut positions = s.positions.clone();
        let mesh = TriangleMesh::new(&s.positions, &s.triangles);
        let n = s.triangles.len();
        let options = halfray_core::bvh::BuildOptions {
            exclude_non_finite: false,
            ..s.options
        };
        let Ok(built) = Bvh::build(
            &mesh,
            vec![BvhNode::EMPTY; halfray_core::bvh::node_capacity(n)],
            vec![0u32; n],
            &options,
        ) else {
            return; // Unusable triangles: nothing to bake.
        };
        let mut nodes = built.nodes().to_vec();
        let mut indices = built.indices().to_vec();
        let mut scratch = vec![0u32; load_scratch_len(n)];
        if mutations.is_empty() {
            let loaded = Bvh::from_parts(&nodes[..], &indices[..], &mesh, &mut scratch);
            assert!(loaded.is_ok(), "a built tree is refused: {loaded:?}");
        }
        for &(kind, at, value) in mutations {
            let at = usize::from(at);
            match kind % 8 {
                0..=2 if !nodes.is_empty() => {
                    let k = at % nodes.len();
                    let (mut b, mut start, mut count) = nodes[k].to_raw();
                    match kind % 8 {
                        0 => b[(at / nodes.len()) % 2][at % 3] = f32::from_bits(value),
                        1 => start = value,
                        _ => count = value,
                    }
                    nodes[k] = BvhNode::from_raw(b, start, count);
                }
                3 if !indices.is_empty() => {
                    let k = at % indices.len();
                    indices[k] = value;
                }
                4 if !positions.is_empty() => {
                    let k = at % positions.len();
                    positions[k][at % 3] = f32::from_bits(value);
                }
                5 => {
                    nodes.pop();
                }
                6 => {
                    indices.pop();
                }
                7 if !nodes.is_empty() => {
                    let (a, b) = (at % nodes.len(), value as usize % nodes.len());
                    nodes.swap(a, b);
                }
                _ => {}
            }
        }
        let mesh = TriangleMesh::new(&positions, &s.triangles);
        let Ok(bvh) = Bvh::from_parts(&nodes[..], &indices[..], &mesh, &mut scratch) else {
            return;
        };
        let in_tree = vec![true; n];
        let ctx = || {
            format!(
                "mutations {mutations:?}\n  nodes {nodes:?}\n  indices {indices:?}\n  positions {positions:?}"
            )
        };
        for ray in &s.rays {
            check_ray(&bvh, &mesh, &Watertight, ray, &in_tree, true, &ctx);
        }
    }
}

pub mod halfedge {
    //! The `halfedge_ops` target: arbitrary edit sequences on small half-edge meshes.
    //!
    //! Layout: `start: u8` (mod 6: tetrahedron, octahedron, open 3×3 grid, one triangle,
    //! hexagon fan, or a raw mesh: `vertex count: u8` mod 13, `triangle count: u8` mod 17,
    //! quantized positions, triangles of three index bytes mod `vertex count + 1`), then
    //! operations until the input ends (at most 24), each an opcode byte (mod 10, see [`Op`])
    //! followed by its arguments.

    use super::Input;
    use glam::Vec3;
    use halfray_core::halfedge::{
        CollapseAt, Counts, DiffuseBoundary, EdgeId, ExportError, HalfedgeId, HalfedgeMesh,
        LoopWeights, VertexId, build_scratch_len,
    };

    /// The mesh type fuzzed: room for two Loop levels of a tetrahedron or one of an
    /// octahedron, and for some dozens of splits.
    pub type FuzzMesh = HalfedgeMesh<64, 192, 128>;

    /// Opcodes (the first byte of an operation, mod 10).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    #[repr(u8)]
    pub enum Op {
        /// `flip_edge(edge: u8)`.
        Flip = 0,
        /// `split_edge(edge: u8)`.
        Split = 1,
        /// `split_edge_at(edge: u8, raw: u8, point)`: quantized point if `raw` is even, else
        /// three raw `f32`s.
        SplitAt = 2,
        /// `collapse_edge(halfedge: u16, at: u8)`: `at` mod 4 = head, tail, midpoint, point
        /// (quantized).
        Collapse = 3,
        /// `diffuse_vertex(vertex: u8, k: f32)`.
        DiffuseVertex = 4,
        /// `diffuse(k: u8 / 16, boundary: u8, short scratch: u8)`.
        Diffuse = 5,
        /// `subdivide_loop(weights: u8)` into a fresh mesh, which replaces the mesh on success.
        Loop = 6,
        /// `compact`.
        Compact = 7,
        /// `set_position(vertex: u8, raw: u8, point)` (point as for `SplitAt`).
        SetPosition = 8,
        /// `export` (also into a too-small buffer), `build` from the export, re-export.
        ExportRebuild = 9,
    }

    fn euler(c: Counts) -> i64 {
        c.vertices as i64 - c.edges as i64 + c.faces as i64
    }

    /// The start meshes (positions, triangles), indexed by the start byte mod 5.
    pub fn start_mesh(k: u8) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        match k % 5 {
            0 => (
                vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
                vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            ),
            1 => (
                vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z],
                vec![
                    [0, 2, 4],
                    [2, 1, 4],
                    [1, 3, 4],
                    [3, 0, 4],
                    [2, 0, 5],
                    [1, 2, 5],
                    [3, 1, 5],
                    [0, 3, 5],
                ],
            ),
            2 => {
                let p = (0..9)
                    .map(|i| Vec3::new((i % 3) as f32, (i / 3) as f32, 0.0))
                    .collect();
                let mut t = Vec::new();
                for j in 0..2u32 {
                    for i in 0..2u32 {
                        let (a, b, c, d) = (i + 3 * j, i + 1 + 3 * j, i + 4 + 3 * j, i + 3 + 3 * j);
                        t.push([a, b, c]);
                        t.push([a, c, d]);
                    }
                }
                (p, t)
            }
            3 => (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]),
            _ => {
                let mut p = vec![Vec3::ZERO];
                for k in 0..6 {
                    let a = k as f32 * core::f32::consts::FRAC_PI_3;
                    p.push(Vec3::new(a.cos(), a.sin(), 0.0));
                }
                let t = (1..=6u32).map(|k| [0, k, k % 6 + 1]).collect();
                (p, t)
            }
        }
    }

    fn point(i: &mut Input<'_>) -> Vec3 {
        if i.u8().is_multiple_of(2) {
            i.qvec3()
        } else {
            i.vec3()
        }
    }

    /// Fuzz target `halfedge_ops`.
    ///
    /// Properties: no panic; a build either succeeds with `validate()` Ok or fails leaving the
    /// mesh empty; after every successful operation `validate()` is Ok and the Euler
    /// characteristic `V − E + F` is unchanged; an operation that refuses leaves the mesh
    /// bit-for-bit unchanged (`Mesh: PartialEq` compares every slot and the free lists);
    /// `can_flip_edge` / `can_collapse_edge` predict `flip_edge` / `collapse_edge` exactly and
    /// the collapse survivor sits at the predicted point; Loop subdivision produces the
    /// documented counts and leaves its output untouched when it refuses; a refused export
    /// writes nothing; build(export(mesh)) validates and re-exports identically.
    pub fn halfedge_ops(data: &[u8]) {
        let mut i = Input::new(data);
        let start = i.u8() % 6;
        let (positions, triangles) = if start == 5 {
            let nv = usize::from(i.u8()) % 13;
            let nt = usize::from(i.u8()) % 17;
            let p: Vec<Vec3> = (0..nv).map(|_| i.qvec3()).collect();
            let m = nv as u32 + 1;
            let t = (0..nt)
                .map(|_| {
                    [
                        u32::from(i.u8()) % m,
                        u32::from(i.u8()) % m,
                        u32::from(i.u8()) % m,
                    ]
                })
                .collect();
            (p, t)
        } else {
            start_mesh(start)
        };
        let mut log = vec![format!("build {positions:?} {triangles:?}")];
        let mut mesh = FuzzMesh::new();
        let mut scratch = vec![0u32; build_scratch_len(triangles.len())];
        match mesh.build(&positions, &triangles, &mut scratch) {
            Ok(()) => assert_eq!(mesh.validate(), Ok(()), "built mesh invalid: {log:?}"),
            Err(_) => {
                assert!(mesh.is_empty(), "failed build left elements: {log:?}");
                assert_eq!(mesh, FuzzMesh::new(), "failed build left state: {log:?}");
            }
        }

        for _ in 0..24 {
            if i.is_empty() {
                break;
            }
            let before = mesh.clone();
            let slots = mesh.slots();
            let chi = euler(mesh.len());
            let edge =
                |i: &mut Input<'_>| EdgeId::new(u32::from(i.u8()) % (slots.edges as u32 + 2));
            let vertex =
                |i: &mut Input<'_>| VertexId::new(u32::from(i.u8()) % (slots.vertices as u32 + 2));
            let op = i.u8() % 10;
            // `Ok(keep_chi)` on success, `Err(())` when refused.
            let outcome: Result<bool, String> = match op {
                0 => {
                    let e = edge(&mut i);
                    let can = mesh.can_flip_edge(e);
                    let r = mesh.flip_edge(e);
                    log.push(format!("flip {e:?} -> {r:?}"));
                    assert_eq!(can, r, "can_flip_edge disagrees: {log:?}");
                    r.map(|()| true).map_err(|e| format!("{e:?}"))
                }
                1 => {
                    let e = edge(&mut i);
                    let r = mesh.split_edge(e);
                    log.push(format!("split {e:?} -> {r:?}"));
                    r.map(|_| true).map_err(|e| format!("{e:?}"))
                }
                2 => {
                    let e = edge(&mut i);
                    let p = point(&mut i);
                    let r = mesh.split_edge_at(e, p);
                    log.push(format!("split_at {e:?} {p:?} -> {r:?}"));
                    if let Ok(m) = r {
                        assert_eq!(mesh.position(m), Some(p), "split point: {log:?}");
                    }
                    r.map(|_| true).map_err(|e| format!("{e:?}"))
                }
                3 => {
                    let h = HalfedgeId::new(u32::from(i.u16()) % (2 * slots.edges as u32 + 2));
                    let at = match i.u8() % 4 {
                        0 => CollapseAt::Head,
                        1 => CollapseAt::Tail,
                        2 => CollapseAt::Midpoint,
                        _ => CollapseAt::Point(i.qvec3()),
                    };
                    let can = mesh.can_collapse_edge(h, at);
                    let r = mesh.collapse_edge(h, at);
                    log.push(format!(
                        "collapse {h:?} {at:?} -> {r:?} (predicted {can:?})"
                    ));
                    assert_eq!(
                        can.is_ok(),
                        r.is_ok(),
                        "can_collapse_edge disagrees: {log:?}"
                    );
                    if let (Ok(p), Ok(v)) = (can, r) {
                        assert_eq!(mesh.position(v), Some(p), "survivor position: {log:?}");
                    }
                    r.map(|_| true).map_err(|e| format!("{e:?}"))
                }
                4 => {
                    let v = vertex(&mut i);
                    let k = i.f32();
                    let r = mesh.diffuse_vertex(v, k);
                    log.push(format!("diffuse_vertex {v:?} {k:e} -> {r:?}"));
                    r.map(|_| true).map_err(|e| format!("{e:?}"))
                }
                5 => {
                    let k = f32::from(i.u8()) / 16.0;
                    let boundary = if i.u8().is_multiple_of(2) {
                        DiffuseBoundary::Free
                    } else {
                        DiffuseBoundary::Fixed
                    };
                    let short = usize::from(i.u8() % 2 == 1 && slots.vertices > 0);
                    let mut sc = vec![Vec3::ZERO; slots.vertices - short];
                    let r = mesh.diffuse(k, boundary, &mut sc);
                    log.push(format!("diffuse {k} {boundary:?} short={short} -> {r:?}"));
                    r.map(|()| true).map_err(|e| format!("{e:?}"))
                }
                6 => {
                    let weights = if i.u8().is_multiple_of(2) {
                        LoopWeights::Warren
                    } else {
                        LoopWeights::Loop
                    };
                    let mut out = FuzzMesh::new();
                    let r = mesh.subdivide_loop(&mut out, weights);
                    log.push(format!("loop {weights:?} -> {r:?}"));
                    match r {
                        Ok(()) => {
                            assert_eq!(out.len(), mesh.len().after_loop(), "Loop counts: {log:?}");
                            mesh = out;
                            Ok(true)
                        }
                        Err(e) => {
                            assert_eq!(out, FuzzMesh::new(), "refused Loop wrote output: {log:?}");
                            Err(format!("{e:?}"))
                        }
                    }
                }
                7 => {
                    let mut moves = 0usize;
                    mesh.compact(|_| moves += 1);
                    log.push(format!("compact ({moves} moves)"));
                    assert!(mesh.is_compact(), "not compact after compact: {log:?}");
                    assert_eq!(mesh.len(), before.len(), "compact changed counts: {log:?}");
                    Ok(true)
                }
                8 => {
                    let v = vertex(&mut i);
                    let p = point(&mut i);
                    let r = mesh.set_position(v, p);
                    log.push(format!("set_position {v:?} {p:?} -> {r:?}"));
                    r.map(|()| true).map_err(|e| format!("{e:?}"))
                }
                _ => {
                    let (np, nt) = (slots.vertices, mesh.len().faces);
                    if np + nt > 0 {
                        let mut sp = vec![Vec3::splat(7.0); np.saturating_sub(1)];
                        let mut st = vec![[9u32; 3]; nt];
                        let r = mesh.export(&mut sp, &mut st);
                        assert_eq!(
                            r,
                            Err(ExportError::BufferTooSmall {
                                positions: np,
                                triangles: nt
                            }),
                            "short export: {log:?}"
                        );
                        assert!(
                            sp.iter().all(|p| *p == Vec3::splat(7.0))
                                && st.iter().all(|t| *t == [9; 3]),
                            "refused export wrote: {log:?}"
                        );
                    }
                    let mut p = vec![Vec3::ZERO; np];
                    let mut t = vec![[0u32; 3]; nt];
                    let r = mesh.export(&mut p, &mut t);
                    assert_eq!(r, Ok((np, nt)), "export: {log:?}");
                    let mut rebuilt = FuzzMesh::new();
                    let mut sc = vec![0u32; build_scratch_len(nt)];
                    let b = rebuilt.build(&p, &t, &mut sc);
                    log.push(format!("export+rebuild -> {b:?}"));
                    assert_eq!(
                        b,
                        Ok(()),
                        "the export of a valid mesh does not build: {log:?}"
                    );
                    assert_eq!(rebuilt.validate(), Ok(()), "rebuilt mesh: {log:?}");
                    let mut p2 = vec![Vec3::ZERO; np];
                    let mut t2 = vec![[0u32; 3]; nt];
                    assert_eq!(rebuilt.export(&mut p2, &mut t2), Ok((np, nt)));
                    assert!(p == p2 && t == t2, "export does not round-trip: {log:?}");
                    assert_eq!(mesh, before, "export changed the mesh: {log:?}");
                    Ok(true)
                }
            };
            match outcome {
                Ok(keep_chi) => {
                    if let Err(e) = mesh.validate() {
                        panic!("validate() = {e:?} after a successful operation: {log:#?}");
                    }
                    if keep_chi {
                        assert_eq!(euler(mesh.len()), chi, "V − E + F changed: {log:#?}");
                    }
                }
                Err(_) => assert!(
                    mesh == before,
                    "refused operation changed the mesh: {log:#?}"
                ),
            }
        }
    }
}

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
    vec![
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
    ]
}

/// The hard-case seed corpus, checked in as `fuzz/corpus/<target>/seed-<name>` (the replay test
/// verifies the files match; `HALFRAY_WRITE_SEEDS=1` rewrites them).
pub fn seeds() -> Vec<Seed> {
    let mut s = Vec::new();
    seeds_ray_triangle(&mut s);
    seeds_ray_box(&mut s);
    seeds_sphere(&mut s);
    seeds_quadric(&mut s);
    seeds_obj(&mut s);
    seeds_scene(&mut s);
    seeds_bvh(&mut s);
    seeds_bvh_load(&mut s);
    seeds_halfedge(&mut s);
    s
}

fn seeds_bvh_load(s: &mut Vec<Seed>) {
    let grid: Vec<Vec3> = (0..9)
        .map(|k| {
            Vec3::new(
                (k % 3) as f32 * 2.0,
                (k / 3) as f32 * 2.0,
                (k % 2) as f32 * 0.5,
            )
        })
        .collect();
    let tris: Vec<[u8; 3]> = (0..4u8)
        .flat_map(|q| {
            let (i, j) = (q % 2, q / 2);
            let v = |di: u8, dj: u8| (j + dj) * 3 + i + di;
            [[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]]
        })
        .collect();
    let o = Vec3::new(1.5, 1.25, 6.0);
    let soup = bvh::encode_quantized(
        &grid,
        &tris,
        &[(o, 0, 8, 4), (o, 4, 4, 0), (o, 1, 7, 4), (o, 2, 6, 2)],
    );
    let with = |name: &str, muts: &[(u8, u16, u32)]| {
        let mut e = Enc::new().u8(muts.len() as u8);
        for &(k, at, v) in muts {
            e = e.u8(k).u16(at).bytes(&v.to_le_bytes());
        }
        (
            "bvh_load",
            format!("seed-{name}"),
            [e.done(), soup.clone()].concat(),
        )
    };
    s.push(with("as-built", &[]));
    s.push(with("box-coordinate", &[(0, 0, 1.0f32.to_bits())]));
    s.push(with("leaf-start", &[(1, 5, 3)]));
    s.push(with("repeated-index", &[(3, 1, 0)]));
    s.push(with("vertex-moved", &[(4, 4, 9.0f32.to_bits())]));
    s.push(with("nodes-swapped", &[(7, 0, 2)]));
    s.push(with("truncated", &[(5, 0, 0), (6, 0, 0)]));
}

fn seeds_bvh(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("bvh", format!("seed-{name}"), bytes);
    let quad = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(4.0, 4.0, 0.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::new(2.0, 2.0, 3.0),
    ];
    let o = Vec3::new(1.25, -2.5, 7.0);
    // Two triangles sharing the diagonal; rays at the shared edge, a shared vertex, interior.
    s.push(t(
        "quad-shared-edge",
        bvh::encode_quantized(
            &quad,
            &[[0, 1, 2], [0, 2, 3]],
            &[(o, 0, 2, 4), (o, 0, 2, 1), (o, 0, 0, 0), (o, 1, 3, 3)],
        ),
    ));
    // Pyramid (closed fan around the apex) with rays at the apex and the ridges.
    s.push(t(
        "pyramid",
        bvh::encode_quantized(
            &quad,
            &[
                [0, 1, 4],
                [1, 2, 4],
                [2, 3, 4],
                [3, 0, 4],
                [0, 2, 1],
                [0, 3, 2],
            ],
            &[
                (o, 4, 4, 0),
                (o, 0, 4, 4),
                (Vec3::new(-3.0, 1.0, 0.5), 2, 4, 2),
            ],
        ),
    ));
    // Duplicated coplanar triangles (tie rule), a degenerate one and a collinear one.
    s.push(t(
        "duplicates-degenerate",
        bvh::encode_quantized(
            &quad,
            &[
                [0, 1, 2],
                [0, 1, 2],
                [1, 2, 0],
                [3, 3, 3],
                [0, 1, 1],
                [0, 2, 3],
            ],
            &[
                (o, 0, 2, 2),
                (o, 0, 1, 4),
                (Vec3::new(-1.0, 0.0, 0.0), 1, 1, 0),
            ],
        ),
    ));
    // Out-of-range vertex index (unusable primitive): the build must name it.
    s.push(t(
        "out-of-range-index",
        bvh::encode_quantized(&quad[..3], &[[0, 1, 2], [0, 1, 4]], &[(o, 0, 1, 4)]),
    ));
    // Same with exclude_non_finite, and a NaN vertex (raw coordinates).
    let mut raw = Enc::new().u8(2).u8(4).u8(3);
    for p in [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(f32::NAN, 0.0, 0.0)] {
        raw = raw.vec3(p);
    }
    let raw = raw
        .bytes(&[0, 1, 2, 0, 1, 3, 2, 1, 0])
        .u8(0)
        .vec3(Vec3::new(0.25, 0.25, 1.0))
        .vec3(-Vec3::Z)
        .u8(4)
        .vec3(Vec3::new(0.25, 0.25, 1.0))
        .vec3(-Vec3::Z)
        .f32(0.0)
        .f32(1.0);
    s.push(t("nan-vertex-excluded", raw.done()));
    s.push(t("empty", Enc::new().u8(1).u8(0).u8(0).u8(0).done()));
}

fn seeds_halfedge(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("halfedge_ops", format!("seed-{name}"), bytes);
    // Opcodes: 0 flip e, 1 split e, 2 split_at e raw p, 3 collapse h16 at, 4 diffuse_vertex v k,
    // 5 diffuse k b short, 6 loop w, 7 compact, 8 set_position v raw p, 9 export+rebuild.
    let q0 = [0u8, 0, 0];
    s.push(t(
        "tetra-loop-loop",
        Enc::new()
            .u8(0)
            .bytes(&[6, 0, 6, 1, 0, 3, 3, 0, 0, 9])
            .done(),
    ));
    s.push(t(
        "tetra-flip-collapse-refused",
        Enc::new()
            .u8(0)
            .bytes(&[0, 0, 0, 1, 3, 0, 0, 0, 3, 5, 0, 2])
            .done(),
    ));
    s.push(t(
        "octa-split-flip-collapse-compact",
        Enc::new()
            .u8(1)
            .bytes(&[
                1, 0, 1, 5, 0, 12, 0, 13, 3, 24, 0, 2, 3, 7, 0, 1, 7, 9, 6, 1,
            ])
            .done(),
    ));
    s.push(t(
        "grid-boundary-ops",
        Enc::new()
            .u8(2)
            .bytes(&[0, 0, 3, 0, 0, 0, 3, 1, 0, 1, 1, 2, 4, 0])
            .bytes(&q0)
            .bytes(&[5, 8, 1, 0, 5, 8, 0, 1, 7, 9])
            .done(),
    ));
    s.push(t(
        "triangle-everything",
        Enc::new()
            .u8(3)
            .bytes(&[0, 0, 1, 0, 3, 2, 0, 1, 6, 0, 9, 7])
            .done(),
    ));
    s.push(t(
        "fan-nonfinite-refusals",
        Enc::new()
            .u8(4)
            .u8(4)
            .u8(0)
            .f32(f32::INFINITY)
            .u8(2)
            .u8(0)
            .u8(1)
            .vec3(Vec3::new(f32::NAN, 0.0, 0.0))
            .u8(8)
            .u8(1)
            .u8(1)
            .vec3(Vec3::new(0.0, f32::INFINITY, 0.0))
            .u8(4)
            .u8(0)
            .f32(1e38)
            .u8(3)
            .u16(0)
            .u8(3)
            .qvec3(Vec3::new(0.0, 0.0, 5.0))
            .done(),
    ));
    // Raw builds: a bowtie (non-manifold vertex), an inconsistent orientation, an edge
    // shared by three faces, a repeated index: every one must fail and leave the mesh empty.
    for (name, nv, tris) in [
        ("raw-bowtie", 5u8, vec![[0u8, 1, 2], [0, 3, 4]]),
        ("raw-flipped", 4, vec![[0, 1, 2], [0, 1, 3]]),
        ("raw-three-faces", 5, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
        ("raw-repeated-index", 3, vec![[0, 0, 1]]),
        ("raw-out-of-range", 3, vec![[0, 1, 3]]),
        ("raw-two-triangles", 4, vec![[0, 1, 2], [0, 2, 3]]),
    ] {
        let mut e = Enc::new().u8(5).u8(nv).u8(tris.len() as u8);
        for k in 0..nv {
            e = e.qvec3(Vec3::new(
                f32::from(k),
                f32::from(k * k % 5),
                f32::from(k % 2),
            ));
        }
        for tri in &tris {
            e = e.bytes(tri);
        }
        s.push(t(name, e.bytes(&[1, 0, 0, 0, 7, 9]).done()));
    }
}

fn seeds_ray_triangle(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("ray_triangle", format!("seed-{name}"), bytes);
    let unit = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let dflt = (0.0, f32::INFINITY);
    let aim = flags::AIM | flags::DEFAULT_INTERVAL;
    let o = Vec3::new(0.3, -0.7, 5.0);
    // Plain hit, front and back.
    s.push(t(
        "plain",
        encode_ray_triangle(2, Vec3::new(0.25, 0.25, 5.0), -Vec3::Z, dflt, unit),
    ));
    s.push(t(
        "back",
        encode_ray_triangle(2, Vec3::new(0.25, 0.25, -5.0), Vec3::Z, dflt, unit),
    ));
    // Rays through vertices, edge midpoints and the centroid (exact targets).
    for (name, u, w) in [
        ("vertex0", 0.0, 0.0),
        ("vertex1", 1.0, 0.0),
        ("vertex2", 0.0, 1.0),
        ("edge01", 0.5, 0.0),
        ("edge12", 0.5, 0.5),
        ("edge20", 0.0, 0.5),
        ("centroid", 1.0 / 3.0, 1.0 / 3.0),
        ("outside", 0.75, 0.75),
    ] {
        s.push(t(
            &format!("aim-{name}"),
            encode_ray_triangle(aim, o, Vec3::new(u, w, 0.0), dflt, unit),
        ));
    }
    // A skinny, far triangle hit near its long edge (grazing, T8) and at 1e7 (T12).
    let skinny = [
        Vec3::new(1e7, 0.0, 0.0),
        Vec3::new(1e7 + 11.2, 0.1, 0.0),
        Vec3::new(1e7 + 1.4, 9.7, 0.3),
    ];
    s.push(t(
        "far-skinny-edge",
        encode_ray_triangle(aim, Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0), dflt, skinny),
    ));
    // In-plane ray (T6) and ray parallel one ulp above (T7).
    s.push(t(
        "in-plane",
        encode_ray_triangle(2, Vec3::new(-1.0, 0.25, 0.0), Vec3::X, dflt, unit),
    ));
    s.push(t(
        "parallel-ulp-above",
        encode_ray_triangle(
            2,
            Vec3::new(-1.0, 0.25, f32::from_bits(1)),
            Vec3::X,
            dflt,
            unit,
        ),
    ));
    // Degenerate triangles (T9).
    s.push(t(
        "collinear",
        encode_ray_triangle(
            2,
            Vec3::new(0.5, 0.0, 1.0),
            -Vec3::Z,
            dflt,
            [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        ),
    ));
    s.push(t(
        "point",
        encode_ray_triangle(2, Vec3::new(1.0, 1.0, 2.0), -Vec3::Z, dflt, [Vec3::ONE; 3]),
    ));
    // Tiny and huge triangles (T10, T11).
    for (name, k) in [("tiny", 1e-20f32), ("huge", 1e19), ("subnormal", 1e-40)] {
        let v = [Vec3::ZERO, Vec3::new(k, 0.0, 0.0), Vec3::new(0.0, k, 0.0)];
        s.push(t(
            name,
            encode_ray_triangle(aim, Vec3::new(k, k, k), Vec3::new(0.25, 0.25, 0.0), dflt, v),
        ));
    }
    // Origin on the triangle (T13), hit exactly at t_max (T14), tiny t interval.
    s.push(t(
        "origin-on-triangle",
        encode_ray_triangle(2, Vec3::new(0.25, 0.25, 0.0), Vec3::Z, dflt, unit),
    ));
    s.push(t(
        "hit-at-tmax",
        encode_ray_triangle(0, Vec3::new(0.25, 0.25, 2.0), -Vec3::Z, (0.0, 2.0), unit),
    ));
    s.push(t(
        "tmax-just-short",
        encode_ray_triangle(
            0,
            Vec3::new(0.25, 0.25, 2.0),
            -Vec3::Z,
            (0.0, 2.0f32.next_down()),
            unit,
        ),
    ));
    // Unnormalised directions (T16), ±0 components (T17), dominant-axis ties (T18).
    for (name, d) in [
        ("dir-1e-10", Vec3::new(0.0, 0.0, -1e-10)),
        ("dir-1e10", Vec3::new(0.0, 0.0, -1e10)),
        ("neg-zero", Vec3::new(-0.0, -0.0, -1.0)),
        ("tie-xyz", Vec3::new(-1.0, -1.0, -1.0)),
    ] {
        s.push(t(
            name,
            encode_ray_triangle(2, Vec3::new(0.5, 0.4, 1.0), d, dflt, unit),
        ));
    }
    // Invalid rays (T19) and non-finite vertices (T20).
    for (name, o, d, iv) in [
        ("nan-origin", Vec3::new(f32::NAN, 0.0, 1.0), -Vec3::Z, dflt),
        (
            "inf-direction",
            Vec3::new(0.2, 0.2, 1.0),
            Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
            dflt,
        ),
        ("zero-direction", Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO, dflt),
        (
            "nan-tmax",
            Vec3::new(0.2, 0.2, 1.0),
            -Vec3::Z,
            (0.0, f32::NAN),
        ),
        (
            "inverted-interval",
            Vec3::new(0.2, 0.2, 1.0),
            -Vec3::Z,
            (2.0, 1.0),
        ),
    ] {
        s.push(t(name, encode_ray_triangle(0, o, d, iv, unit)));
    }
    s.push(t(
        "inf-vertex",
        encode_ray_triangle(
            2,
            Vec3::new(0.2, 0.2, 1.0),
            -Vec3::Z,
            dflt,
            [Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::Y],
        ),
    ));
}

fn seeds_ray_box(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("ray_box", format!("seed-{name}"), bytes);
    let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
    let dflt = (0.0, f32::INFINITY);
    let df = flags::DEFAULT_INTERVAL;
    s.push(t(
        "plain",
        encode_ray_box(df, Vec3::new(0.5, 0.5, -1.0), Vec3::Z, dflt, lo, hi),
    ));
    // Origin on each slab plane with ±0 direction components (B1) and one ulp outside (B2).
    for axis in 0..3 {
        for (face_name, face) in [("min", 0.0f32), ("max", 1.0)] {
            for (zname, zero) in [("pz", 0.0f32), ("nz", -0.0)] {
                let mut o = Vec3::splat(0.5);
                o[axis] = face;
                let along = (axis + 1) % 3;
                o[along] = -1.0;
                let mut d = Vec3::ZERO;
                d[axis] = zero;
                d[along] = 1.0;
                s.push(t(
                    &format!("on-plane-{axis}-{face_name}-{zname}"),
                    encode_ray_box(df, o, d, dflt, lo, hi),
                ));
                o[axis] = if face == 0.0 {
                    face.next_down()
                } else {
                    face.next_up()
                };
                s.push(t(
                    &format!("ulp-outside-{axis}-{face_name}-{zname}"),
                    encode_ray_box(df, o, d, dflt, lo, hi),
                ));
            }
        }
    }
    // Along a box edge (B4), flat box (B3), subnormal / tiny directions (B5), far thin box (B6).
    s.push(t(
        "along-edge",
        encode_ray_box(df, Vec3::new(0.0, 0.0, -1.0), Vec3::Z, dflt, lo, hi),
    ));
    s.push(t(
        "flat-box",
        encode_ray_box(
            df,
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::Z,
            dflt,
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 1.0, 2.0),
        ),
    ));
    for (name, tiny) in [
        ("1e-30", 1e-30f32),
        ("subnormal", 1e-40),
        ("neg-subnormal", -1e-40),
    ] {
        s.push(t(
            &format!("tiny-dir-{name}"),
            encode_ray_box(
                df,
                Vec3::new(0.5, 0.5, -1.0),
                Vec3::new(tiny, 0.0, 1.0),
                dflt,
                lo,
                hi,
            ),
        ));
        if tiny.abs() < f32::MIN_POSITIVE {
            continue; // origin outside + subnormal direction: see regressions()
        }
        s.push(t(
            &format!("tiny-dir-outside-{name}"),
            encode_ray_box(
                df,
                Vec3::new(-1.0, 0.5, 0.5),
                Vec3::new(0.0, 0.0, tiny),
                dflt,
                lo,
                hi,
            ),
        ));
    }
    let x = 1e7f32;
    let far_lo = Vec3::new(x, -1.0, -1.0);
    let far_hi = Vec3::new(x.next_up(), 1.0, 1.0);
    s.push(t(
        "far-thin",
        encode_ray_box(
            df | flags::AIM,
            Vec3::new(0.0, 0.3, 0.2),
            Vec3::new(0.0, 0.5, 0.5),
            dflt,
            far_lo,
            far_hi,
        ),
    ));
    // Entry exactly at t_max (B7), aimed at corners, NaN ray (B8), inverted and NaN boxes.
    s.push(t(
        "entry-at-tmax",
        encode_ray_box(0, Vec3::new(0.5, 0.5, -2.0), Vec3::Z, (0.0, 2.0), lo, hi),
    ));
    s.push(t(
        "aim-corner",
        encode_ray_box(
            df | flags::AIM,
            Vec3::new(-3.0, 2.0, 7.0),
            Vec3::new(1.0, 0.0, 1.0),
            dflt,
            lo,
            hi,
        ),
    ));
    s.push(t(
        "nan-origin",
        encode_ray_box(df, Vec3::new(f32::NAN, 0.5, -1.0), Vec3::Z, dflt, lo, hi),
    ));
    s.push(t(
        "inverted-box",
        encode_ray_box(df, Vec3::new(0.5, 0.5, -1.0), Vec3::Z, dflt, hi, lo),
    ));
    s.push(t(
        "nan-box",
        encode_ray_box(
            df,
            Vec3::new(0.5, 0.5, -1.0),
            Vec3::Z,
            dflt,
            Vec3::new(f32::NAN, 0.0, 0.0),
            hi,
        ),
    ));
    s.push(t(
        "negative-interval",
        encode_ray_box(
            0,
            Vec3::new(0.5, 0.5, 3.0),
            Vec3::Z,
            (f32::NEG_INFINITY, -1.5),
            lo,
            hi,
        ),
    ));
}

fn seeds_obj(s: &mut Vec<Seed>) {
    let t = |name: &str, text: &str| ("obj_file", format!("seed-{name}"), text.as_bytes().to_vec());
    s.push(t(
        "quad",
        "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
    ));
    s.push(t(
        "slashes-negative",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3/1\nf -3 -2 -1\n",
    ));
    s.push(t(
        "crlf-comments",
        "o thing\r\ng g\r\nv 0 0 0 1\r\nv 1 0 0 # c\r\nv 0 1 0\r\ns off\r\nf 1 2 3\r\n",
    ));
    s.push(t(
        "extreme-floats",
        "v 3.4028235e38 -1e-45 1.17549435e-38\nv -0 0 inf\nv nan 0 0\nf 1 2 3\n",
    ));
    s.push(t("overflowing-float", "v 1e39 0 0\n"));
    s.push(t("index-zero", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"));
    s.push(t("index-out-of-range", "v 0 0 0\nf 1 2 3\nf -4 1 1\n"));
    s.push(t(
        "big-index",
        "v 0 0 0\nf 99999999999999999999 1 1\nf 4294967297 1 1\n",
    ));
    s.push(t("short-face", "v 0 0 0\nf 1 1\n"));
    s.push(t("unknown", "bogus 1 2\n"));
    s.push(t("unicode", "v 0 0 0 \u{00e9}\nv\u{3000}1 0 0\nf 1 1 1\n"));
    s.push(t("empty", ""));
}

/// The contract every curved-surface hit shares: `t` in the ray's interval, a unit normal
/// (within `1e-5`: one `f32` normalisation).
fn check_hit_basics(ray: &Ray, h: &halfray_core::hit::Hit, ctx: &dyn Fn() -> String) {
    assert!(
        ray.contains(h.t),
        "t = {:e} outside the interval\n{}",
        h.t,
        ctx()
    );
    assert!(
        (h.normal.length() - 1.0).abs() <= 1e-5,
        "normal not unit\n{}",
        ctx()
    );
}

pub mod sphere {
    //! The `ray_sphere` target: the stable quadratic against an `f64` evaluation of the same
    //! `f32` inputs, and against the textbook (naive) form where both are well conditioned.
    //!
    //! Layout: `flags: u8` (bit 0: quantized centre/radius/origin ([`Input::q`]), else raw
    //! `f32`; bit 1: interval `(0, ∞]`), `center`, `radius`, `origin`, `direction`, `t_min`,
    //! `t_max`. Missing bytes read as zero.

    use super::{Enc, Input, fmt_ray};
    use glam::Vec3;
    use halfray_core::float::F32_UNIT_ROUNDOFF;
    use halfray_core::ray::Ray;
    use halfray_core::sphere::Sphere;

    /// Multiple of `u = 2⁻²⁴` in the residual and `t` bounds below. The first-order analyses
    /// (module docs of `halfray_core::sphere`) give constants under 20; 64 leaves room for the
    /// second-order terms without hiding a real error, which is orders of magnitude larger.
    pub const K: f64 = 64.0;

    /// Inputs whose magnitudes (`|o − C|`, `r`, `|t·d|`) lie outside `[DOMAIN_MIN, DOMAIN_MAX]`
    /// are only checked for totality: outside it `f32` squares under- or overflow and the
    /// relative bounds do not apply (the intersector then answers `None`, documented).
    pub const DOMAIN_MIN: f64 = 1e-15;
    /// See [`DOMAIN_MIN`].
    pub const DOMAIN_MAX: f64 = 1e15;

    /// Largest `|t|` checked against the reference: well inside `f32` (a root that overflows
    /// `f32` gives no hit, documented).
    pub const MAX_T: f64 = 1e30;

    /// Smallest `|t|` checked against the reference: a root near the `f32` subnormal range
    /// rounds to a `t` from which the hit point cannot be rebuilt.
    pub const MIN_T: f64 = 1e-30;

    /// Decodes a `ray_sphere` input.
    pub fn decode(data: &[u8]) -> (Vec3, f32, Ray) {
        let mut i = Input::new(data);
        let fl = i.u8();
        let q = fl & 1 != 0;
        let center = if q { i.qvec3() } else { i.vec3() };
        let radius = if q { i.q() } else { i.f32() };
        let origin = if q { i.qvec3() } else { i.vec3() };
        let direction = i.vec3();
        let (t_min, t_max) = if fl & 2 != 0 {
            (0.0, f32::INFINITY)
        } else {
            (i.f32(), i.f32())
        };
        (
            center,
            radius,
            Ray::with_interval(origin, direction, t_min, t_max),
        )
    }

    /// Encodes a raw (`f32`) `ray_sphere` input with the default interval.
    pub fn encode(center: Vec3, radius: f32, o: Vec3, d: Vec3) -> Vec<u8> {
        Enc::new()
            .u8(2)
            .vec3(center)
            .f32(radius)
            .vec3(o)
            .vec3(d)
            .done()
    }

    /// Fuzz target `ray_sphere`.
    pub fn ray_sphere(data: &[u8]) {
        let (c, r, ray) = decode(data);
        check(c, r, &ray);
    }

    /// The properties:
    /// 1. `Sphere::new` is `Ok` exactly for a finite centre and a finite radius `> 0`.
    /// 2. Every root from `roots()` satisfies the implicit equation: with
    ///    `F(t) = |o + t·d − C|² − r²` in `f64`, `|F(t)| ≤ K·u·(|o − C|² + r² + (t·|d|)²)`.
    /// 3. A hit has `t` in `(t_min, t_max]`, a unit normal along `point − C`, and a point within
    ///    its own `point_error` of the sphere.
    /// 4. Against the `f64` roots of the same inputs: where the ray clearly crosses
    ///    (`|l| < r − margin`) and a root is clearly inside (or both clearly outside) the
    ///    interval, the hit (or miss) agrees and `t` is within the bound; a ray that clearly
    ///    misses (`|l| > r + margin`) gives no hit.
    /// 5. Where both forms are well conditioned (`|l| ≤ r/2`, `|o − C| ≤ 10·r`,
    ///    `|d|`, `|o − C| + r` and their product in `[1e-15, 1e15]`), the naive roots agree
    ///    with the stable ones.
    pub fn check(c: Vec3, r: f32, ray: &Ray) {
        let ctx = || {
            format!(
                "sphere C = {c:?} ({:x?}), r = {r:e} ({:#x})\n{}",
                c.to_array().map(f32::to_bits),
                r.to_bits(),
                fmt_ray(ray)
            )
        };
        let s = match Sphere::new(c, r) {
            Ok(s) => {
                assert!(
                    c.is_finite() && r.is_finite() && r > 0.0,
                    "accepted\n{}",
                    ctx()
                );
                s
            }
            Err(_) => {
                assert!(
                    !(c.is_finite() && r.is_finite() && r > 0.0),
                    "rejected a valid sphere\n{}",
                    ctx()
                );
                return;
            }
        };
        let roots = s.roots(ray);
        let hit = s.intersect(ray);
        let naive = s.roots_naive(ray);
        let _ = s.intersect_naive(ray);
        if !ray.is_valid() {
            assert!(
                roots.is_none() && hit.is_none() && naive.is_none(),
                "{}",
                ctx()
            );
            return;
        }
        let u = f64::from(F32_UNIT_ROUNDOFF);
        let (o, d, cc, rr) = (
            ray.origin.as_dvec3(),
            ray.direction.as_dvec3(),
            c.as_dvec3(),
            f64::from(r),
        );
        let f = o - cc;
        let (fl, dl) = (f.length(), d.length());
        let in_domain = |x: f64| x == 0.0 || (DOMAIN_MIN..=DOMAIN_MAX).contains(&x);
        let domain = in_domain(fl) && in_domain(rr) && fl + rr >= DOMAIN_MIN;
        let resid = |t: f64| (f + d * t).length_squared() - rr * rr;
        // 2. Residuals.
        if let Some((t0, t1)) = roots {
            assert!(t0 <= t1, "roots out of order\n{}", ctx());
            for t in [f64::from(t0), f64::from(t1)] {
                if domain && in_domain(t.abs() * dl) {
                    // Plus the f32 rounding of t itself (relative u, absolute 2⁻¹⁴⁹ below the
                    // normal range) times |F'| ≤ 2|d|·(|o − C| + r + |t·d|) between the
                    // computed and the exact root.
                    let dt = u * t.abs() + f64::from(f32::from_bits(1));
                    let bound = K * u * (fl * fl + rr * rr + (t * dl).powi(2))
                        + 2.0 * dl * (fl + rr + t.abs() * dl) * dt;
                    assert!(
                        resid(t).abs() <= bound,
                        "root t = {t:e} has residual {:e} > {bound:e}\n{}",
                        resid(t),
                        ctx()
                    );
                }
            }
        }
        // 3. Hit contract.
        if let Some(h) = hit {
            super::check_hit_basics(ray, &h, &ctx);
            let n = h.normal.as_dvec3();
            let p = h.point.as_dvec3();
            if domain && p.is_finite() {
                let dist = ((p - cc).length() - rr).abs();
                let e = h.point_error.as_dvec3().length();
                assert!(
                    dist <= e + 1e-300,
                    "hit point {:?} is {dist:e} from the sphere, bound {e:e}\n{}",
                    h.point,
                    ctx()
                );
                // The stored point is rounded to f32 near C: its direction from C is only
                // meaningful when that rounding is small against r.
                let radial = (p - cc) / (p - cc).length();
                assert!(
                    e > 1e-3 * rr || radial.dot(n) > 0.999,
                    "normal {n:?} not along point − C\n{}",
                    ctx()
                );
            }
        }
        if !domain || dl == 0.0 {
            return;
        }
        // 4. Against the f64 roots.
        let a = d.dot(d);
        let b = f.dot(d);
        let l = f - d * (b / a);
        let ll = l.length();
        let margin = 16.0 * u * (fl + rr) + 1e-3 * rr;
        if ll > rr + margin {
            assert!(
                hit.is_none(),
                "clear miss (|l| = {ll:e}) reported as a hit\n{}",
                ctx()
            );
            return;
        }
        if ll >= rr - margin {
            return; // near-tangent: either answer is right
        }
        let cos = (rr * rr - ll * ll).sqrt() / rr;
        let disc = a * (rr - ll) * (rr + ll);
        let qq = -(b + disc.sqrt().copysign(b));
        let cq = f.dot(f) - rr * rr;
        let (x, y) = (cq / qq, qq / a);
        let (r0, r1) = if x <= y { (x, y) } else { (y, x) };
        // The last term: f32 rounding of a subnormal t.
        let tol = |t: f64| {
            K * u * ((fl * fl + rr * rr) / qq.abs() + (fl + rr) / (dl * cos) + t.abs())
                + 4.0 * f64::from(f32::from_bits(1))
        };
        // Both roots and their distances in range (a root beyond f32::MAX is no hit, documented).
        let (lo, hi) = (r0.abs().min(r1.abs()), r0.abs().max(r1.abs()));
        if !(in_domain(lo * dl) && in_domain(hi * dl)) || hi > MAX_T || lo < MIN_T {
            return;
        }
        let (t_min, t_max) = (f64::from(ray.t_min), f64::from(ray.t_max));
        let status = |t: f64| {
            let e = tol(t);
            if t > t_min + e && t < t_max - e {
                Some(true)
            } else if t < t_min - e || t > t_max + e {
                Some(false)
            } else {
                None
            }
        };
        let expect = match (status(r0), status(r1)) {
            (Some(true), _) => Some(Some(r0)),
            (Some(false), Some(true)) if r1 - r0 > 2.0 * (tol(r0) + tol(r1)) => Some(Some(r1)),
            (Some(false), Some(false)) => Some(None),
            _ => None,
        };
        match expect {
            Some(Some(t_ref)) => {
                let Some(h) = hit else {
                    panic!(
                        "missed: the f64 root {t_ref:e} is clearly inside the interval\n{}",
                        ctx()
                    );
                };
                let t = f64::from(h.t);
                assert!(
                    (t - t_ref).abs() <= tol(t_ref),
                    "t = {t:e}, f64 reference {t_ref:e}, bound {:e}\n{}",
                    tol(t_ref),
                    ctx()
                );
            }
            Some(None) => assert!(
                hit.is_none(),
                "hit at {:?} although both f64 roots ({r0:e}, {r1:e}) are clearly outside \
                 the interval\n{}",
                hit.map(|h| h.t),
                ctx()
            ),
            None => {}
        }
        // 5. Naive against stable where both are well conditioned.
        // The naive form has no scaling: a = d·d, c and b², 4ac must stay normal f32 numbers.
        let naive_range = (1e-15..=1e15).contains(&dl)
            && (1e-15..=1e15).contains(&(fl + rr))
            && (1e-15..=1e15).contains(&(dl * (fl + rr)));
        if ll <= 0.5 * rr && fl <= 10.0 * rr && naive_range {
            let (Some((s0, s1)), Some((n0, n1))) = (roots, naive) else {
                panic!(
                    "well-conditioned crossing: stable {roots:?}, naive {naive:?}\n{}",
                    ctx()
                );
            };
            let tol = (fl + rr) / dl / 512.0;
            let close = |p: f32, q: f32| (f64::from(p) - f64::from(q)).abs() <= tol;
            assert!(
                close(s0, n0) && close(s1, n1),
                "stable ({s0:e}, {s1:e}) and naive ({n0:e}, {n1:e}) disagree beyond {tol:e}\n{}",
                ctx()
            );
        }
    }
}

pub mod quadric {
    //! The `ray_quadric` target: general quadrics (matrix form), ellipsoids, cylinders and
    //! cones from fuzz bytes; roots against the implicit equation, hits against their own
    //! error bound.
    //!
    //! Layout: `flags: u8` (bits 0–1: 0 general, 1 ellipsoid, 2 cylinder, 3 cone; bit 2:
    //! quantized parameters; bit 3: interval `(0, ∞]`), then the ray (`origin`, `direction`,
    //! `t_min`, `t_max` unless bit 3), then the parameters: general `A` (6 upper-triangle
    //! entries `xx xy xz yy yz zz`), `b` (3), `c`; ellipsoid centre and radii; cylinder axis
    //! point, axis direction, radius; cone apex, axis, tan of the half angle.

    use super::{Enc, Input, fmt_ray};
    use glam::{DMat3, DVec3, Vec3};
    use halfray_core::float::F64_UNIT_ROUNDOFF;
    use halfray_core::quadric::{Ellipsoid, Quadric};
    use halfray_core::ray::Ray;

    /// Below this the discriminant's terms are close to the `f64` subnormal range (`2.2e-308`)
    /// and round absolutely; residuals are not checked there.
    pub const F64_NEAR_UNDERFLOW: f64 = 1e-290;

    /// Multiple of the `f64` unit roundoff in the residual bound. The roots come from the
    /// stable formulation in `f64` (module docs of `halfray_core::quadric`), whose first-order
    /// residual constant is below 20.
    pub const K: f64 = 64.0;

    /// Decodes a `ray_quadric` input: the surface (or the constructor's error) and the ray.
    pub fn decode(data: &[u8]) -> (Result<Quadric, halfray_core::error::GeometryError>, Ray) {
        let mut i = Input::new(data);
        let fl = i.u8();
        let q = fl & 4 != 0;
        let origin = if q { i.qvec3() } else { i.vec3() };
        let direction = i.vec3();
        let (t_min, t_max) = if fl & 8 != 0 {
            (0.0, f32::INFINITY)
        } else {
            (i.f32(), i.f32())
        };
        let ray = Ray::with_interval(origin, direction, t_min, t_max);
        let mut s = || if q { i.q() } else { i.f32() };
        let mut v = || Vec3::new(s(), s(), s());
        let surface = match fl & 3 {
            0 => {
                let e: [f64; 10] = core::array::from_fn(|_| f64::from(s()));
                let a =
                    DMat3::from_cols_array(&[e[0], e[1], e[2], e[1], e[3], e[4], e[2], e[4], e[5]]);
                Quadric::new(a, DVec3::new(e[6], e[7], e[8]), e[9])
            }
            1 => {
                let (c, r) = (v(), v());
                Ellipsoid::new(c, r).map(|e| *e.quadric())
            }
            2 => {
                let (p, a) = (v(), v());
                Quadric::cylinder(p, a, s())
            }
            _ => {
                let (p, a) = (v(), v());
                Quadric::cone(p, a, s())
            }
        };
        (surface, ray)
    }

    /// Encodes a raw general-quadric input with the default interval.
    pub fn encode_general(o: Vec3, d: Vec3, e: [f32; 10]) -> Vec<u8> {
        let mut enc = Enc::new().u8(8).vec3(o).vec3(d);
        for x in e {
            enc = enc.f32(x);
        }
        enc.done()
    }

    /// Encodes a raw ellipsoid (`kind` 1), cylinder (2) or cone (3) input, default interval.
    pub fn encode_shape(kind: u8, o: Vec3, d: Vec3, p: Vec3, q: Vec3, s: f32) -> Vec<u8> {
        let enc = Enc::new().u8(8 | kind).vec3(o).vec3(d).vec3(p).vec3(q);
        if kind == 1 {
            enc.done()
        } else {
            enc.f32(s).done()
        }
    }

    /// Fuzz target `ray_quadric`.
    pub fn ray_quadric(data: &[u8]) {
        let (surface, ray) = decode(data);
        if let Ok(q) = surface {
            check(&q, &ray);
        }
    }

    /// `(|f|(x), ‖A‖)`: `f` evaluated with absolute values (the scale of its rounding error).
    fn scale(q: &Quadric, x: DVec3) -> f64 {
        q.eval_abs(x)
    }

    /// The properties:
    /// 1. Every root from `roots()` satisfies `|f(o + t·d)| ≤ K·u·(|qa|·t² + 2|qb|·|t| + |qc|)`
    ///    where the `|q·|` are the ray polynomial's coefficients with absolute values
    ///    (the scale of their rounding error), evaluated in `f64`.
    /// 2. A hit has `t` in `(t_min, t_max]`, a unit normal, and a point within its
    ///    `point_error` of the surface: `|f(p)| ≤ |∇f(p)|·e + 3‖A‖·e² + γ·|f|(p)`, `e = |point_error|`.
    /// 3. A ray whose `f64` roots are both clearly outside the interval gets no hit; one whose
    ///    near root is clearly inside gets a hit at that root.
    pub fn check(q: &Quadric, ray: &Ray) {
        let ctx = || format!("quadric {q:?}\n{}", fmt_ray(ray));
        let roots = q.roots(ray);
        let hit = q.intersect(ray);
        if !ray.is_valid() {
            assert!(roots.is_none() && hit.is_none(), "{}", ctx());
            return;
        }
        let u = F64_UNIT_ROUNDOFF;
        let o = ray.origin.as_dvec3();
        let d = ray.direction.as_dvec3();
        let am = q.matrix();
        let aa = DMat3::from_cols(am.x_axis.abs(), am.y_axis.abs(), am.z_axis.abs());
        let xc = q.reference_point();
        let f0 = o - xc;
        // Coefficient scales: |qa| = |d|ᵀ|A||d|, |qb| = |d|ᵀ(|A||f₀| + |b_c|),
        // |qc| = |f|(o) (the same bound eval_abs documents).
        let qa_abs = d.abs().dot(aa * d.abs());
        let bc = q.gradient(xc) * 0.5;
        let k = q.eval(xc);
        let g_abs = bc.abs(); // |b_c|
        let qb_abs = d.abs().dot(aa * f0.abs() + g_abs);
        let qc_abs = scale(q, o);
        // The near root `qc/q` inherits qc's rounding: forward error δ = K·u·|qc|/|q| with
        // |q| ≥ |qb|, which adds qa·δ² + |F'|·δ to the residual.
        let qb = d.dot(q.gradient(o) * 0.5);
        let delta = K * u * qc_abs / qb.abs();
        // The discriminant's scale qb² (or qa·qc) near the f64 subnormal range loses relative
        // precision: roots there are checked for order only.
        let underflows = (qb_abs * qb_abs).max(qa_abs * qc_abs) < F64_NEAR_UNDERFLOW;
        if let Some((t0, t1)) = roots.filter(|_| !underflows) {
            assert!(t0 <= t1, "roots out of order\n{}", ctx());
            for t in [t0, t1] {
                // f in the quadric's centred coordinates, y = (o − x_c) + t·d: a world point
                // o + t·d would round away a displacement that a large curvature still sees.
                let y = f0 + d * t;
                let fx = y.dot(am * y + bc * 2.0) + k;
                let ya = y.abs();
                let f_abs = ya.dot(aa * ya + bc.abs() * 2.0) + k.abs();
                // Plus the rounding of y itself (≤ u·|y| per component).
                let bound = K * u * (qa_abs * t * t + 2.0 * qb_abs * t.abs() + qc_abs + f_abs)
                    + qa_abs * delta * delta
                    + 2.0 * (qb_abs + qa_abs * t.abs()) * delta;
                if bound.is_finite() && fx.is_finite() {
                    assert!(
                        fx.abs() <= bound + 1e-300,
                        "root t = {t:e}: f = {fx:e} > bound {bound:e}\n{}",
                        ctx()
                    );
                }
            }
        }
        if let Some(h) = hit {
            super::check_hit_basics(ray, &h, &ctx);
            let p = h.point.as_dvec3();
            let e = h.point_error.as_dvec3().length();
            let fx = q.eval(p);
            let gl = q.gradient(p).length();
            let a_norm = (am.x_axis.length_squared()
                + am.y_axis.length_squared()
                + am.z_axis.length_squared())
            .sqrt();
            let bound = gl * e + 3.0 * a_norm * e * e + 32.0 * u * scale(q, p);
            if bound.is_finite() && fx.is_finite() {
                assert!(
                    fx.abs() <= bound * (1.0 + 1e-9) + 1e-300,
                    "hit point {:?}: f = {fx:e} > {bound:e} (point_error {:?})\n{}",
                    h.point,
                    h.point_error,
                    ctx()
                );
            }
            let Some((t0, t1)) = roots else {
                panic!("a hit without roots\n{}", ctx())
            };
            assert!(
                h.t == t0 as f32 || h.t == t1 as f32,
                "hit t = {:e} is neither root ({t0:e}, {t1:e})\n{}",
                h.t,
                ctx()
            );
        }
        // 3. Interval logic against the roots themselves (the f32 rounding of each root is
        // what `contains` sees).
        if let Some((t0, t1)) = roots {
            let c0 = ray.contains(t0 as f32);
            let c1 = ray.contains(t1 as f32);
            match (c0, c1, hit) {
                (true, _, Some(h)) => assert_eq!(h.t, t0 as f32, "near root skipped\n{}", ctx()),
                (false, true, Some(h)) => assert_eq!(h.t, t1 as f32, "{}", ctx()),
                (false, false, Some(_)) => panic!("hit with both roots outside\n{}", ctx()),
                _ => {} // a hit may be dropped only when its point is not representable
            }
        }
    }
}

pub mod scene {
    //! The `scene_file` target: arbitrary bytes as a scene file. Never a panic; an error names
    //! the scene file (and a line for errors inside it); an accepted scene has a usable camera,
    //! and the centre pixel's ray through every object answers inside its interval.
    //!
    //! The file is parsed as if it lived in `fuzz/scene_dir/` (small meshes only, so the target
    //! stays fast): `meshes/cube.obj` and friends resolve there.

    use halfray::error::Error;
    use halfray::render::geom::QueryCtx;
    use halfray::render::plan::EffectPlan;
    use std::path::Path;

    /// Where the fuzzed scene pretends to live (absolute at compile time: the fuzz crate and
    /// the replay test both sit one folder below the project root).
    pub const SCENE_PATH: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fuzz/scene_dir/input.toml"
    );

    /// Fuzz target `scene_file`: lossy UTF-8 text through [`check`].
    pub fn scene_file(data: &[u8]) {
        check(&String::from_utf8_lossy(data));
    }

    /// The properties (module documentation).
    pub fn check(text: &str) {
        // A fuzzed path could name a device or a huge file outside the sandbox folder; parse
        // only files the target controls.
        if text.contains("..") || text.contains("\"/") || text.contains("'/") {
            return;
        }
        let path = Path::new(SCENE_PATH);
        match halfray::scene::parse(text, path) {
            Ok(scene) => {
                let cam = &scene.camera;
                assert!(
                    cam.width >= 1 && cam.height >= 1,
                    "empty image accepted\n{text}"
                );
                for v in [cam.eye, cam.forward, cam.right, cam.up] {
                    assert!(v.is_finite(), "non-finite camera {cam:?}\n{text}");
                }
                for v in [cam.forward, cam.right, cam.up] {
                    assert!(
                        (v.length() - 1.0).abs() < 1e-3,
                        "camera frame not unit {cam:?}\n{text}"
                    );
                }
                let ray = cam.pixel_ray(cam.width / 2, cam.height / 2);
                assert!(ray.is_valid(), "invalid centre ray {ray:?}\n{text}");
                let plan = EffectPlan::derive(&scene, false);
                let _ = plan.explain(&scene);
                let mut qc = QueryCtx::default();
                for o in &scene.objects {
                    if let Some(h) = o.closest(&ray, &mut qc) {
                        assert!(
                            ray.contains(h.hit.t),
                            "object hit at t = {} outside the ray interval\n{text}",
                            h.hit.t
                        );
                    }
                    let _ = o.occludes(&ray, &mut qc);
                }
            }
            Err(e) => {
                let msg = e.to_string();
                match &e {
                    Error::Input { at, .. } if at.file == path => assert!(
                        at.line.is_some() && msg.starts_with(SCENE_PATH),
                        "scene error without a line: {msg:?}\n{text}"
                    ),
                    Error::Input { .. } | Error::Io { .. } => {
                        assert!(!msg.is_empty(), "empty message\n{text}")
                    }
                    other => panic!("unexpected error kind {other:?}\n{text}"),
                }
            }
        }
    }
}

fn seeds_sphere(s: &mut Vec<Seed>) {
    let t = |name: &str, b: Vec<u8>| ("ray_sphere", format!("seed-{name}"), b);
    let c = Vec3::new(1.0, 2.0, 3.0);
    let x = Vec3::X;
    s.push(t("through-centre", sphere::encode(c, 1.0, c - 5.0 * x, x)));
    s.push(t(
        "tangent",
        sphere::encode(c, 1.0, c + Vec3::new(-5.0, 1.0, 0.0), x),
    ));
    s.push(t(
        "inside",
        sphere::encode(c, 1.0, c, Vec3::new(0.3, -0.2, 0.9)),
    ));
    s.push(t("on-surface-inward", sphere::encode(c, 1.0, c + x, -x)));
    s.push(t("on-surface-outward", sphere::encode(c, 1.0, c + x, x)));
    // Small far spheres (where the textbook discriminant cancels).
    let far = Vec3::new(1e4, 0.0, 0.0);
    s.push(t(
        "far-small",
        sphere::encode(far, 1.0, Vec3::ZERO, far + Vec3::new(0.0, 0.7, 0.0)),
    ));
    let far = Vec3::new(3e6, -2e6, 1e6);
    s.push(t("very-far", sphere::encode(far, 0.5, Vec3::ZERO, far)));
    s.push(t(
        "tiny-direction",
        sphere::encode(c, 1.0, c - 5.0 * x, x * 1e-30),
    ));
    s.push(t(
        "huge-direction",
        sphere::encode(c, 1.0, c - 5.0 * x, x * 1e30),
    ));
    s.push(t("zero-radius", sphere::encode(c, 0.0, c - 5.0 * x, x)));
    s.push(t("nan-radius", sphere::encode(c, f32::NAN, c - 5.0 * x, x)));
    s.push(t(
        "inf-origin",
        sphere::encode(c, 1.0, Vec3::splat(f32::INFINITY), -x),
    ));
    s.push(t(
        "subnormal-radius",
        sphere::encode(Vec3::ZERO, 1e-40, -x, x),
    ));
}

fn seeds_quadric(s: &mut Vec<Seed>) {
    let t = |name: &str, b: Vec<u8>| ("ray_quadric", format!("seed-{name}"), b);
    let o = Vec3::new(-5.0, 0.25, 0.5);
    let x = Vec3::X;
    // The specification's ellipsoid x²/4 + y²/9 + z² = 1 and a ray along x.
    s.push(t(
        "ellipsoid",
        quadric::encode_shape(1, o, x, Vec3::ZERO, Vec3::new(2.0, 3.0, 1.0), 0.0),
    ));
    s.push(t(
        "ellipsoid-far",
        quadric::encode_shape(
            1,
            Vec3::ZERO,
            Vec3::new(1e5, 1.0, 0.0),
            Vec3::new(1e5, 0.0, 0.0),
            Vec3::new(2.0, 3.0, 1.0),
            0.0,
        ),
    ));
    s.push(t(
        "cylinder-along-axis",
        quadric::encode_shape(2, Vec3::ZERO, Vec3::Z, Vec3::ZERO, Vec3::Z, 1.0),
    ));
    s.push(t(
        "cylinder-across",
        quadric::encode_shape(2, o, x, Vec3::ZERO, Vec3::Z, 1.0),
    ));
    s.push(t(
        "cone-apex",
        quadric::encode_shape(3, Vec3::new(-1.0, 0.0, 0.0), x, Vec3::ZERO, Vec3::Z, 0.5),
    ));
    s.push(t(
        "cone-generator",
        quadric::encode_shape(
            3,
            Vec3::new(-1.0, 0.0, -2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::ZERO,
            Vec3::Z,
            0.5,
        ),
    ));
    // General forms: hyperboloid x² + y² − z² − 1, paraboloid x² + y² − z, plane-like 2x − 1.
    s.push(t(
        "hyperboloid",
        quadric::encode_general(o, x, [1.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0]),
    ));
    s.push(t(
        "paraboloid-axis",
        quadric::encode_general(
            Vec3::new(0.0, 0.0, 5.0),
            -Vec3::Z,
            [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -0.5, 0.0],
        ),
    ));
    s.push(t(
        "linear",
        quadric::encode_general(
            o,
            x,
            [0.0; 6]
                .into_iter()
                .chain([1.0, 0.0, 0.0, -1.0])
                .collect::<Vec<_>>()
                .try_into()
                .unwrap(),
        ),
    ));
    s.push(t(
        "nan-entry",
        quadric::encode_general(
            o,
            x,
            [1.0, f32::NAN, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0],
        ),
    ));
}

fn seeds_scene(s: &mut Vec<Seed>) {
    let t = |name: &str, text: &str| {
        (
            "scene_file",
            format!("seed-{name}"),
            text.as_bytes().to_vec(),
        )
    };
    s.push(t("shadows", include_str!("../../../scenes/shadows.toml")));
    s.push(t("mirror", include_str!("../../../scenes/mirror.toml")));
    s.push(t("glass", include_str!("../../../scenes/glass.toml")));
    s.push(t("csg", include_str!("../../../scenes/csg.toml")));
    s.push(t(
        "subdivision",
        include_str!("../../../scenes/subdivision.toml"),
    ));
    let small = r#"ambient = [0.1, 0.1, 0.1]
max_depth = 3

[camera]
eye = [0, 1, 6]
look_at = [0, 0, 0]
width = 8
height = 6
fov = 45

[[light]]
type = "point"
position = [4, 5, 6]
intensity = 40
cast_shadows = true

[material.m]
diffuse = [0.8, 0.2, 0.2]

[mesh.cube]
file = "meshes/cube.obj"
smooth = { step = 0.5, iterations = 2 }
subdivide = 1

[mesh.octa]
file = "meshes/octahedron.obj"

[[object]]
type = "mesh"
mesh = "cube"
material = "m"
transform = [{ scale = [0.5, 0.5, 0.5] }, { rotate = { axis = [0, 1, 0], degrees = 30 } }]

[[object]]
type = "csg"
op = "difference"
material = "m"
operands = [
  { type = "mesh", mesh = "octa", material = "m" },
  { type = "sphere", center = [0, 0, 0], radius = 0.6, material = "m" },
]
"#;
    s.push(t("small-meshes", small));
    s.push(t("unknown-key", "bogus = 1\n"));
    s.push(t("not-toml", "[camera\nwidth = "));
    s.push(t("empty", ""));
    s.push(t(
        "open-mesh-in-csg",
        &small.replace("meshes/octahedron.obj", "meshes/open.obj"),
    ));
    s.push(t(
        "missing-mesh",
        &small.replace("meshes/cube.obj", "meshes/none.obj"),
    ));
    s.push(t("nan", &small.replace("fov = 45", "fov = nan")));
    s.push(t(
        "singular-transform",
        &small.replace("scale = [0.5, 0.5, 0.5]", "scale = [0.5, 0, 0.5]"),
    ));
}
