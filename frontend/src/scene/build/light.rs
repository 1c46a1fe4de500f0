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
