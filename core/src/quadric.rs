//! General quadrics `f(x) = xᵀAx + 2bᵀx + c = 0`, solved in `f64`, and axis-aligned ellipsoids.
//!
//! **Representation.** A quadric is stored in *centred form* around a reference point `x_c`:
//! `f(x) = yᵀAy + 2b_cᵀy + k`, `y = x − x_c`, with `b_c = A·x_c + b` and `k = f(x_c)`. This is
//! an identity for *any* `x_c`; choosing `x_c` at the quadric's centre (`A·x_c = −b`, so
//! `b_c = 0`) removes the cancellation of `xᵀAx + 2bᵀx + c` for points far from the world origin
//! but near the quadric. The ellipsoid, cylinder and cone constructors set the centre (or an axis
//! point, or the apex) exactly; [`Quadric::new`] computes `−A⁻¹b` when `A` is well conditioned
//! ([`crate::tolerance::QUADRIC_CENTER_MIN_REL_DET`]) and uses the world origin otherwise;
//! [`Quadric::recentered`] moves the reference point anywhere (e.g. a paraboloid's vertex).
//!
//! **Axial form** (cylinders and cones). `A = I − (1 + τ²)·ŵŵᵀ` (`τ = 0` for a cylinder) is
//! singular along the axis, but a matrix built from a rounded unit vector `ŵ` is not: along an
//! `f32` axis `w` that is not a coordinate axis its `dᵀAd` is near `±10⁻¹⁶·|d|²`, not `0`,
//! which would give a ray along the axis two roots near `±10⁸` and a ray `10⁻⁷` rad off the
//! axis a `t` off by `0.3 %`. [`Quadric::cylinder`] and [`Quadric::cone`] therefore keep the
//! axis `w` exactly as given (its `f32` components, exact in `f64`) and the ray polynomial
//! evaluates `uᵀAv = ((u × w)·(v × w) − τ²(u·w)(v·w)) / |w|²` (Lagrange's identity): for an `f32`
//! direction `d` each component of `d × w` is a difference of two exact `f64` products,
//! rounded once, so `qa = (|d × w|² − τ²(d·w)²)/|w|²` carries a few roundings *relative to
//! itself* — at any angle between `d` and the axis — and is exactly `0` (with `qb`) for a
//! cylinder and any `d` parallel to `w` (`d = λw`: both products of each component are the
//! same real number). The surface these quadrics solve is therefore the one of the `f32` axis
//! as given ([`Quadric::axial_form`]). [`Quadric::matrix`] is `A` rounded to `f64` (each entry
//! within `12·2⁻⁵³·(δ_ij + (1 + τ²)|ŵ_i ŵ_j|)` of the exact one), and [`Quadric::eval`],
//! [`Quadric::gradient`] and the hit's Newton step, normal and `point_error` use it: a hit's
//! point is bounded against that matrix's surface, within `12·2⁻⁵³·(2 + τ²)·|y|²/|∇f|` (first
//! order, `y` from the axis point or apex) of the axial one — a few `2⁻⁵³` of the radius for a
//! hit as far from the axis point as the radius.
//!
//! **Solve** (the cancellation-free quadratic formula), all in `f64` from the `f32` ray: with `f₀ = o − x_c`,
//! `qa = dᵀAd`, `qb = dᵀ(Af₀ + b_c)`, `qc = f(o)`, the ray gives `qa·t² + 2qb·t + qc = 0`.
//! 1. The origin is shifted along the ray to `o' = o + t_c·d`, `t_c = −qb/qa` (the point of the
//!    line closest to the centre in the metric of `A`), and the discriminant is evaluated there
//!    as `Δ = qb² − qa·qc = −qa·f(o')`: no cancellation between `qb²` and `qa·qc`. When `o'` is
//!    far from `o` (a direction nearly along the surface, small `qa`), `f(o')` cancels instead;
//!    the form with the smaller rounding bound (`|qa|·|f|(o')` against `qb² + |qa·qc|`) is used.
//! 2. The stable root pair `q = −(qb + sign(qb)·√Δ)`, roots `qc/q` and `q/qa`.
//! 3. `qa = 0` (a direction along which the quadric is flat: a cylinder's axis, a paraboloid's
//!    axis, a cone's generator) leaves the linear equation: one root `−qc/(2qb)`, reported twice;
//!    `qa = qb = 0` is a ray that never crosses the surface (or lies in it): no root. `qa` is
//!    compared with `0` exactly: it is `0` where the quadric is flat along `d` exactly (for
//!    cylinders and cones, along the `f32` axis or generator as given: *axial form* above),
//!    and a general quadric's `A` is taken as given (a matrix flat along `d` only up to its
//!    own rounding is not flat, and its far root is the root of that matrix).
//!
//! **Hits.** The root nearest in `(t_min, t_max]` (comparing the `f32`-rounded roots with the
//! interval). The point `o + t·d` is computed in `f64`, moved by one Newton step along the
//! gradient onto the surface, and rounded to `f32`; `point_error` (all components) is
//! `gamma(1)·|p_i|` for that rounding plus `QUADRIC_DISTANCE_SLACK·(|f(x)| + γ₁₀·F(x))/|∇f(x)|`,
//! a bound on the distance of the `f64` point to the surface (`F` = `f` with absolute values,
//! `γ₁₀` the `f64` gamma covering its evaluation). The normal is `∇f = 2(A·y + b_c)`
//! normalised: it points to where `f > 0` (outward for the ellipsoid, cylinder and cone
//! constructors). At a singular point (`∇f = 0`, a cone's apex) the normal is `−d/|d|` and the
//! distance bound uses `√(|f|/‖A‖)`. `uv = (0, 0)` for general quadrics (no natural
//! parameterisation); [`Ellipsoid`] hits carry spherical `uv`.
//!
//! Every function is total: invalid rays, NaN and infinity give `None`, never a panic.

