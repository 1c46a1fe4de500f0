//! Affine transforms for instancing: intersect an object placed by `M` by taking the ray to
//! object space with `M⁻¹`, and the hit back with `M`.
//!
//! * **Rays** ([`Transform::ray_to_object`]): origin and direction by `M⁻¹`; the direction is
//!   **not normalised**, so `o' + t·d' = M⁻¹(o + t·d)` for every `t`: the parameter `t` and the
//!   interval `(t_min, t_max]` are the same in both spaces, and closest-hit searches can mix
//!   hits from differently transformed objects.
//! * **Points** ([`Transform::point_to_world`]): `M·p`, each row summed pairwise
//!   `(m₀x + m₁y) + (m₂z + m₃)` so every term carries at most three roundings (pbrt's
//!   `gamma(3)` per row term).
//! * **Normals** ([`Transform::normal_to_world`]): by the inverse transpose `M⁻ᵀ`, normalised.
//!   This is the gradient rule `∇(f∘M⁻¹) = M⁻ᵀ·∇f`: correct under non-uniform scale and shear,
//!   and it keeps "outward" (`f > 0` side) outward even for mirroring transforms. (A triangle's
//!   winding-based normal `(v1 − v0) × (v2 − v0)` of the *transformed* vertices is `det(M)·M⁻ᵀn`:
//!   under a mirror it is the opposite of [`Transform::hit_to_world`]'s normal.)
//! * **Hits** ([`Transform::hit_to_world`]): point by `M` with the error bound grown as in pbrt
//!   (`Transform::operator()(Point3fi)`): for row `r`,
//!   `(1 + gamma(3))·Σ_c |m_rc|·e_c + gamma(3)·(Σ_c |m_rc·p_c| + |m_r3|)`, where `e` is the
//!   object-space bound. The world surface is by definition the image of the object surface by
//!   the stored `f32` matrix `M`, so this bounds the distance to the world surface; `t`, `uv`
//!   and `front_face` are unchanged (`(M·d)·(M⁻ᵀn) = d·n`). The bound also covers the
//!   rounding of taking a spawned origin back to object space (see
//!   [`Transform::hit_to_world`]), so spawned rays do not re-hit through the round trip.
//!
//! Only affine matrices (last row `(0, 0, 0, 1)`) are accepted; the inverse is computed in `f64`
//! and rounded once. Nothing panics: a transform that overflows produces a non-finite ray, which
//! every intersector treats as hitting nothing.

use crate::error::GeometryError;
use crate::float::{gamma, sqrt_f64, unit_direction_f64};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::tolerance::TRANSFORM_MAX_CONDITION;
use glam::{DMat3, DVec3, Mat4, Vec3, Vec4};

/// An invertible affine transform and its inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    m: Mat4,
    inv: Mat4,
}

/// Row `r` of the 3×4 affine part: `(linear row, translation)`.
#[inline]
fn row(m: &Mat4, r: usize) -> (Vec3, f32) {
    (
        Vec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]),
        m.w_axis[r],
    )
}

/// `M·(p, w)` for `w ∈ {0, 1}`, summed pairwise (at most three roundings per term).
#[inline]
fn apply(m: &Mat4, p: Vec3, w: f32) -> Vec3 {
    let mut out = Vec3::ZERO;
    for r in 0..3 {
        let (l, t) = row(m, r);
        out[r] = (l.x * p.x + l.y * p.y) + (l.z * p.z + t * w);
    }
    out
}

