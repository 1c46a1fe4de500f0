//! The `overlap` target: pairs of bounding volumes from raw `f32` bits, the conservative
//! overlap tests of `halfray_core::volume::overlap` against an independent `f64` oracle.
//!
//! Layout: two volumes, each `kind: u8` (mod 4: sphere, box, OBB, capsule), then 13 raw
//! `f32`s: `p` (3), `q` (3), `s` (3), `rot` (4). A sphere is `(p, |s.x|)` with the sign kept
//! (`BoundingSphere::new(p, s.x)`), a box `[p, q]`, an OBB `Obb::orthonormalized(p, rows of
//! Mat3::from_quat(rot), s)` (the quaternion normalised in `f32`), a capsule
//! `Capsule::new(p, q, s.x)`. Any bit pattern occurs: NaN, ±∞, negative sizes and
//! non-rotations must be refused by the constructors with the matching typed error, never a
//! panic; every constructor's answer (accepted, or refused and with which error) is checked
//! against a prediction from its documented contract ([`expected_error`]).
//!
//! Properties, for every pair the crate has a test for (all but capsule–box, capsule–OBB):
//! 1. **Never "apart" for overlapping volumes**: when the oracle finds a point inside both
//!    volumes shrunk by `m = 2⁻⁴⁰·M` (`M` the largest input magnitude; the margin only has to
//!    exceed the `f64` rounding of the membership checks), the test must answer "overlap".
//!    The oracle searches by alternating projections in `f64` (exact ball, box, segment
//!    projections; for an OBB the clamp in its frame mapped back with the `f64` inverse of
//!    the axis matrix); only the witness's membership, checked directly on each volume's
//!    definition, counts. Valid for every finite input (no narrowing).
//! 2. **No answer "overlap" beyond the documented band**: along the axis between the
//!    closest points the alternating projections reach (for OBB–OBB: along each of the 15
//!    SAT axes), the exact `f64` projections of the two volumes (from their corners,
//!    endpoints and radii) are farther apart than the test's documented band. Narrowed to
//!    `2⁻⁹⁰ ≤ M ≤ 2⁹⁰` (outside it the bands' absolute terms are stated only loosely). For
//!    box–OBB the box's side is the box itself (its exact corners, the world axes), never
//!    its `Obb::from_aabb` conversion, which the test under check uses.
//! 3. Symmetry: the same answer with the arguments swapped (where both orders exist).

use crate::{Enc, Input, Seed, reached};
use glam::{DMat3, DVec3, Mat3, Quat, Vec3};
use halfray_core::aabb::Aabb;
use halfray_core::volume::overlap::*;
use halfray_core::volume::{
    BoundingSphere, Capsule, OBB_ORTHONORMALIZE_MAX_DEVIATION, Obb, VolumeError,
};

/// One bounding volume of any kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Volume {
    /// A ball.
    Sphere(BoundingSphere),
    /// An axis-aligned box.
    Aabb(Aabb),
    /// An oriented box.
    Obb(Obb),
    /// A capsule.
    Capsule(Capsule),
}

impl Volume {
    /// Largest magnitude of any of its parameters.
    pub fn magnitude(&self) -> f64 {
        let m = |v: Vec3| f64::from(v.abs().max_element());
        match self {
            Self::Sphere(s) => m(s.center()).max(f64::from(s.radius())),
            Self::Aabb(b) => m(b.min).max(m(b.max)),
            Self::Obb(o) => m(o.center()).max(m(o.half_extents())),
            Self::Capsule(c) => m(c.a()).max(m(c.b())).max(f64::from(c.radius())),
        }
    }