use crate::aabb::Aabb;
use crate::error::GeometryError;
use crate::float::{gamma, gamma_f64, unit_direction_f64};
use crate::getters::getters;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::sphere::seam_wrapped;
use crate::tolerance::{QUADRIC_CENTER_MIN_REL_DET, QUADRIC_DISTANCE_SLACK};
use core::f64::consts::{PI, TAU};
use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};

/// A quadric surface `f(x) = 0` in centred form (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    a: DMat3,
    center: DVec3,
    bc: DVec3,
    k: f64,
    /// The axis of a cylinder or cone, from which the ray polynomial's `uᵀAv` is evaluated
    /// (module documentation, *axial form*); `None` for the general form.
    axial: Option<Axial>,
}

/// `A = I − (1 + τ²)·wwᵀ/|w|²` kept as its axis (module documentation, *axial form*).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Axial {
    /// The constructor's axis direction, any non-zero length (`f32`: exact in `f64`).
    w: Vec3,
    /// `τ²` (`0` for a cylinder), exact: the square of an `f32` in `f64`.
    tau2: f64,
}

impl Axial {
    /// `uᵀAv = ((u × w)·(v × w) − τ²(u·w)(v·w)) / |w|²`.
    fn form(&self, u: DVec3, v: DVec3) -> f64 {
        let w = self.w.as_dvec3();
        (u.cross(w).dot(v.cross(w)) - self.tau2 * u.dot(w) * v.dot(w)) / w.length_squared()
    }

    /// [`Axial::form`] with every product replaced by its absolute value: the scale of its
    /// rounding.
    fn form_abs(&self, u: DVec3, v: DVec3) -> f64 {
        let (u, v, w) = (u.abs(), v.abs(), self.w.as_dvec3().abs());
        // |u × w| with absolute values: each component `|u_i w_j| + |u_j w_i|`.
        let cross_abs = |a: DVec3| {
            DVec3::new(
                a.y * w.z + a.z * w.y,
                a.z * w.x + a.x * w.z,
                a.x * w.y + a.y * w.x,
            )
        };
        (cross_abs(u).dot(cross_abs(v)) + self.tau2 * u.dot(w) * v.dot(w)) / w.length_squared()
    }
}