fn linear_f64(m: &Mat4) -> DMat3 {
    DMat3::from_cols(
        m.x_axis.truncate().as_dvec3(),
        m.y_axis.truncate().as_dvec3(),
        m.z_axis.truncate().as_dvec3(),
    )
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        m: Mat4::IDENTITY,
        inv: Mat4::IDENTITY,
    };

    /// The transform with matrix `m` (column-major, glam's convention; points are `M·(p, 1)`).
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`] for a non-finite entry;
    /// [`GeometryError::Degenerate`] for a non-affine matrix (last row not exactly
    /// `(0, 0, 0, 1)`: a projective map does not preserve `t`);
    /// [`GeometryError::SingularTransform`] when the linear part `L` is singular or its
    /// condition number `‖L‖_F·‖L⁻¹‖_F` (in `f64`) exceeds
    /// [`crate::tolerance::TRANSFORM_MAX_CONDITION`] (`2²⁰`), or when the inverse overflows
    /// `f32` (a linear part whose entries are all below about `10⁻³⁸`).
    pub fn new(m: Mat4) -> Result<Self, GeometryError> {
        if !m.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        if m.row(3) != Vec4::W {
            return Err(GeometryError::Degenerate);
        }
        let l = linear_f64(&m);
        let frobenius = |a: &DMat3| {
            libm::sqrt(
                a.x_axis.length_squared() + a.y_axis.length_squared() + a.z_axis.length_squared(),
            )
        };
        if l.determinant() == 0.0 {
            return Err(GeometryError::SingularTransform);
        }
        let li = l.inverse();
        // NaN (an inverse that overflowed `f64`) is refused too.
        if !(frobenius(&l) * frobenius(&li) <= TRANSFORM_MAX_CONDITION) {
            return Err(GeometryError::SingularTransform);
        }
        let ti: DVec3 = -(li * m.w_axis.truncate().as_dvec3());
        let inv = Mat4::from_cols(
            li.x_axis.as_vec3().extend(0.0),
            li.y_axis.as_vec3().extend(0.0),
            li.z_axis.as_vec3().extend(0.0),
            ti.as_vec3().extend(1.0),
        );
        if !inv.is_finite() {
            return Err(GeometryError::SingularTransform);
        }
        Ok(Self { m, inv })
    }

    /// Translation by `v`.
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`].
    pub fn translate(v: Vec3) -> Result<Self, GeometryError> {
        Self::new(Mat4::from_translation(v))
    }

    /// Scale by `s` per axis (negative components mirror).
    ///
    /// # Errors
    ///
    /// As [`Transform::new`]
    /// (a zero or relatively tiny component is singular).
    pub fn scale(s: Vec3) -> Result<Self, GeometryError> {
        Self::new(Mat4::from_scale(s))
    }

    /// Rotation by `angle` radians (counter-clockwise looking down `axis`) about `axis` (any
    /// non-zero length).
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`], [`GeometryError::Degenerate`]
    /// for a zero axis.
    pub fn rotate(axis: Vec3, angle: f32) -> Result<Self, GeometryError> {
        if !axis.is_finite() || !angle.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let unit = unit_direction_f64(axis)?.as_vec3();
        Self::new(Mat4::from_axis_angle(unit, angle))
    }

    /// `self` followed by `next` (matrix `next.M · self.M`, inverse recomputed in `f64`).
    ///
    /// # Errors
    ///
    /// As [`Transform::new`].
    pub fn then(&self, next: &Self) -> Result<Self, GeometryError> {
        Self::new(next.m * self.m)
    }

    /// The inverse transform.
    #[inline]
    #[must_use]
    pub fn inverse(&self) -> Self {
        Self {
            m: self.inv,
            inv: self.m,
        }
    }

    /// The matrix `M` (object → world).
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Mat4 {
        self.m
    }

    /// The matrix `M⁻¹` (world → object).
    #[inline]
    #[must_use]
    pub fn inverse_matrix(&self) -> Mat4 {
        self.inv
    }

    /// The ray in object space: `(M⁻¹o, M⁻¹d)`, direction not normalised, interval unchanged
    /// (module documentation). A non-finite result is returned as is (it fails
    /// [`Ray::validate`], so intersectors report no hit).
    #[inline]
    #[must_use]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        Ray::with_interval(
            apply(&self.inv, ray.origin, 1.0),
            apply(&self.inv, ray.direction, 0.0),
            ray.t_min,
            ray.t_max,
        )
    }

    /// `M·p`.
    #[inline]
    #[must_use]
    pub fn point_to_world(&self, p: Vec3) -> Vec3 {
        apply(&self.m, p, 1.0)
    }

    /// `M⁻¹·p`.
    #[inline]
    #[must_use]
    pub fn point_to_object(&self, p: Vec3) -> Vec3 {
        apply(&self.inv, p, 1.0)
    }

    /// `M·v` for a direction (no translation).
    #[inline]
    #[must_use]
    pub fn vector_to_world(&self, v: Vec3) -> Vec3 {
        apply(&self.m, v, 0.0)
    }

    /// `M·p` and the conservative bound on its error given the bound `p_error` on `p`
    /// (module documentation).
    #[must_use]
    pub fn point_to_world_with_error(&self, p: Vec3, p_error: Vec3) -> (Vec3, Vec3) {
        let out = self.point_to_world(p);
        let mut err = Vec3::ZERO;
        for r in 0..3 {
            let (l, t) = row(&self.m, r);
            let la = l.abs();
            err[r] = (1.0 + gamma(3)) * la.dot(p_error)
                + gamma(3) * ((l * p).abs().element_sum() + t.abs());
        }
        (out, err)
    }

    /// `M⁻ᵀ·n`, normalised (zero if `n` is zero or not finite). Evaluated in `f64` and
    /// rounded once: the product and its length stay in range for every `f32` matrix and
    /// normal, so a transform that scales by `10⁻²⁰` or `10²³`, or a normal of length `10²⁰`,
    /// gives a unit normal (within one `f32` rounding a component).
    #[must_use]
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        let li = &self.inv;
        let n = n.as_dvec3();
        let w = DVec3::new(
            li.x_axis.truncate().as_dvec3().dot(n),
            li.y_axis.truncate().as_dvec3().dot(n),
            li.z_axis.truncate().as_dvec3().dot(n),
        );
        let len = sqrt_f64(w.length_squared());
        if len > 0.0 && len.is_finite() {
            (w / len).as_vec3()
        } else {
            Vec3::ZERO
        }
    }

    /// An object-space hit in world space: point by `M` with the grown error bound, normal by
    /// `M⁻ᵀ` (normalised), `t`, `uv`, `front_face` unchanged (module documentation).
    ///
    /// **Round trip.** A ray spawned from the world hit is intersected again *in object space*,
    /// through [`Transform::ray_to_object`], whose origin `M⁻¹·o` is rounded again (by up to
    /// `gamma(3)·(|M⁻¹|·|o| + |M⁻¹ translation|)` per component: three roundings a term in the
    /// pairwise sum; large when the translation is large compared with the object). The bound
    /// is evaluated in `f32`, and its sum of magnitudes may itself round low by `γ₃`, so the
    /// code takes `e_back = gamma(4)·(…)` (`γ₃/(1 − γ₃) ≤ γ₄`). `point_error` therefore also includes
    /// `|L|·e_back` (with `L` the linear part of `M`), which is exactly enough for the world
    /// offset along `M⁻ᵀn` to map to an object-space offset along `n` that clears `e_back`
    /// (`|n_w|ᵀ|L| ≥ |Lᵀn_w| = |n|/|M⁻ᵀn|`). It stays a valid (larger) bound on the point.
    #[must_use]
    pub fn hit_to_world(&self, hit: &Hit) -> Hit {
        let (point, mut point_error) = self.point_to_world_with_error(hit.point, hit.point_error);
        let mut back = Vec3::ZERO;
        for r in 0..3 {
            let (l, t) = row(&self.inv, r);
            back[r] = gamma(4) * ((l * point).abs().element_sum() + t.abs());
        }
        for r in 0..3 {
            let (l, _) = row(&self.m, r);
            point_error[r] += (1.0 + gamma(3)) * l.abs().dot(back);
        }
        Hit {
            t: hit.t,
            point,
            point_error,
            normal: self.normal_to_world(hit.normal),
            uv: hit.uv,
            front_face: hit.front_face,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hit::spawn_ray;
    use crate::quadric::Quadric;
    use crate::sphere::Sphere;
    use crate::test_util::{lcg, special_f32, unit_vec};
    use crate::triangle::{TriangleIntersector, Watertight};

    /// A unit normal whatever the scale: through `scale(10⁻²⁰)` and `scale(10²³)` (the
    /// inverse's entries `10²⁰` and `10⁻²³`: their squares leave `f32`'s range) and for
    /// normals of length `10²⁰` and `10⁻²⁵` under the identity.
    #[test]
    fn normals_are_unit_at_every_scale() {
        for s in [1.0e-20f32, 1.0e23] {
            let t = Transform::scale(Vec3::splat(s)).unwrap();
            let n = t.normal_to_world(Vec3::new(0.0, 0.6, 0.8));
            assert!(
                (n.length() - 1.0).abs() < UNIT_NORMAL_ABS,
                "scale {s}: {n:?}"
            );
            assert!((n - Vec3::new(0.0, 0.6, 0.8)).abs().max_element() < UNIT_NORMAL_ABS);
        }
        for k in [1.0e20f32, 1.0e-25] {
            assert_eq!(
                Transform::IDENTITY.normal_to_world(Vec3::X * k),
                Vec3::X,
                "{k}"
            );
        }
        for n in [Vec3::ZERO, Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
            assert_eq!(Transform::IDENTITY.normal_to_world(n), Vec3::ZERO, "{n:?}");
        }
    }

    /// `M·M⁻¹` against the identity, per entry (absolute; unitless in the linear block,
    /// world units in the translation column): the inverse is computed in `f64` and rounded
    /// once (module docs), so each entry of the `f32` product is a 4-term dot product of
    /// once-rounded values, a few unit roundoffs (`6e-8`) of its terms (at most a few units in
    /// the linear block); `1e-5` is well above that, yet a wrong inverse entry fails it. On
    /// the test matrix the product is exactly the identity.
    const INVERSE_ENTRY_ABS: f32 = 1.0e-5;

    /// A point taken to the world and back, distance from where it started (world units):
    /// the world point, near the translation `(1e3, −20, 5)`, is rounded to `f32` (half an
    /// ulp there is `3.1e-5`) and the map back adds a rounding or two of that size; `1e-4` is
    /// about three of them (measured: `4.6e-5`).
    const ROUND_TRIP_ABS: f32 = 1.0e-4;

    /// Distance allowed between two `f32` evaluations of the same world point (world
    /// units): the tests' coordinates reach `|x| ≈ 1e3`, where one ulp is `6.1e-5`, and each
    /// evaluation takes a few roundings there; `1e-3` is 16 of those ulps.
    const WORLD_POINT_ABS: f32 = 1.0e-3;

    /// Distance between the transformed `f32` normal and the analytic `f64` one (unit
    /// vectors, so radians for small angles): `M⁻ᵀ` in `f32` (entries rounded once), a
    /// dot product and a normalisation, amplified by the anisotropy of `L` (`κ ≈ 8`): a few
    /// `1e-7`.
    const NORMAL_ANGLE: f64 = 1.0e-6;

    /// Barycentrics of one hit found in world and in object space (unitless): the world
    /// vertices and the object-space ray are each rounded once at `|x| ≈ 100` (ulp
    /// `7.6e-6`) on edges of ~2, so the two triangles differ by a few `1e-6` of their size;
    /// checked only for rays not grazing the plane (`|cos| > 0.2`).
    const BARYCENTRIC_AGREEMENT: f32 = 1.0e-4;

    /// The geometric normals of one hit from the world triangle and from the object
    /// triangle transformed (unit vectors): world vertices rounded at `|v| ≈ 100` (ulp
    /// `7.6e-6`) on edges of ~2 turn the normal by a few `1e-6`.
    const NORMAL_AGREEMENT: f32 = 2.0e-5;

    /// `| |n| − 1 |` of a world normal for rays of arbitrary (special-value) parameters: a
    /// normalisation in `f32` is good to a few unit roundoffs; this loose bound only tells
    /// a normalised vector from an unnormalised or collapsed one.
    const UNIT_LENGTH_ABS: f32 = 1.0e-3;

    /// An `f64` unit vector rounded to `f32` against the unit vector expected (per component,
    /// and its length against 1; unitless): each component is rounded once, within half an
    /// ulp of a value ≤ 1 (`2⁻²⁴`), so the length is within `3·2⁻²⁴`; `4ε = 2⁻²⁰` leaves a
    /// margin and still fails a normal off by one `f32` rounding step of the inverse.
    const UNIT_NORMAL_ABS: f32 = 4.0 * f32::EPSILON;

    /// One hit's `t` found in world and in object space, compared as a distance along the
    /// normal (the well-conditioned quantity), in ulps of the world coordinates (`ε·|x|`):
    /// the `f32` ray and the world vertices are known only to a rounding or two of `|x|`,
    /// the object-space ray adds three roundings a component (`apply`), and each side's
    /// intersection its own few; 16 covers the sum with a margin.
    const ALONG_NORMAL_ULPS: f64 = 16.0;

    /// Smallest `t` of the far side for an inward ray spawned from an ellipsoid hit (ray
    /// parameter; the direction is the unit world normal): a self-hit would lie within the
    /// spawn offset (`point_error`, about `1e-4` at `|x| ≈ 1e3`), the far side a chord of
    /// the ellipsoid away, of the order of its smallest semi-axis (`0.5` before the shear).
    const FAR_SIDE_T_MIN: f32 = 0.1;

    /// Rays of the ellipsoid test that must hit, of 5 000: each aims at a point inside it
    /// (`0.95` of the unit sphere, transformed), so all hit unless the transform is wrong.
    const ELLIPSOID_MIN_HITS: usize = 4_900;

    /// Rays of the triangle test that must be checked, of 2 000: the barycentric filter keeps
    /// the area `(0.96)²/2 ≈ 0.46` of the unit square, about 920 expected; 800 is a floor
    /// that only a broken generator or a missed hit falls below.
    const TRIANGLE_MIN_CHECKED: usize = 800;

    /// Translate · shear · non-uniform scale.
    fn sheared_ellipsoid_transform() -> Transform {
        let scale = Transform::scale(Vec3::new(2.0, 0.5, 3.0)).unwrap();
        let shear = Transform::new(Mat4::from_cols(
            Vec4::new(1.0, 0.0, -0.4, 0.0),
            Vec4::new(0.7, 1.0, 0.0, 0.0),
            Vec4::new(0.0, 0.3, 1.0, 0.0),
            Vec4::W,
        ))
        .unwrap();
        let tr = Transform::translate(Vec3::new(1.0e3, -20.0, 5.0)).unwrap();
        scale.then(&shear).unwrap().then(&tr).unwrap()
    }

    #[test]
    fn constructor_validation() {
        assert_eq!(
            Transform::scale(Vec3::new(1.0, 0.0, 1.0)),
            Err(GeometryError::SingularTransform)
        );
        assert_eq!(
            Transform::scale(Vec3::new(1.0, 1.0, 1.0e-7)),
            Err(GeometryError::SingularTransform)
        );
        assert!(
            Transform::scale(Vec3::new(1.0, 1.0, 1.0e-4)).is_ok(),
            "a flattened sphere: axis ratio 10⁻⁴"
        );
        // A rod: condition number 2 000 (two small axes; refused by a scaled determinant).
        assert!(Transform::scale(Vec3::new(1.0, 5.0e-4, 5.0e-4)).is_ok());
        // The bound by hand: a scale (1, 1, a) has ‖L‖_F = √(2 + a²), ‖L⁻¹‖_F = √(2 + 1/a²),
        // so κ_F = 2²⁰ at a ≈ 1.3487e-6 (from κ_F² = (2 + a²)(2 + a⁻²) = 2⁴⁰). Just above and
        // below that axis ratio (1 % each way).
        assert!(Transform::scale(Vec3::new(1.0, 1.0, 1.3621e-6)).is_ok());
        assert_eq!(
            Transform::scale(Vec3::new(1.0, 1.0, 1.3352e-6)),
            Err(GeometryError::SingularTransform)
        );
        assert!(
            Transform::scale(Vec3::splat(1.0e-20)).is_ok(),
            "uniform scale is fine"
        );
        assert_eq!(
            Transform::translate(Vec3::new(f32::NAN, 0.0, 0.0)),
            Err(GeometryError::NonFinite)
        );
        let mut proj = Mat4::IDENTITY;
        proj.x_axis.w = 0.5;
        assert_eq!(Transform::new(proj), Err(GeometryError::Degenerate));
        assert_eq!(
            Transform::rotate(Vec3::ZERO, 1.0),
            Err(GeometryError::Degenerate)
        );
        assert_eq!(
            Transform::rotate(Vec3::X, f32::INFINITY),
            Err(GeometryError::NonFinite)
        );
        // A rank-2 matrix with a rounding-level third direction.
        let m = Mat4::from_cols(
            Vec4::new(1.0, 2.0, 3.0, 0.0),
            Vec4::new(2.0, 4.0, 6.0 + 1.0e-6, 0.0),
            Vec4::new(0.0, 0.0, 1.0, 0.0),
            Vec4::W,
        );
        assert_eq!(Transform::new(m), Err(GeometryError::SingularTransform));
        // The inverse is an inverse.
        let t = sheared_ellipsoid_transform();
        let prod = t.matrix() * t.inverse_matrix();
        assert!(
            prod.abs_diff_eq(Mat4::IDENTITY, INVERSE_ENTRY_ABS),
            "{prod:?}"
        );
        let p = Vec3::new(0.3, -0.7, 0.2);
        assert!((t.point_to_object(t.point_to_world(p)) - p).length() < ROUND_TRIP_ABS);
        assert_eq!(t.inverse().inverse(), t);
    }

    #[test]
    fn ray_to_object_keeps_t_and_interval() {
        let t = sheared_ellipsoid_transform();
        let ray = Ray::with_interval(
            Vec3::new(990.0, -25.0, 1.0),
            Vec3::new(3.0, 2.0, 1.0),
            0.25,
            7.5,
        );
        let r = t.ray_to_object(&ray);
        assert_eq!((r.t_min, r.t_max), (0.25, 7.5));
        for s in [0.0f32, 0.5, 2.0, 7.5] {
            let w = t.point_to_world(r.at(s));
            assert!(
                (w - ray.at(s)).length() <= WORLD_POINT_ABS,
                "{s}: {w} vs {}",
                ray.at(s)
            );
        }
        assert_eq!(Transform::IDENTITY.ray_to_object(&ray), ray);
        let mut bad = ray;
        bad.origin.y = f32::NAN;
        assert!(!t.ray_to_object(&bad).is_valid());
    }

    #[test]
    fn sheared_sphere_normal_matches_the_analytic_ellipsoid() {
        // World ellipsoid = M(unit sphere): f(x) = |L⁻¹(x − T)|² − 1, ∇f ∝ L⁻ᵀL⁻¹(x − T),
        // with L⁻¹ the exact (f64) inverse of the stored f32 matrix.
        let tf = sheared_ellipsoid_transform();
        let sphere = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let l = linear_f64(&tf.matrix());
        let li = l.inverse();
        let a = li.transpose() * li;
        let center = tf.matrix().w_axis.truncate().as_dvec3();
        let world = Quadric::from_center_form(a, center, -1.0).unwrap();
        let mut st = 9u64;
        let (mut worst_angle, mut worst_t, mut hits) = (0.0f64, 0.0f64, 0);
        for _ in 0..5000 {
            let target = tf.point_to_world(unit_vec(&mut st) * 0.95);
            let o = target + unit_vec(&mut st) * 10.0;
            let ray = Ray::new(o, target - o);
            let Some(h) = sphere.intersect(&tf.ray_to_object(&ray)) else {
                continue;
            };
            hits += 1;
            let hw = tf.hit_to_world(&h);
            let x = hw.point.as_dvec3();
            // The analytic normal at the exact image (f64) of the object-space hit point, so
            // that the rounding of the world point (ulps of |x| ≈ 1e3, times the curvature)
            // does not mask the normal transform's own error.
            let x_exact = l * h.point.as_dvec3() + center;
            let analytic = world.gradient(x_exact).normalize();
            let angle = (hw.normal.as_dvec3() - analytic).length();
            worst_angle = worst_angle.max(angle);
            assert!(angle <= NORMAL_ANGLE, "normal off by {angle}");
            // Same t in both spaces: the object-space root is the world-space root.
            let (t0, _) = world.roots(&ray).unwrap();
            // Compared as a distance along the normal (the well-conditioned quantity) in ulps
            // of the world coordinates (|x| ≈ 1e3): the f32 ray itself is known to that.
            let cos = (ray.direction.normalize().dot(hw.normal)).abs() as f64;
            let along_n = (h.t as f64 - t0).abs() * ray.direction.length() as f64 * cos;
            let ulps = along_n / (f32::EPSILON as f64 * x.abs().max_element());
            worst_t = worst_t.max(ulps);
            assert!(ulps <= ALONG_NORMAL_ULPS, "t {} vs {t0}: {ulps} ulps", h.t);
            // The world point is within its bound of the world surface.
            let dist = world.eval(x).abs() / world.gradient(x).length();
            let along = hw.point_error.as_dvec3().dot(hw.normal.abs().as_dvec3());
            assert!(dist <= along, "dist {dist} > bound {along}");
            assert_eq!(hw.front_face, ray.direction.dot(hw.normal) < 0.0);
            // Spawned rays, taken back to object space: outward misses, inward hits far side.
            let out = spawn_ray(&hw, hw.normal);
            assert!(sphere.intersect(&tf.ray_to_object(&out)).is_none());
            let inward = spawn_ray(&hw, -hw.normal);
            let far = sphere.intersect(&tf.ray_to_object(&inward)).unwrap();
            assert!(far.t > FAR_SIDE_T_MIN, "{}", far.t);
        }
        assert!(hits >= ELLIPSOID_MIN_HITS, "{hits}");
        std::eprintln!(
            "sheared ellipsoid: worst normal error {worst_angle:e}, worst t error along n {worst_t:.2} ulps of |x|"
        );
    }

    #[test]
    fn rotated_translated_triangle_matches_transformed_vertices() {
        let tf = Transform::rotate(Vec3::new(1.0, 2.0, 3.0), 0.7)
            .unwrap()
            .then(&Transform::translate(Vec3::new(100.0, -50.0, 20.0)).unwrap())
            .unwrap();
        let obj = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.5, 0.0),
            Vec3::new(0.3, 1.5, 0.4),
        ];
        let world = obj.map(|v| tf.point_to_world(v));
        let mut st = 4u64;
        let mut n = 0;
        for _ in 0..2000 {
            let (b1, b2) = (lcg(&mut st), lcg(&mut st));
            if b1 + b2 > 0.98 || b1 < 0.01 || b2 < 0.01 {
                continue;
            }
            let target = world[0] * (1.0 - b1 - b2) + world[1] * b1 + world[2] * b2;
            let o = target + unit_vec(&mut st) * 5.0;
            let ray = Ray::new(o, target - o);
            let hw = Watertight.intersect(&ray, &world).expect("world hit");
            let ho = Watertight
                .intersect(&tf.ray_to_object(&ray), &obj)
                .expect("object hit");
            n += 1;
            // t agrees as a distance along the normal, within ulps of the coordinates (the
            // world vertices and the object-space ray are each rounded once at |x| ≈ 100).
            let nrm = (world[1] - world[0]).cross(world[2] - world[0]).normalize();
            let along_n = (hw.t - ho.t).abs() * ray.direction.dot(nrm).abs();
            assert!(
                f64::from(along_n) <= ALONG_NORMAL_ULPS * f64::from(f32::EPSILON) * 120.0,
                "{} vs {}",
                hw.t,
                ho.t
            );
            if ray.direction.normalize().dot(nrm).abs() > 0.2 {
                assert!(
                    (hw.b1 - ho.b1).abs() <= BARYCENTRIC_AGREEMENT
                        && (hw.b2 - ho.b2).abs() <= BARYCENTRIC_AGREEMENT
                );
            }
            assert_eq!(hw.front_face, ho.front_face);
            let pw = hw.to_hit(&world);
            let po = tf.hit_to_world(&ho.to_hit(&obj));
            assert!((pw.point - po.point).length() <= WORLD_POINT_ABS);
            assert!(
                (pw.normal - po.normal).length() <= NORMAL_AGREEMENT,
                "{} vs {}",
                pw.normal,
                po.normal
            );
            assert_eq!(pw.front_face, po.front_face);
        }
        assert!(n >= TRIANGLE_MIN_CHECKED, "{n}");
    }

    #[test]
    fn mirror_keeps_gradient_normals_outward() {
        let tf = Transform::scale(Vec3::new(-1.0, 2.0, 1.0)).unwrap();
        let sphere = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X);
        let h = tf.hit_to_world(&sphere.intersect(&tf.ray_to_object(&ray)).unwrap());
        assert_eq!(h.point, Vec3::new(-1.0, 0.0, 0.0));
        assert_eq!(h.normal, Vec3::new(-1.0, 0.0, 0.0));
        assert!(h.front_face);
        assert_eq!(h.t, 4.0);
    }

    #[test]
    fn random_bit_pattern_rays_never_panic() {
        // NaN, ±inf, subnormals, huge and tiny values in every field, against every primitive
        // of this crate's non-triangle intersectors: no panic, and every reported hit is
        // finite with t in the interval.
        use crate::plane::Plane;
        use crate::polygon::Polygon;
        use crate::quadric::Ellipsoid;
        let tf = sheared_ellipsoid_transform();
        let plane = Plane::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.2, -0.3, 1.0)).unwrap();
        let sphere = Sphere::new(Vec3::new(0.5, 0.0, -1.0), 2.0).unwrap();
        let ell = Ellipsoid::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.5)).unwrap();
        let cone = Quadric::cone(Vec3::ZERO, Vec3::Z, 0.5).unwrap();
        let poly = Polygon::<8>::new(&[
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ])
        .unwrap();
        let mut st = 99u64;
        let pick = |st: &mut u64| -> f32 {
            let r = lcg(st);
            if r < 0.3 {
                special_f32(st)
            } else if r < 0.5 {
                f32::from_bits((lcg(st) * 4.0e9) as u32)
            } else {
                (lcg(st) - 0.5) * 8.0
            }
        };
        let check = |ray: &Ray, h: Option<Hit>| {
            if let Some(h) = h {
                assert!(ray.contains(h.t), "{ray:?} {h:?}");
                assert!(h.point.is_finite() && h.point_error.is_finite() && h.normal.is_finite());
            }
        };
        for _ in 0..50_000 {
            let ray = Ray::with_interval(
                Vec3::new(pick(&mut st), pick(&mut st), pick(&mut st)),
                Vec3::new(pick(&mut st), pick(&mut st), pick(&mut st)),
                if lcg(&mut st) < 0.8 {
                    0.0
                } else {
                    pick(&mut st)
                },
                if lcg(&mut st) < 0.8 {
                    f32::INFINITY
                } else {
                    pick(&mut st)
                },
            );
            check(&ray, plane.intersect(&ray));
            check(&ray, sphere.intersect(&ray));
            check(&ray, sphere.intersect_naive(&ray));
            check(&ray, ell.intersect(&ray));
            check(&ray, cone.intersect(&ray));
            check(&ray, poly.intersect(&ray));
            let obj = tf.ray_to_object(&ray);
            if let Some(h) = sphere.intersect(&obj) {
                // The world hit of an object-space hit: a finite unit normal, and the same
                // side of the surface as the object-space normal says (`front_face` kept).
                let w = tf.hit_to_world(&h);
                assert!(w.normal.is_finite() && w.point.is_finite(), "{w:?}");
                assert!((w.normal.length() - 1.0).abs() < UNIT_LENGTH_ABS, "{w:?}");
                assert_eq!(w.front_face, h.front_face);
            }
        }
    }
}
