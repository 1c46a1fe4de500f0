//! `[material.NAME]`.

use crate::error::Result;
use crate::scene::Material;
use crate::scene::def::{self, S};

use super::Ctx;

pub(super) fn material(ctx: &Ctx<'_>, name: &str, m: &S<def::MaterialDef>) -> Result<Material> {
    let m = m.get_ref();
    let p = format!("material.{name}");
    let mut out = Material::with_name(name);
    if let Some(v) = &m.diffuse {
        out.diffuse = ctx.color(v, &format!("{p}.diffuse"))?;
    }
    out.ambient = match &m.ambient {
        Some(v) => ctx.color(v, &format!("{p}.ambient"))?,
        None => out.diffuse,
    };
    if let Some(v) = &m.specular {
        out.specular = ctx.color(v, &format!("{p}.specular"))?;
    }
    if let Some(v) = &m.shininess {
        let x = ctx.f(v, &format!("{p}.shininess"))?;
        if x < 0.0 {
            return Err(ctx.err(&v.span(), &format!("{p}.shininess"), "must be ≥ 0"));
        }
        out.shininess = x;
    }
    if let Some(v) = &m.specular_model {
        out.specular_model = match v.get_ref().as_str() {
            "blinn-phong" => crate::scene::SpecularModel::BlinnPhong,
            "phong" => crate::scene::SpecularModel::Phong,
            other => {
                return Err(ctx.err(
                    &v.span(),
                    &format!("{p}.specular_model"),
                    format!("unknown specular model `{other}` (expected `blinn-phong` or `phong`)"),
                ));
            }
        };
    }
    if let Some(v) = &m.mirror {
        out.mirror = ctx.unit_range(v, &format!("{p}.mirror"))?;
    }
    if let Some(v) = &m.transparency {
        out.transparency = ctx.unit_range(v, &format!("{p}.transparency"))?;
    }
    if let Some(v) = &m.ior {
        out.ior = ctx.positive(v, &format!("{p}.ior"))?;
    }
    Ok(out)
}