fn mat_is_finite(m: &DMat3) -> bool {
    m.x_axis.is_finite() && m.y_axis.is_finite() && m.z_axis.is_finite()
}

fn frobenius(m: &DMat3) -> f64 {
    libm::sqrt(m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared())
}

fn abs_mat(m: &DMat3) -> DMat3 {
    DMat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

fn symmetrize(m: DMat3) -> DMat3 {
    (m + m.transpose()) * 0.5
}

fn outer(v: DVec3) -> DMat3 {
    DMat3::from_cols(v * v.x, v * v.y, v * v.z)
}

impl Quadric {
    /// The quadric `xᵀAx + 2bᵀx + c = 0`. `A` is symmetrised (`(A + Aᵀ)/2`: only the symmetric
    /// part enters `xᵀAx`, and the gradient formula needs it).
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`] for a non-finite entry, or when the form centred at the
    /// quadric's centre overflows `f64` (finite entries whose centre or constant `k` lies
    /// beyond `f64`'s range, such as `A = I`, `b = (10²⁰⁰, 0, 0)`: `k = −10⁴⁰⁰`; every root
    /// of such a quadric would overflow too); [`GeometryError::Degenerate`] when `A = 0` and
    /// `b = 0` (`f` is constant).
    pub fn new(a: DMat3, b: DVec3, c: f64) -> Result<Self, GeometryError> {
        if !mat_is_finite(&a) || !b.is_finite() || !c.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let a = symmetrize(a);
        if a == DMat3::ZERO && b == DVec3::ZERO {
            return Err(GeometryError::Degenerate);
        }
        let fro = frobenius(&a);
        let det = a.determinant();
        let mut center = DVec3::ZERO;
        if fro > 0.0 && det.abs() >= QUADRIC_CENTER_MIN_REL_DET * fro * fro * fro {
            let xc = -(a.inverse() * b);
            if xc.is_finite() {
                center = xc;
            }
        }
        let bc = a * center + b;
        let k = center.dot(a * center + b * 2.0) + c;
        if !bc.is_finite() || !k.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        Ok(Self {
            a,
            center,
            bc,
            k,
            axial: None,
        })
    }

    /// The quadric `x̄ᵀQx̄ = 0` with `x̄ = (x, 1)`: `A` is the upper-left 3×3 block, `b` the
    /// average of the last column and the last row (so a non-symmetric `Q` is symmetrised),
    /// `c = Q₃₃`.
    ///
    /// # Errors
    ///
    /// As [`Quadric::new`].
    pub fn from_mat4(q: DMat4) -> Result<Self, GeometryError> {
        let a = DMat3::from_cols(
            q.x_axis.truncate(),
            q.y_axis.truncate(),
            q.z_axis.truncate(),
        );
        let b = (q.w_axis.truncate() + q.row(3).truncate()) * 0.5;
        Self::new(a, b, q.w_axis.w)
    }

    /// The quadric `(x − center)ᵀA(x − center) + k = 0`, exactly (no centre computation).
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`], or [`GeometryError::Degenerate`] for `A = 0`.
    pub fn from_center_form(a: DMat3, center: DVec3, k: f64) -> Result<Self, GeometryError> {
        if !mat_is_finite(&a) || !center.is_finite() || !k.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let a = symmetrize(a);
        if a == DMat3::ZERO {
            return Err(GeometryError::Degenerate);
        }
        Ok(Self {
            a,
            center,
            bc: DVec3::ZERO,
            k,
            axial: None,
        })
    }

    /// The axis-aligned ellipsoid `Σ ((x_i − center_i)/radii_i)² − 1 = 0` (see [`Ellipsoid`]).
    ///
    /// # Errors
    ///
    /// As [`Ellipsoid::new`]: [`GeometryError::NonFinite`], [`GeometryError::Degenerate`] for a
    /// radius `≤ 0`.
    pub fn ellipsoid(center: Vec3, radii: Vec3) -> Result<Self, GeometryError> {
        Ellipsoid::new(center, radii).map(|e| e.quadric)
    }

    /// The infinite circular cylinder of `radius` around the line through `axis_point` with
    /// direction `axis_dir` (any non-zero length): `|y|² − (y·â)² − r² = 0`, `y = x − axis_point`.
    /// `f > 0` outside. Its roots are those of this exact `axis_dir` (module documentation,
    /// *axial form*): a ray along it has none.
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`]; [`GeometryError::Degenerate`] for a zero axis or
    /// `radius ≤ 0`.
    pub fn cylinder(axis_point: Vec3, axis_dir: Vec3, radius: f32) -> Result<Self, GeometryError> {
        if !axis_point.is_finite() || !axis_dir.is_finite() || !radius.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let u = unit_direction_f64(axis_dir)?;
        if !(radius > 0.0) {
            return Err(GeometryError::Degenerate);
        }
        let r = radius as f64;
        let q =
            Self::from_center_form(DMat3::IDENTITY - outer(u), axis_point.as_dvec3(), -(r * r))?;
        Ok(q.with_axis(axis_dir, 0.0))
    }

    /// The infinite double cone with apex `apex`, axis direction `axis_dir` (any non-zero
    /// length) and half-angle `atan(tan_half_angle)`: `|y|² − (1 + τ²)(y·â)² = 0`,
    /// `y = x − apex` (both nappes). `f > 0` outside. Its roots are those of this exact
    /// `axis_dir` (module documentation, *axial form*).
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`]; [`GeometryError::Degenerate`] for a zero axis or
    /// `tan_half_angle ≤ 0`.
    pub fn cone(apex: Vec3, axis_dir: Vec3, tan_half_angle: f32) -> Result<Self, GeometryError> {
        if !apex.is_finite() || !axis_dir.is_finite() || !tan_half_angle.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let u = unit_direction_f64(axis_dir)?;
        if !(tan_half_angle > 0.0) {
            return Err(GeometryError::Degenerate);
        }
        let tau = tan_half_angle as f64;
        let q = Self::from_center_form(
            DMat3::IDENTITY - outer(u) * (1.0 + tau * tau),
            apex.as_dvec3(),
            0.0,
        )?;
        Ok(q.with_axis(axis_dir, tau * tau))
    }

    fn with_axis(self, w: Vec3, tau2: f64) -> Self {
        Self {
            axial: Some(Axial { w, tau2 }),
            ..self
        }
    }

    /// For a quadric built by [`Quadric::cylinder`] or [`Quadric::cone`]: the axis direction
    /// as given and `τ²` (`0` for a cylinder), from which [`Quadric::roots`] evaluates the
    /// ray polynomial (module documentation, *axial form*); `None` for the general form.
    #[inline]
    #[must_use]
    pub fn axial_form(&self) -> Option<(Vec3, f64)> {
        self.axial.map(|ax| (ax.w, ax.tau2))
    }

    /// The same quadric with reference point `p` (exact identity up to the rounding of the new
    /// `b_c = A(p − x_c) + b_c` and `k = f(p)`). Choose `p` near the surface's region of
    /// interest when `A` is singular. The result is in the general form, even for a cylinder
    /// or cone: its ray polynomial comes from the rounded `A` ([`Quadric::axial_form`] is
    /// `None`), so a ray along the axis may get the far roots of that matrix.
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`].
    pub fn recentered(&self, p: DVec3) -> Result<Self, GeometryError> {
        if !p.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        let bc = self.a * (p - self.center) + self.bc;
        let k = self.eval(p);
        if !bc.is_finite() || !k.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        Ok(Self {
            a: self.a,
            center: p,
            bc,
            k,
            axial: None,
        })
    }

    /// The symmetric matrix `A` (for a cylinder or cone, rounded from the axis: module
    /// documentation, *axial form*).
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> DMat3 {
        self.a
    }

    /// The reference point `x_c` of the centred form.
    #[inline]
    #[must_use]
    pub fn reference_point(&self) -> DVec3 {
        self.center
    }

    /// `f(x)`, evaluated in the centred form.
    #[inline]
    #[must_use]
    pub fn eval(&self, x: DVec3) -> f64 {
        let y = x - self.center;
        y.dot(self.a * y + self.bc * 2.0) + self.k
    }

    /// `F(x)`: `f(x)` with every term replaced by its absolute value; `|fl(f(x)) − f(x)|` is at
    /// most `gamma_f64(10)·F(x)` (subtraction, 3×3 product, additions, dot product).
    #[inline]
    #[must_use]
    pub fn eval_abs(&self, x: DVec3) -> f64 {
        let y = (x - self.center).abs();
        y.dot(abs_mat(&self.a) * y + self.bc.abs() * 2.0) + self.k.abs()
    }

    /// The gradient `∇f(x) = 2(A·y + b_c)`.
    #[inline]
    #[must_use]
    pub fn gradient(&self, x: DVec3) -> DVec3 {
        (self.a * (x - self.center) + self.bc) * 2.0
    }

    /// Both roots `t0 ≤ t1` of `f(o + t·d) = 0` in `f64` (not clipped to the ray's interval;
    /// a double or single root is reported twice). `None` for no real root, a ray along which
    /// `f` is constant or linear with zero slope, an invalid ray, or overflow.
    ///
    /// **Domain of the residual bound.** Each root satisfies `|f(o + t·d)|` within
    /// `64·2⁻⁵³·(|q_a|t² + 2|q_b||t| + |q_c| + F(o + t·d))` (absolute-value scales of the ray
    /// polynomial `q_a t² + 2 q_b t + q_c`, plus the first-order effect of `q_c`'s rounding)
    /// while the discriminant's scale `max(q_b², |q_a|·|q_c|)` is at least `10⁻²⁹⁰`; below it
    /// the `f64` terms are near the subnormal range and round absolutely, and only
    /// `t0 ≤ t1` is promised. Against the exact roots: for a clearly quadratic polynomial
    /// (`|q_a|` above `64·2⁻⁵³` of its scale) with scales in `[10⁻¹⁵⁰, 10¹⁵⁰]`, a root exists
    /// exactly when the exact discriminant is outside the band `|Δ| ≤ 256·2⁻⁵³·S`, and where
    /// `Δ > 2⁻³⁰·S` each root is within `10⁻⁶` of its scale plus its first-order rounding
    /// bound of the exact one. For a cylinder or cone, the polynomial, its scales and `F` are
    /// those of the axial form (`|d × w|` with absolute values for `|q_a|`; module
    /// documentation), whose exact roots are those of the `f32` axis as given.
    /// The fuzz property `ray_quadric` checks exactly these domains.
    #[must_use]
    pub fn roots(&self, ray: &Ray) -> Option<(f64, f64)> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.direction.as_dvec3();
        let f0 = ray.origin.as_dvec3() - self.center;
        let [qa, qb, qc] = self.ray_polynomial(ray);
        if !(qa.is_finite() && qb.is_finite() && qc.is_finite()) {
            return None;
        }
        let (t0, t1) = if qa == 0.0 {
            if qb == 0.0 {
                return None;
            }
            let t = -qc / (2.0 * qb);
            (t, t)
        } else {
            let tc = -qb / qa;
            let l = f0 + d * tc;
            let shifted = -qa * self.centred(l);
            // The shifted form cancels inside f(o') when o' is far from o (qa small against
            // qb: a direction nearly along the surface, e.g. a cone's generator); then the
            // plain form qb² − qa·qc is the accurate one. Take the form with the smaller
            // rounding bound (both as multiples of the same unit roundoff).
            let shifted_err = qa.abs() * self.centred_abs(l);
            let plain_err = qb * qb + (qa * qc).abs();
            let disc = if shifted_err <= plain_err {
                shifted
            } else {
                qb * qb - qa * qc
            };
            if !(disc >= 0.0) {
                return None;
            }
            let q = -(qb + libm::copysign(libm::sqrt(disc), qb));
            // Δ = 0 is the double root tc (like the sphere's tangent case). `qc/q` would give
            // `−qc/(2qb)` instead, whose `qc = f(o)` rounds independently of `f(o')`: for an
            // origin on the surface within rounding the two disagree (found by the
            // `ray_quadric` fuzz target).
            if q == 0.0 || disc == 0.0 {
                (tc, tc)
            } else {
                let (x, y) = (qc / q, q / qa);
                if x <= y { (x, y) } else { (y, x) }
            }
        };
        (t0.is_finite() && t1.is_finite()).then_some((t0, t1))
    }

    /// The coefficients `[qa, qb, qc]` of `f(o + t·d) = qa·t² + 2qb·t + qc` along `ray`, in
    /// `f64` (module documentation: `uᵀAv` from the axis for a cylinder or cone).
    pub(crate) fn ray_polynomial(&self, ray: &Ray) -> [f64; 3] {
        let d = ray.direction.as_dvec3();
        let f0 = ray.origin.as_dvec3() - self.center;
        match self.axial {
            None => {
                let g0 = self.a * f0 + self.bc;
                [d.dot(self.a * d), d.dot(g0), f0.dot(g0 + self.bc) + self.k]
            }
            Some(ax) => [
                ax.form(d, d),
                ax.form(d, f0) + d.dot(self.bc),
                self.centred(f0),
            ],
        }
    }

    /// `f(x_c + y)`, with `yᵀAy` from the axis for a cylinder or cone.
    fn centred(&self, y: DVec3) -> f64 {
        match self.axial {
            None => y.dot(self.a * y + self.bc * 2.0) + self.k,
            Some(ax) => ax.form(y, y) + y.dot(self.bc * 2.0) + self.k,
        }
    }

    /// [`Quadric::centred`] with every term replaced by its absolute value.
    fn centred_abs(&self, y: DVec3) -> f64 {
        let ya = y.abs();
        match self.axial {
            None => ya.dot(abs_mat(&self.a) * ya + self.bc.abs() * 2.0) + self.k.abs(),
            Some(ax) => ax.form_abs(y, y) + ya.dot(self.bc.abs() * 2.0) + self.k.abs(),
        }
    }

    /// The nearest hit in `(t_min, t_max]` (module documentation: point, error bound, normal).
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t0, t1) = self.roots(ray)?;
        let t = [t0, t1].into_iter().find(|&t| ray.contains(t as f32))?;
        self.hit_at(ray, t)
    }

    fn hit_at(&self, ray: &Ray, t: f64) -> Option<Hit> {
        let d = ray.direction.as_dvec3();
        let mut x = ray.origin.as_dvec3() + d * t;
        let g = self.gradient(x);
        let gg = g.length_squared();
        let fx = self.eval(x);
        if gg > 0.0 && gg.is_finite() {
            let x1 = x - g * (fx / gg);
            if x1.is_finite() && self.eval(x1).abs() <= fx.abs() {
                x = x1;
            }
        }
        let fx = self.eval(x);
        let g = self.gradient(x);
        // |g| from g scaled by its largest component: near a singular point |g|² can
        // underflow even f64 (a non-unit normal; found by the `ray_quadric` fuzz target).
        let gm = g.abs().max_element();
        let gs = g / gm;
        let gsl = gs.length();
        let gl = gsl * gm;
        let slop = fx.abs() + gamma_f64(10) * self.eval_abs(x);
        let (dist, normal) = if gm > 0.0 && gl > 0.0 && gl.is_finite() {
            (QUADRIC_DISTANCE_SLACK * slop / gl, gs / gsl)
        } else {
            let fro = frobenius(&self.a);
            (
                QUADRIC_DISTANCE_SLACK * libm::sqrt(slop / fro),
                -d / d.length(),
            )
        };
        let point = x.as_vec3();
        let dist32 = (dist as f32).next_up();
        if !point.is_finite() || !dist32.is_finite() || !normal.is_finite() {
            return None;
        }
        let point_error = point.abs() * gamma(1) + Vec3::splat(dist32);
        Some(Hit {
            t: t as f32,
            point,
            point_error,
            normal: normal.as_vec3(),
            uv: Vec2::ZERO,
            front_face: d.dot(normal) < 0.0,
        })
    }
}

