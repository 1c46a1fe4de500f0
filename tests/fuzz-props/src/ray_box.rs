//! `ray_box`: decoding and the slab test against the exact `f64` interval.

use super::*;

/// Decodes a `ray_box` input: `flags: u8` ([`flags`]), `origin: 3×f32`, `direction: 3×f32`,
/// `t_min: f32`, `t_max: f32`, `a: 3×f32`, `b: 3×f32` (the box `[a, b]`, or
/// `[min(a, b), max(a, b)]` with [`flags::ORDERED`]); 57 bytes.
pub fn decode_ray_box(data: &[u8]) -> (Ray, Aabb) {
    let mut i = Input::new(data);
    let h = RayHeader::decode(&mut i);
    let (a, b) = (i.vec3(), i.vec3());
    let bx = if h.has(flags::ORDERED) {
        Aabb::new(a.min(b), a.max(b))
    } else {
        Aabb::new(a, b)
    };
    let direction = if h.has(flags::AIM) {
        bx.min + (bx.max - bx.min) * h.dir - h.origin
    } else {
        h.dir
    };
    (h.ray(direction), bx)
}

/// Encodes a `ray_box` input (see [`decode_ray_box`]).
pub fn encode_ray_box(fl: u8, o: Vec3, d: Vec3, t: (f32, f32), a: Vec3, b: Vec3) -> Vec<u8> {
    Enc::new().ray_header(fl, o, d, t).vec3(a).vec3(b).done()
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
///    NaN or inverted interval) gives `None`; a hit has
///    `t_min ≤ t_enter ≤ t_exit ≤ t_max`; the plain (unpadded) slab test never hits where the
///    padded one misses. NaN *box* coordinates are allowed and only need an answer, no
///    panic (the BVH never builds such boxes). **Deterministic:** a second call on copies of
///    the same ray and box gives the bit-identical answer.
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
    let (ray_again, bx_again) = (*ray, *bx);
    let again = bx_again.intersect_ray(&ray_again);
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
        opt_bits(again),
        "a second call on the same input gives {again:?}\n{}",
        ctx()
    );
    if !ray.is_valid() {
        reached();
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
        reached();
        assert!(
            got.is_some(),
            "missed a box the exact ray crosses: exact interval [{enter:e}, {exit:e}]\n{}",
            ctx()
        );
    }
    // Property 4, in the tame domain.
    // The tame domain's bounds (property 4): 2^-120 and 2^120, where the f32 slab distances
    // and their products stay clear of the subnormal range and of overflow.
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
            reached();
            assert!(
                got.is_none(),
                "hit a box the exact ray misses: exact interval [{enter:e}, {exit:e}]\n{}",
                ctx()
            );
        }
    }
}

/// A ray into the unit box that starts on its `face` plane (0 or 1) of `axis`, outside the box
/// along the next axis and heading along it, with the direction's `axis` component `zero`
/// (`±0`): origin and direction.
fn on_face_plane(axis: usize, face: f32, zero: f32) -> (Vec3, Vec3) {
    let along = (axis + 1) % 3;
    let (mut o, mut d) = (Vec3::splat(0.5), Vec3::ZERO);
    (o[axis], o[along]) = (face, -1.0);
    (d[axis], d[along]) = (zero, 1.0);
    (o, d)
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
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
                let (mut o, d) = on_face_plane(axis, face, zero);
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
