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
                let v = match sc.get_ref() {
                    def::ScaleDef::Uniform(x) => {
                        Vec3::splat(ctx.f(&S::new(sc.span(), *x), &format!("{f}.scale"))?)
                    }
                    def::ScaleDef::Axes(axes) => ctx.components(axes, &format!("{f}.scale"))?,
                };
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    /// A sphere scene with `transform = [{ scale = SCALE }]` on line 11.
    fn scene(scale: &str) -> String {
        format!(
            "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
             [material.m]\n\n[[object]]\ntransform = [{{ scale = {scale} }}]\n\
             type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
        )
    }

    /// A scale `f32` cannot hold is refused as written, at the factor (`scale`, or
    /// `scale[k]` in an array) and its column; NaN and infinities as not finite.
    #[test]
    fn a_scale_beyond_f32_is_named_as_written() {
        let field = "field `object[0].transform[0].scale";
        for (scale, want) in [
            (
                "1e39",
                format!("s.toml:11:24: {field}`: 1e39 is beyond the largest `f32` (±3.4e38)"),
            ),
            (
                "-4E38",
                format!("s.toml:11:24: {field}`: -4E38 is beyond the largest `f32` (±3.4e38)"),
            ),
            (
                "[1, 1, 1e39]",
                format!("s.toml:11:31: {field}[2]`: 1e39 is beyond the largest `f32` (±3.4e38)"),
            ),
            (
                "[nan, 1, 1]",
                format!("s.toml:11:25: {field}[0]`: NaN is not a finite number"),
            ),
            (
                "inf",
                format!("s.toml:11:24: {field}`: inf is not a finite number"),
            ),
        ] {
            let e = crate::scene::parse(&scene(scale), Path::new("s.toml"))
                .err()
                .map(|e| e.to_string());
            assert_eq!(e.as_deref(), Some(want.as_str()), "scale = {scale}");
        }
        for scale in ["2", "3e38", "[1, 2, 3]"] {
            let ok = crate::scene::parse(&scene(scale), Path::new("s.toml"));
            assert!(ok.is_ok(), "scale = {scale}: {:?}", ok.err());
        }
    }
}
