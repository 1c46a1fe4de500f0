//! `[camera]`: the projection, the image size and the thin lens.

use crate::error::Result;
use crate::scene::def::{self, S};
use crate::scene::{Camera, MAX_IMAGE_SIDE, Projection};
use glam::Vec3;

use super::Ctx;

pub(super) fn camera(ctx: &Ctx<'_>, c: &S<def::CameraDef>) -> Result<Camera> {
    let span = c.span();
    let c = c.get_ref();
    let kind = c
        .kind
        .as_ref()
        .map_or("perspective", |k| k.get_ref().as_str());
    let projection = match kind {
        "perspective" => {
            if let Some(v) = &c.view_size {
                return Err(ctx.err(
                    &v.span(),
                    "camera.view_size",
                    "only for `type = \"orthographic\"`",
                ));
            }
            let fov = ctx.need(&c.fov, &span, "camera.fov", "perspective")?;
            let f = ctx.f(fov, "camera.fov")?;
            if !(f > 0.0 && f < 180.0) {
                return Err(ctx.err(&fov.span(), "camera.fov", "must be in (0, 180) degrees"));
            }
            Projection::Perspective { fov: f }
        }
        "orthographic" => {
            if let Some(v) = &c.fov {
                return Err(ctx.err(&v.span(), "camera.fov", "only for `type = \"perspective\"`"));
            }
            let v = ctx.need(&c.view_size, &span, "camera.view_size", "orthographic")?;
            Projection::Orthographic {
                view_size: ctx.positive(v, "camera.view_size")?,
            }
        }
        other => {
            let k = c.kind.as_ref().map(|k| k.span()).unwrap_or(span.clone());
            return Err(ctx.err(
                &k,
                "camera.type",
                format!("unknown camera type `{other}` (expected `perspective` or `orthographic`)"),
            ));
        }
    };
    for (v, name) in [(&c.width, "camera.width"), (&c.height, "camera.height")] {
        let x = *v.get_ref();
        if x == 0 || x > MAX_IMAGE_SIDE {
            return Err(ctx.err(&v.span(), name, format!("must be in 1..={MAX_IMAGE_SIDE}")));
        }
    }
    let eye = ctx.v3(&c.eye, "camera.eye")?;
    let look_at = ctx.v3(&c.look_at, "camera.look_at")?;
    let up = match &c.up {
        Some(u) => ctx.dir(u, "camera.up")?,
        None => Vec3::Y,
    };
    // The view direction and the default focus distance are `look_at − eye` and its length.
    if !(look_at - eye).length().is_finite() {
        return Err(ctx.err(
            &c.look_at.span(),
            "camera.look_at",
            "is too far from `eye`: the square of the distance between them is beyond the largest `f32` (distances up to about 1.8e19 are taken)",
        ));
    }
    let mut camera = Camera::new(
        eye,
        look_at,
        up,
        projection,
        *c.width.get_ref(),
        *c.height.get_ref(),
    )
    .ok_or_else(|| {
        ctx.err(
            &c.look_at.span(),
            "camera.look_at",
            "must differ from `eye`, and the view direction must not be parallel to `up`",
        )
    })?;
    let aperture = match &c.aperture {
        Some(a) => {
            if kind != "perspective" {
                return Err(ctx.err(
                    &a.span(),
                    "camera.aperture",
                    "only for `type = \"perspective\"`",
                ));
            }
            let aperture = ctx.f(a, "camera.aperture")?;
            if !(aperture >= 0.0) {
                return Err(ctx.err(&a.span(), "camera.aperture", "must be ≥ 0"));
            }
            aperture
        }
        None => 0.0,
    };
    if aperture == 0.0 {
        // A pinhole: the lens's fields would have no effect.
        let lens_only = "only with `aperture` > 0";
        if let Some(f) = &c.focus_distance {
            return Err(ctx.err(&f.span(), "camera.focus_distance", lens_only));
        }
        if let Some(n) = &c.lens_samples {
            return Err(ctx.err(&n.span(), "camera.lens_samples", lens_only));
        }
        return Ok(camera);
    }
    let focus_distance = match &c.focus_distance {
        Some(f) => ctx.positive(f, "camera.focus_distance")?,
        None => (look_at - eye).length(),
    };
    let samples = match &c.lens_samples {
        Some(n) if *n.get_ref() == 0 || *n.get_ref() > crate::scene::MAX_LENS_SAMPLES => {
            return Err(ctx.err(
                &n.span(),
                "camera.lens_samples",
                format!("must be in 1..={}", crate::scene::MAX_LENS_SAMPLES),
            ));
        }
        Some(n) => *n.get_ref(),
        None => 16,
    };
    camera.lens = Some(crate::scene::Lens {
        aperture,
        focus_distance,
        samples,
    });
    Ok(camera)
}