    /// The volume moved by `t` (its parameters rounded to `f32`).
    pub fn translated(&self, t: DVec3) -> Self {
        let mv = |v: Vec3| (v.as_dvec3() + t).as_vec3();
        match self {
            Self::Sphere(s) => {
                BoundingSphere::new(mv(s.center()), s.radius()).map_or(*self, Self::Sphere)
            }
            Self::Aabb(b) => Self::Aabb(Aabb::new(mv(b.min), mv(b.max))),
            Self::Obb(o) => {
                Obb::new(mv(o.center()), o.axes(), o.half_extents()).map_or(*self, Self::Obb)
            }
            Self::Capsule(c) => {
                Capsule::new(mv(c.a()), mv(c.b()), c.radius()).map_or(*self, Self::Capsule)
            }
        }
    }

    /// A point of the volume.
    pub fn center(&self) -> DVec3 {
        match self {
            Self::Sphere(s) => s.center().as_dvec3(),
            Self::Aabb(b) => (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5,
            Self::Obb(o) => o.center().as_dvec3(),
            Self::Capsule(c) => c.a().as_dvec3(),
        }
    }

    /// `true` when `x` lies in the volume shrunk by `m` (evaluated in `f64` straight from
    /// the definition).
    pub fn contains(&self, x: DVec3, m: f64) -> bool {
        match self {
            Self::Sphere(s) => (x - s.center().as_dvec3()).length() <= f64::from(s.radius()) - m,
            Self::Aabb(b) => {
                (x - b.min.as_dvec3()).min_element() >= m
                    && (b.max.as_dvec3() - x).min_element() >= m
            }
            Self::Obb(o) => {
                let d = x - o.center().as_dvec3();
                (0..3).all(|k| {
                    o.axes()[k].as_dvec3().dot(d).abs() <= f64::from(o.half_extents()[k]) - m
                })
            }
            Self::Capsule(c) => {
                let q = closest_on_segment(x, c.a().as_dvec3(), c.b().as_dvec3());
                (x - q).length() <= f64::from(c.radius()) - m
            }
        }
    }

    /// The projection of `x` onto the volume shrunk by `s` (exact for balls, boxes and
    /// capsules; for an OBB the clamp in its frame, a point of the box near the projection).
    fn project(&self, x: DVec3, s: f64) -> DVec3 {
        let ball = |c: DVec3, r: f64| {
            let r = (r - s).max(0.0);
            let d = x - c;
            let l = d.length();
            if l <= r { x } else { c + d * (r / l) }
        };
        match self {
            Self::Sphere(sp) => ball(sp.center().as_dvec3(), f64::from(sp.radius())),
            Self::Aabb(b) => {
                let lo = b.min.as_dvec3() + s;
                let hi = b.max.as_dvec3() - s;
                let mid = (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5;
                let lo2 = lo.min(mid);
                let hi2 = hi.max(mid);
                x.clamp(lo2, hi2.max(lo2))
            }
            Self::Obb(o) => {
                let (a, inv) = frame(o);
                let c = o.center().as_dvec3();
                let e = (o.half_extents().as_dvec3() - s).max(DVec3::ZERO);
                let t = (a * (x - c)).clamp(-e, e);
                c + inv * t
            }
            Self::Capsule(c) => {
                let q = closest_on_segment(x, c.a().as_dvec3(), c.b().as_dvec3());
                ball(q, f64::from(c.radius()))
            }
        }
    }

    /// `(min, max)` of `n·x` over the volume, in `f64` from its corners, endpoints and radii.
    pub fn support(&self, n: DVec3) -> (f64, f64) {
        let pts_r = |pts: &[DVec3], r: f64| {
            let lo = pts.iter().map(|p| p.dot(n)).fold(f64::INFINITY, f64::min);
            let hi = pts
                .iter()
                .map(|p| p.dot(n))
                .fold(f64::NEG_INFINITY, f64::max);
            let rr = r * n.length();
            (lo - rr, hi + rr)
        };
        match self {
            Self::Sphere(s) => pts_r(&[s.center().as_dvec3()], f64::from(s.radius())),
            Self::Aabb(b) => {
                let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
                pts_r(
                    &corners(|t| DVec3::select(t.cmplt(DVec3::ZERO), lo, hi)),
                    0.0,
                )
            }
            Self::Obb(o) => {
                let (_, inv) = frame(o);
                let (c, e) = (o.center().as_dvec3(), o.half_extents().as_dvec3());
                pts_r(&corners(|t| c + inv * (t * e)), 0.0)
            }
            Self::Capsule(c) => pts_r(&[c.a().as_dvec3(), c.b().as_dvec3()], f64::from(c.radius())),
        }
    }
}

/// The 8 points `f(t)` for `t ∈ {−1, 1}³`.
fn corners(f: impl Fn(DVec3) -> DVec3) -> Vec<DVec3> {
    let sign = |bit: bool| if bit { 1.0 } else { -1.0 };
    (0..8)
        .map(|i| {
            f(DVec3::new(
                sign(i & 1 != 0),
                sign(i & 2 != 0),
                sign(i & 4 != 0),
            ))
        })
        .collect()
}

/// The axis matrix of an OBB (rows = axes) and its inverse, in `f64`: the box's corners are
/// `c + A⁻¹·(±e)` exactly (slab definition).
fn frame(o: &Obb) -> (DMat3, DMat3) {
    let [a0, a1, a2] = o.axes().map(|a| a.as_dvec3());
    let a = DMat3::from_cols(a0, a1, a2).transpose();
    (a, a.inverse())
}

/// The point of `[a, b]` closest to `x` (`f64`).
fn closest_on_segment(x: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 <= 0.0 {
        return a;
    }
    a + ab * ((x - a).dot(ab) / l2).clamp(0.0, 1.0)
}

/// The crate's test for the pair, `None` for capsule–box and capsule–OBB (no test).
pub fn f32_overlap(a: &Volume, b: &Volume) -> Option<bool> {
    use Volume::*;
    Some(match (a, b) {
        (Aabb(x), Aabb(y)) => aabb_aabb(x, y),
        (Sphere(x), Sphere(y)) => sphere_sphere(x, y),
        (Sphere(s), Aabb(x)) | (Aabb(x), Sphere(s)) => sphere_aabb(s, x),
        (Sphere(s), Obb(x)) | (Obb(x), Sphere(s)) => sphere_obb(s, x),
        (Obb(x), Obb(y)) => obb_obb(x, y),
        (Aabb(x), Obb(y)) | (Obb(y), Aabb(x)) => aabb_obb(x, y),
        (Capsule(x), Capsule(y)) => capsule_capsule(x, y),
        (Capsule(c), Sphere(s)) | (Sphere(s), Capsule(c)) => capsule_sphere(c, s),
        _ => return None,
    })
}

/// A point of both volumes shrunk by `m`, by alternating projections onto them shrunk by
/// `2m` (at most 400 rounds); `None` when none was found (the volumes may still overlap).
pub fn overlap_witness(a: &Volume, b: &Volume, m: f64) -> Option<DVec3> {
    let mut x = (a.center() + b.center()) * 0.5;
    for _ in 0..400 {
        let y = a.project(x, 2.0 * m);
        if a.contains(y, m) && b.contains(y, m) {
            return Some(y);
        }
        x = b.project(y, 2.0 * m);
        if a.contains(x, m) && b.contains(x, m) {
            return Some(x);
        }
    }
    None
}

/// The gap between the exact projections of the two volumes along the axis joining the
/// closest points reached by 400 rounds of alternating projections, over the axis length
/// (a lower bound on their distance; `≤ 0` when they touch or no axis was found).
pub fn separation(a: &Volume, b: &Volume) -> f64 {
    let mut y = b.center();
    let mut x = a.project(y, 0.0);
    for _ in 0..400 {
        y = b.project(x, 0.0);
        x = a.project(y, 0.0);
    }
    let n = x - y;
    let l = n.length();
    if l <= 0.0 || !l.is_finite() {
        return 0.0;
    }
    let (a_lo, _) = a.support(n);
    let (_, b_hi) = b.support(n);
    (a_lo - b_hi) / l
}

/// The largest gap between the two boxes' projections over the 15 SAT axes (not
/// normalised), and the scale `S = Σ|Δc| + Σe_a + Σe_b` the OBB band is relative to.
pub fn obb_axes_gap(a: &Obb, b: &Obb) -> (f64, f64) {
    let aa = a.axes().map(|x| x.as_dvec3());
    let ba = b.axes().map(|x| x.as_dvec3());
    let gap = sat_gap(&Volume::Obb(*a), aa, &Volume::Obb(*b), ba);
    let s = (b.center().as_dvec3() - a.center().as_dvec3())
        .abs()
        .element_sum()
        + a.half_extents().as_dvec3().element_sum()
        + b.half_extents().as_dvec3().element_sum();
    (gap, s)
}

/// [`obb_axes_gap`] for an axis-aligned box and an OBB: the box's side of every projection
/// is its own exact `f64` support (from its corners), its axes the world axes, and its
/// centre and half-extents in `S` the exact `(min + max)/2` and `(max − min)/2`. Nothing of
/// the code under test (in particular not [`Obb::from_aabb`], which [`aabb_obb`] uses).
pub fn box_obb_axes_gap(a: &Aabb, b: &Obb) -> (f64, f64) {
    let ba = b.axes().map(|x| x.as_dvec3());
    let gap = sat_gap(
        &Volume::Aabb(*a),
        [DVec3::X, DVec3::Y, DVec3::Z],
        &Volume::Obb(*b),
        ba,
    );
    let (lo, hi) = (a.min.as_dvec3(), a.max.as_dvec3());
    let s = (b.center().as_dvec3() - (lo + hi) * 0.5)
        .abs()
        .element_sum()
        + ((hi - lo) * 0.5).element_sum()
        + b.half_extents().as_dvec3().element_sum();
    (gap, s)
}

/// The largest gap between the exact projections of `va` and `vb` over the 15 SAT axes of
/// two boxes with axes `aa` and `ba`: the 6 face normals and the 9 cross products `aᵢ × bⱼ`
/// (not normalised).
fn sat_gap(va: &Volume, aa: [DVec3; 3], vb: &Volume, ba: [DVec3; 3]) -> f64 {
    let mut axes: Vec<DVec3> = aa.iter().chain(ba.iter()).copied().collect();
    for x in aa {
        for y in ba {
            axes.push(x.cross(y));
        }
    }
    axes.iter()
        .map(|&l| {
            let (alo, ahi) = va.support(l);
            let (blo, bhi) = vb.support(l);
            (alo - bhi).max(blo - ahi)
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The absolute part of every band, [`BAND_ABS_PER_MAGNITUDE`]`·max(m, 1)`, for the largest
/// input magnitude `m` (world units).
fn band_abs(m: f64) -> f64 {
    f64::from(BAND_ABS_PER_MAGNITUDE) * m.max(1.0)
}

/// The documented false-positive band of the pair's test as a distance, `None` where
/// property 2 is not checked this way (OBB–OBB and box–OBB use [`obb_axes_gap`]).
pub fn band(a: &Volume, b: &Volume) -> Option<f64> {
    use Volume::*;
    let m = a.magnitude().max(b.magnitude());
    let abs = band_abs(m);
    let l1 = |v: Vec3| v.as_dvec3().abs().element_sum();
    Some(match (a, b) {
        (Aabb(_), Aabb(_)) => m * 1e-15,
        (Sphere(x), Sphere(y)) => {
            f64::from(SPHERE_BAND_REL) * (f64::from(x.radius()) + f64::from(y.radius())) + abs
        }
        (Sphere(s), Aabb(_)) | (Aabb(_), Sphere(s)) => {
            f64::from(SPHERE_BAND_REL) * f64::from(s.radius()) + abs
        }
        (Sphere(s), Obb(o)) | (Obb(o), Sphere(s)) => {
            let d = l1(s.center() - o.center()).max(
                (s.center().as_dvec3() - o.center().as_dvec3())
                    .abs()
                    .element_sum(),
            );
            f64::from(SPHERE_OBB_BAND_REL) * (f64::from(s.radius()) + d + l1(o.half_extents()))
                + abs
        }
        (Capsule(x), Capsule(y)) => {
            CAPSULE_BAND_REL
                * (l1(x.a())
                    + l1(x.b())
                    + l1(y.a())
                    + l1(y.b())
                    + f64::from(x.radius())
                    + f64::from(y.radius()))
        }
        (Capsule(c), Sphere(s)) | (Sphere(s), Capsule(c)) => {
            CAPSULE_BAND_REL
                * (l1(c.a())
                    + l1(c.b())
                    + 2.0 * l1(s.center())
                    + f64::from(c.radius())
                    + f64::from(s.radius()))
        }
        _ => return None,
    })
}

/// What [`check_pair`] could decide.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Decided {
    /// The oracle proved overlap (and the test agreed).
    pub overlap: bool,
    /// The oracle proved a separation beyond the band (and the test agreed).
    pub apart: bool,
}

/// Properties 1–3 of the module docs on one pair; panics with the pair printed when one is
/// broken. `None` when the crate has no test for the pair.
pub fn check_pair(a: &Volume, b: &Volume) -> Option<Decided> {
    let got = f32_overlap(a, b)?;
    let ctx = || format!("a = {a:?}\nb = {b:?}");
    if let Some(swapped) = f32_overlap(b, a) {
        assert_eq!(got, swapped, "asymmetric answer\n{}", ctx());
    }
    let mut decided = Decided::default();
    let mag = a.magnitude().max(b.magnitude()).max(f64::MIN_POSITIVE);
    let m = mag * 2f64.powi(-40);
    if let Some(w) = overlap_witness(a, b, m) {
        assert!(
            got,
            "test says apart, but {w} lies inside both (margin {m:e})\n{}",
            ctx()
        );
        decided.overlap = true;
    }
    let in_domain = (2f64.powi(-90)..=2f64.powi(90)).contains(&mag);
    if !decided.overlap && in_domain {
        let sat = match (a, b) {
            (Volume::Obb(x), Volume::Obb(y)) => Some(obb_axes_gap(x, y)),
            (Volume::Aabb(x), Volume::Obb(y)) | (Volume::Obb(y), Volume::Aabb(x)) => {
                Some(box_obb_axes_gap(x, y))
            }
            _ => None,
        };
        if let Some((gap, s)) = sat {
            if gap > f64::from(OBB_OBB_BAND_REL) * s + band_abs(mag) {
                assert!(
                    !got,
                    "gap {gap:e} beyond the OBB band, test says overlap\n{}",
                    ctx()
                );
                decided.apart = true;
            }
        } else if let Some(band) = band(a, b) {
            let gap = separation(a, b);
            if gap > band {
                assert!(
                    !got,
                    "separated by {gap:e} > band {band:e}, test says overlap\n{}",
                    ctx()
                );
                decided.apart = true;
            }
        }
    }
    Some(decided)
}

/// Builds one volume from its kind and raw parameters (module docs), or the constructor's
/// error.
pub fn build(kind: u8, p: Vec3, q: Vec3, s: Vec3, rot: [f32; 4]) -> Result<Volume, VolumeError> {
    Ok(match kind % 4 {
        0 => Volume::Sphere(BoundingSphere::new(p, s.x)?),
        1 => Volume::Aabb(Aabb::new(p, q)),
        2 => Volume::Obb(Obb::orthonormalized(p, obb_axes(rot), s)?),
        _ => Volume::Capsule(Capsule::new(p, q, s.x)?),
    })
}

/// Half-width of the band around [`OBB_ORTHONORMALIZE_MAX_DEVIATION`] in which the oracle
/// does not judge `NotOrthonormal`, relative to `max(1, max |aᵢ|²)` (unitless). The oracle's
/// `f64` Gram entries `aᵢ·aⱼ` are sums of three exact products of `f32`s (each fits an
/// `f64`), so each carries at most `3·2⁻⁵³` of `max |aᵢ|²`; the code's deviation rounds
/// likewise. `2⁻⁴⁰` is 2¹¹ times both together: only a deviation within rounding of the
/// threshold is left undecided.
pub const OBB_DEVIATION_BAND_REL: f64 = 1.0 / 1_099_511_627_776.0;

/// The OBB axes the decoder hands to `Obb::orthonormalized`: the rows of
/// `Mat3::from_quat(q/|q|)`, the quaternion normalised in `f32` (module docs). Harness
/// code (glam), not the code under test.
fn obb_axes(rot: [f32; 4]) -> [Vec3; 3] {
    let qt = Quat::from_array(rot);
    let qt = qt * (1.0 / qt.length());
    let m = Mat3::from_quat(qt);
    [m.x_axis, m.y_axis, m.z_axis]
}

/// What the constructor must answer, from the documented contracts of
/// `BoundingSphere::new`, `Capsule::new`, `Obb::new` and `Obb::orthonormalized` alone:
/// `Some(Ok(()))` when it must accept, `Some(Err(kinds))` when it must refuse with one of
/// `kinds` (several where more than one documented error applies: the contracts do not
/// order them), `None` where the contract leaves it undecided (an OBB whose axes deviate
/// from orthonormal by the threshold within [`OBB_DEVIATION_BAND_REL`]). `Aabb::new` never
/// refuses.
///
/// * Sphere, capsule: `NonFiniteParameter` for a non-finite centre, endpoint or radius;
///   `NegativeSize` for a radius `< 0` (`−0.0` is not).
/// * OBB: `NonFiniteParameter` for a non-finite centre, half-extent or axis; `NegativeSize`
///   for a half-extent `< 0`; `NotOrthonormal` when the finite axes' largest
///   `|aᵢ·aⱼ − δᵢⱼ|` (here in `f64` from the `f32` axes) exceeds
///   [`OBB_ORTHONORMALIZE_MAX_DEVIATION`]. Otherwise accepted: the re-orthonormalised axes
///   are an `f64` orthonormal frame rounded to `f32`, which [`halfray_core::volume::OBB_ORTHONORMAL_TOL`]
///   is documented to accept (3 units of roundoff against its 8).
pub fn expected_error(
    kind: u8,
    p: Vec3,
    q: Vec3,
    s: Vec3,
    rot: [f32; 4],
) -> Option<Result<(), Vec<VolumeError>>> {
    use VolumeError::{NegativeSize, NonFiniteParameter, NotOrthonormal};
    let r = s.x;
    let mut kinds = Vec::new();
    match kind % 4 {
        0 => {
            if !p.is_finite() || !r.is_finite() {
                kinds.push(NonFiniteParameter);
            }
            if r < 0.0 {
                kinds.push(NegativeSize);
            }
        }
        1 => {}
        2 => {
            let axes = obb_axes(rot);
            let axes_finite = axes.iter().all(|a| a.is_finite());
            if !p.is_finite() || !s.is_finite() || !axes_finite {
                kinds.push(NonFiniteParameter);
            }
            if s.min_element() < 0.0 {
                kinds.push(NegativeSize);
            }
            if axes_finite {
                let a = axes.map(|a| a.as_dvec3());
                let mut dev = 0.0f64;
                let mut scale = 1.0f64;
                for i in 0..3 {
                    scale = scale.max(a[i].length_squared());
                    for j in 0..3 {
                        let target = if i == j { 1.0 } else { 0.0 };
                        dev = dev.max((a[i].dot(a[j]) - target).abs());
                    }
                }
                let band = OBB_DEVIATION_BAND_REL * scale;
                if (dev - OBB_ORTHONORMALIZE_MAX_DEVIATION).abs() <= band {
                    return None;
                }
                if dev > OBB_ORTHONORMALIZE_MAX_DEVIATION {
                    kinds.push(NotOrthonormal);
                }
            }
        }
        _ => {
            if !p.is_finite() || !q.is_finite() || !r.is_finite() {
                kinds.push(NonFiniteParameter);
            }
            if r < 0.0 {
                kinds.push(NegativeSize);
            }
        }
    }
    Some(if kinds.is_empty() { Ok(()) } else { Err(kinds) })
}

fn decode_one(i: &mut Input<'_>) -> Option<Volume> {
    let kind = i.u8();
    let (p, q, s) = (i.vec3(), i.vec3(), i.vec3());
    let rot = [i.f32(), i.f32(), i.f32(), i.f32()];
    let built = build(kind, p, q, s, rot);
    let ctx = || format!("kind {kind}: p {p} q {q} s {s} rot {rot:?}");
    match (&built, expected_error(kind, p, q, s, rot)) {
        (Ok(_), Some(Ok(()))) | (_, None) => {}
        (Err(e), Some(Err(kinds))) => {
            reached();
            assert!(
                kinds.contains(e),
                "refused as {e:?}, expected one of {kinds:?}: {}",
                ctx()
            );
        }
        (Ok(v), Some(Err(kinds))) => panic!("accepted {v:?}, expected {kinds:?}: {}", ctx()),
        (Err(e), Some(Ok(()))) => panic!("refused valid input ({e:?}): {}", ctx()),
    }
    let v = built.ok()?;
    // A box with NaN or infinite corners is representable but overlaps nothing and has no
    // oracle: only "never panics" is checked for it.
    if let Volume::Aabb(b) = v
        && (!b.is_finite() || !b.is_valid())
    {
        let _ = f32_overlap(&v, &v);
        return None;
    }
    Some(v)
}

/// Fuzz target `overlap`: decodes two volumes (module docs) and checks the properties.
pub fn overlap(data: &[u8]) {
    let mut i = Input::new(data);
    let a = decode_one(&mut i);
    let b = decode_one(&mut i);
    if let (Some(a), Some(b)) = (a, b)
        && check_pair(&a, &b).is_some_and(|d| d.overlap || d.apart)
    {
        reached();
    }
}

/// Encodes one volume of the layout.
pub fn encode_volume(e: Enc, kind: u8, p: Vec3, q: Vec3, s: Vec3, rot: Quat) -> Enc {
    let rot = rot.to_array();
    e.u8(kind)
        .vec3(p)
        .vec3(q)
        .vec3(s)
        .f32(rot[0])
        .f32(rot[1])
        .f32(rot[2])
        .f32(rot[3])
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, bytes: Vec<u8>| ("overlap", format!("seed-{name}"), bytes);
    let id = Quat::IDENTITY;
    let tilt = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let z45 = Quat::from_rotation_z(core::f32::consts::FRAC_PI_4);
    let y45 = Quat::from_rotation_y(core::f32::consts::FRAC_PI_4);
    let r2 = core::f32::consts::SQRT_2;
    let v = |kind, p, q, sv: Vec3, rot| (kind, p, q, sv, rot);
    let pairs = [
        // Spheres touching exactly (3-4-5).
        (
            "spheres-touching",
            v(0, Vec3::ZERO, Vec3::ZERO, Vec3::splat(2.0), id),
            v(
                0,
                Vec3::new(3.0, 4.0, 0.0),
                Vec3::ZERO,
                Vec3::splat(3.0),
                id,
            ),
        ),
        // Sphere touching a box corner.
        (
            "sphere-box-corner",
            v(
                0,
                Vec3::new(4.0, 4.0, 3.0),
                Vec3::ZERO,
                Vec3::splat(3.0),
                id,
            ),
            v(1, Vec3::ONE, Vec3::splat(2.0), Vec3::ZERO, id),
        ),
        // Cubes separated only across two edges (a cross-product axis).
        (
            "obb-edge-edge",
            v(2, Vec3::ZERO, Vec3::ZERO, Vec3::ONE, z45),
            v(
                2,
                Vec3::new(2.0 * r2 + 0.01, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::ONE,
                y45,
            ),
        ),
        // Parallel boxes (degenerate cross axes), one inside the other.
        (
            "obb-parallel-nested",
            v(
                2,
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::ZERO,
                Vec3::new(3.0, 2.0, 1.0),
                tilt,
            ),
            v(
                2,
                Vec3::new(1.5, 2.0, 3.0),
                Vec3::ZERO,
                Vec3::new(0.5, 0.25, 0.1),
                tilt,
            ),
        ),
        // Box against a tilted OBB, near contact.
        (
            "box-obb",
            v(1, Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE, Vec3::ZERO, id),
            v(
                2,
                Vec3::new(2.2, 0.3, 0.1),
                Vec3::ZERO,
                Vec3::new(1.0, 0.5, 0.5),
                tilt,
            ),
        ),
        // Parallel capsules touching side by side; a crossing pair.
        (
            "capsules-parallel",
            v(3, Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::ONE, id),
            v(
                3,
                Vec3::new(1.0, 2.0, 0.0),
                Vec3::new(9.0, 2.0, 0.0),
                Vec3::ONE,
                id,
            ),
        ),
        (
            "capsule-sphere",
            v(3, Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::ONE, id),
            v(0, Vec3::new(6.0, 0.0, 0.0), Vec3::ZERO, Vec3::ONE, id),
        ),
        // Huge and tiny scales (rescaling paths).
        (
            "spheres-huge",
            v(0, Vec3::splat(-3e38), Vec3::ZERO, Vec3::splat(3e38), id),
            v(0, Vec3::splat(3e38), Vec3::ZERO, Vec3::splat(2e38), id),
        ),
        (
            "obb-tiny",
            v(2, Vec3::splat(1e-39), Vec3::ZERO, Vec3::splat(2e-39), tilt),
            v(2, Vec3::splat(-1e-39), Vec3::ZERO, Vec3::splat(1e-40), z45),
        ),
        // Nonsense that the constructors must refuse with typed errors.
        (
            "nan-and-negative",
            v(0, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ZERO, Vec3::ONE, id),
            v(3, Vec3::ZERO, Vec3::ONE, Vec3::splat(-1.0), id),
        ),
        (
            "zero-quaternion",
            v(
                2,
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::ONE,
                Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            ),
            v(0, Vec3::ZERO, Vec3::ZERO, Vec3::ONE, id),
        ),
    ];
    for (name, x, y) in pairs {
        let e = encode_volume(Enc::new(), x.0, x.1, x.2, x.3, x.4);
        let e = encode_volume(e, y.0, y.1, y.2, y.3, y.4);
        s.push(t(name, e.done()));
    }
}

/// Regression inputs (`fuzz/regressions/overlap/`): box–OBB pairs apart beyond the band.
/// The first went undecided while the oracle converted the box with `Obb::from_aabb` (the
/// conversion the test uses); the second, a box one ulp thick at `x = 10⁶`, was reported
/// overlapping `2⁻⁴` away (`aabb_obb` converted the box in world coordinates).
pub(crate) fn regressions(s: &mut Vec<Seed>) {
    let id = Quat::IDENTITY;
    let cube = |c: Vec3| (2, c, Vec3::ZERO, Vec3::splat(0.5), id);
    let pairs = [
        (
            "box-obb-apart-3e-4",
            (1, Vec3::ZERO, Vec3::ONE, Vec3::ZERO, id),
            cube(Vec3::new(1.5003, 0.5, 0.5)),
        ),
        (
            "box-obb-thin-box-far-from-origin",
            (
                1,
                Vec3::new(1e6, 0.0, 0.0),
                Vec3::new(1e6 + 0.0625, 1.0, 1.0),
                Vec3::ZERO,
                id,
            ),
            cube(Vec3::new(1e6 - 0.5625, 0.5, 0.5)),
        ),
    ];
    for (name, x, y) in pairs {
        let e = encode_volume(Enc::new(), x.0, x.1, x.2, x.3, x.4);
        let e = encode_volume(e, y.0, y.1, y.2, y.3, y.4);
        s.push(("overlap", name.to_string(), e.done()));
    }
}
