//! `[[light]]`: point, directional and area lights.

use crate::error::Result;
use crate::scene::def::{self, S};
use crate::scene::{Light, LightKind};
use glam::Vec3;

use super::Ctx;

pub(super) fn light(ctx: &Ctx<'_>, i: usize, l: &S<def::LightDef>) -> Result<Light> {
    let span = l.span();
    let l = l.get_ref();
    let p = format!("light[{i}]");
    let kind = match l.kind.get_ref().as_str() {
        "point" => {
            if let Some(d) = &l.direction {
                return Err(ctx.err(
                    &d.span(),
                    &format!("{p}.direction"),
                    "not used by a point light (give `position`)",
                ));
            }
            let pos = ctx.need(&l.position, &span, &format!("{p}.position"), "point")?;
            LightKind::Point {
                position: ctx.v3(pos, &format!("{p}.position"))?,
            }
        }
        "directional" => {
            if let Some(d) = &l.position {
                return Err(ctx.err(
                    &d.span(),
                    &format!("{p}.position"),
                    "not used by a directional light (give `direction`)",
                ));
            }
            let d = ctx.need(
                &l.direction,
                &span,
                &format!("{p}.direction"),
                "directional",
            )?;
            LightKind::Directional {
                direction: ctx.dir(d, &format!("{p}.direction"))?,
            }
        }
        other => {
            return Err(ctx.err(
                &l.kind.span(),
                &format!("{p}.type"),
                format!("unknown light type `{other}` (expected `point` or `directional`)"),
            ));
        }
    };
    let color = match &l.color {
        Some(c) => ctx.color(c, &format!("{p}.color"))?,
        None => Vec3::ONE,
    };
    let intensity = match &l.intensity {
        Some(v) => {
            let x = ctx.f(v, &format!("{p}.intensity"))?;
            if x < 0.0 {
                return Err(ctx.err(&v.span(), &format!("{p}.intensity"), "must be ≥ 0"));
            }
            if !(color * x).is_finite() {
                // The light's radiance is the product: it must be a finite `f32` too.
                return Err(ctx.err(
                    &v.span(),
                    &format!("{p}.intensity"),
                    format!(
                        "color × intensity exceeds the largest `f32` (±3.4e38): {:e} × {x}",
                        color.max_element()
                    ),
                ));
            }
            x
        }
        None => 1.0,
    };
    let radius = match &l.radius {
        None => 0.0,
        Some(r) if !matches!(kind, LightKind::Point { .. }) => {
            return Err(ctx.err(&r.span(), &format!("{p}.radius"), "only for point lights"));
        }
        Some(r) => {
            let x = ctx.f(r, &format!("{p}.radius"))?;
            if !(x >= 0.0) {
                return Err(ctx.err(&r.span(), &format!("{p}.radius"), "must be ≥ 0"));
            }
            x
        }
    };
    let samples = match &l.samples {
        None => 16,
        // Only an area light casts more than one shadow ray per shading point.
        Some(n) if !(radius > 0.0) => {
            return Err(ctx.err(
                &n.span(),
                &format!("{p}.samples"),
                "only for point lights with `radius` > 0 (area lights)",
            ));
        }
        Some(n) if *n.get_ref() == 0 || *n.get_ref() > crate::scene::MAX_LIGHT_SAMPLES => {
            return Err(ctx.err(
                &n.span(),
                &format!("{p}.samples"),
                format!("must be in 1..={}", crate::scene::MAX_LIGHT_SAMPLES),
            ));
        }
        Some(n) => *n.get_ref(),
    };
    Ok(Light {
        name: l.name.clone().unwrap_or(p),
        kind,
        intensity: color * intensity,
        cast_shadows: l.cast_shadows.unwrap_or(true),
        radius,
        samples,
    })
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    /// A scene with one point light whose extra keys are `light`.
    fn scene(light: &str) -> String {
        format!(
            "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
             [[light]]\ntype = \"point\"\nposition = [3, 3, 3]\n{light}\n"
        )
    }

    /// `color × intensity` is the light's radiance: 3e38 × 10 is beyond `f32` (the largest
    /// is about 3.4e38), refused at `intensity`; 3e38 × 1 is accepted as written.
    #[test]
    fn a_radiance_beyond_f32_is_refused_at_intensity() {
        let text = scene("color = [3e38, 3e38, 3e38]\nintensity = 10");
        let e = crate::scene::parse(&text, Path::new("l.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("l.toml:12:13: field `light[0].intensity`: color × intensity exceeds"),
            "{e}"
        );
        let ok = crate::scene::parse(
            &scene("color = [3e38, 1, 0]\nintensity = 1"),
            Path::new("l.toml"),
        );
        assert_eq!(
            ok.map(|s| s.lights[0].intensity.x).ok(),
            Some(3e38),
            "accepted with its radiance"
        );
    }
}