/// An axis-aligned ellipsoid `Σ ((x_i − center_i)/radii_i)² = 1`, intersected through its
/// [`Quadric`] (`A = diag(1/radii²)`, centre exact, `k = −1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    center: Vec3,
    radii: Vec3,
    quadric: Quadric,
}

impl Ellipsoid {
    /// The ellipsoid of semi-axes `radii` (world units, along x, y, z) around `center`.
    ///
    /// # Errors
    ///
    /// [`GeometryError::NonFinite`] for non-finite input,
    /// [`GeometryError::Degenerate`] for a radius `≤ 0`.
    pub fn new(center: Vec3, radii: Vec3) -> Result<Self, GeometryError> {
        if !center.is_finite() || !radii.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        if !(radii.min_element() > 0.0) {
            return Err(GeometryError::Degenerate);
        }
        let r = radii.as_dvec3();
        let inv = DVec3::ONE / (r * r);
        let quadric =
            Quadric::from_center_form(DMat3::from_diagonal(inv), center.as_dvec3(), -1.0)?;
        Ok(Self {
            center,
            radii,
            quadric,
        })
    }

    getters! {
        /// Centre, world units.
        center: Vec3;
        /// Semi-axes along x, y, z, world units.
        radii: Vec3;
    }

    /// The quadric `Σ ((x_i − c_i)/r_i)² − 1`.
    #[inline]
    #[must_use]
    pub fn quadric(&self) -> &Quadric {
        &self.quadric
    }

