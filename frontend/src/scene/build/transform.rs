//! `transform = [step, …]` on an object.

use crate::error::Result;
use crate::scene::def::{self, S};
use crate::scene::xform;
use glam::{Mat4, Vec3, Vec4};
use halfray_core::GeometryError;
use halfray_core::transform::Transform;

use super::Ctx;

/// The transform of the steps `t` (field `p`) applied in order, the first step first.
///
/// # Errors
///
/// An error at the first step that fails, naming it (`p[k].scale`, …) and its position: a step
/// that is not one well-formed kind, a step that is not an invertible affine map by itself
/// ([`Transform::new`], worded by [`xform::describe`]), or the step at which the running
/// product of steps `0..=k` first stops being one (each step invertible alone, the product
/// singular, too ill-conditioned or overflowing `f32`).
pub(super) fn transform(
    ctx: &Ctx<'_>,
    t: &S<Vec<S<def::TransformDef>>>,
    p: &str,
) -> Result<Transform> {
    let mut m = Mat4::IDENTITY;
    let mut combined = Transform::IDENTITY;
    for (k, step) in t.get_ref().iter().enumerate() {
        let f = format!("{p}[{k}]");
        let s = step.get_ref();
        let (step_m, span, name) = match (&s.translate, &s.rotate, &s.scale, &s.matrix) {
            (Some(v), None, None, None) => (
                Mat4::from_translation(ctx.v3(v, &format!("{f}.translate"))?),
                v.span(),
                "translate",
            ),
            (None, Some(r), None, None) => {
                let rd = r.get_ref();
                let axis = ctx.v3(&rd.axis, &format!("{f}.rotate.axis"))?;
                let deg = ctx.f(&rd.degrees, &format!("{f}.rotate.degrees"))?;
                let rm = xform::rotation(axis, deg).ok_or_else(|| {
                    ctx.err(
                        &rd.axis.span(),
                        &format!("{f}.rotate.axis"),
                        super::NOT_NORMALISABLE,
                    )
                })?;
                (rm, r.span(), "rotate")
            }
            (None, None, Some(sc), None) => {
                let v = Vec3::from_array(sc.get_ref().0);
                if !v.is_finite() {
                    return Err(ctx.err(&sc.span(), &format!("{f}.scale"), "non-finite scale"));
                }
                (Mat4::from_scale(v), sc.span(), "scale")
            }
            (None, None, None, Some(mx)) => {
                let rows = mx.get_ref();
                if rows.iter().flat_map(|r| r.iter()).any(|x| !x.is_finite()) {
                    return Err(ctx.err(
                        &mx.span(),
                        &format!("{f}.matrix"),
                        "non-finite matrix entry",
                    ));
                }
                if *rows[3] != [0.0, 0.0, 0.0, 1.0] {
                    return Err(ctx.err(
                        &mx.span(),
                        &format!("{f}.matrix"),
                        format!(
                            "not an affine transform: the last row must be [0, 0, 0, 1], got {:?}",
                            *rows[3]
                        ),
                    ));
                }
                let r = |i: usize| Vec4::from_array(*rows[i]);
                (
                    Mat4::from_cols(r(0), r(1), r(2), r(3)).transpose(),
                    mx.span(),
                    "matrix",
                )
            }
            _ => {
                return Err(ctx.err(
                    &step.span(),
                    &f,
                    "each transform step needs exactly one of `translate`, `rotate`, `scale`, `matrix`",
                ));
            }
        };
        // Each step alone, then the running product, so the error names the step at which
        // the transform stops being invertible.
        let field = format!("{f}.{name}");
        Transform::new(step_m).map_err(|e| ctx.err(&span, &field, xform::describe(e)))?;
        m = step_m * m;
        combined = Transform::new(m).map_err(|e| {
            let why = match e {
                GeometryError::NonFinite => "overflow f32 (a non-finite entry)",
                e => xform::describe(e),
            };
            ctx.err(
                &span,
                &field,
                format!("steps 0 to {k} together: {why}; each step alone is invertible"),
            )
        })?;
    }
    Ok(combined)
}