    /// Both roots, as [`Quadric::roots`].
    #[must_use]
    pub fn roots(&self, ray: &Ray) -> Option<(f64, f64)> {
        self.quadric.roots(ray)
    }

    /// As [`Quadric::intersect`], with `uv = (φ/2π, θ/π)` of the hit mapped to the unit sphere
    /// (`y = (p − c)/radii`, `φ = atan2(y_y, y_x) ∈ [0, 2π)`, `θ = acos(y_z)`).
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut h = self.quadric.intersect(ray)?;
        let y = (h.point.as_dvec3() - self.center.as_dvec3()) / self.radii.as_dvec3();
        let y = y.normalize_or_zero();
        let mut phi = libm::atan2(y.y, y.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let theta = libm::acos(y.z.clamp(-1.0, 1.0));
        h.uv = Vec2::new(seam_wrapped((phi / TAU) as f32), (theta / PI) as f32);
        Some(h)
    }
}

/// A general quadric (solid where `f < 0`), optionally clipped to a box: hits outside the
/// closed box are dropped ([`crate::shape::Shape`] for the queries). A clipped quadric is an
/// open surface, not a solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClippedQuadric {
    /// The surface.
    pub quadric: Quadric,
    /// Clip box; `None` for the whole surface.
    pub clip: Option<Aabb>,
}

impl ClippedQuadric {
    /// Whether `h`'s point is in the clip box (closed; always without one).
    #[must_use]
    pub fn in_clip(&self, h: &Hit) -> bool {
        self.clip.is_none_or(|b| b.contains_point(h.point))
    }
}

#[cfg(test)]
mod tests;
