//! `[mesh.NAME]` and the objects that name a mesh: read, smoothed, subdivided once, shared.

use crate::error::{Error, Result};
use crate::scene::MeshField;
use crate::scene::def::{MeshDef, S};
use crate::scene::geom::MeshShape;
use std::sync::Arc;

use super::Ctx;
use super::list;

/// A checked `[mesh.NAME]`: the file's path, the Laplacian smoothing `(step, iterations)`,
/// the Loop levels and smooth shading.
type MeshSettings = (std::path::PathBuf, Option<(f32, u32)>, u32, bool);

/// Checks `[mesh.NAME]` without reading the file: it exists and is a file, the smoothing and
/// subdivision settings are in range. Returns the path, the smoothing `(step, iterations)` and
/// the subdivision levels. Run for every mesh definition, used or not.
pub(super) fn mesh_def(ctx: &Ctx<'_>, name: &str, def: &MeshDef) -> Result<MeshSettings> {
    let p = format!("mesh.{name}");
    let file = std::path::Path::new(def.file.get_ref());
    let base = ctx.src.path.parent().unwrap_or(std::path::Path::new(""));
    let path = base.join(file);
    if path.is_dir() {
        return Err(ctx.err(
            &def.file.span(),
            &format!("{p}.file"),
            format!(
                "mesh file `{}` is a directory, not an OBJ file ({})",
                crate::text::escaped(def.file.get_ref()),
                crate::text::path(&path)
            ),
        ));
    }
    if !path.is_file() {
        // What the system says when the path cannot be followed (a loop of symbolic links, a
        // folder without permission), "not found" only when it is not there.
        let why = match std::fs::metadata(&path) {
            Ok(_) => "is not a regular file (a device, FIFO or socket)".to_string(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => "not found".to_string(),
            Err(e) => format!("cannot be read: {e}"),
        };
        return Err(ctx.err(
            &def.file.span(),
            &format!("{p}.file"),
            format!(
                "mesh file `{}` {why} (looked for {})",
                crate::text::escaped(def.file.get_ref()),
                crate::text::path(&path)
            ),
        ));
    }
    let smoothing = match &def.smooth {
        Some(s) => {
            let sd = s.get_ref();
            let step = ctx.f(&sd.step, &format!("{p}.smooth.step"))?;
            if *sd.iterations.get_ref() > crate::scene::MAX_SMOOTH_ITERATIONS {
                return Err(ctx.err(
                    &sd.iterations.span(),
                    &format!("{p}.smooth.iterations"),
                    format!("at most {} iterations", crate::scene::MAX_SMOOTH_ITERATIONS),
                ));
            }
            Some((step, *sd.iterations.get_ref()))
        }
        None => None,
    };
    let levels = def.subdivide.as_ref().map_or(0, |v| *v.get_ref());
    if levels > 4 {
        let span = def.subdivide.as_ref().map(|v| v.span()).unwrap_or_default();
        return Err(ctx.err(
            &span,
            &format!("{p}.subdivide"),
            "at most 4 levels (each multiplies the triangles by 4)",
        ));
    }
    let smooth_shading = match &def.shading {
        None => false,
        Some(v) => match v.get_ref().as_str() {
            "flat" => false,
            "smooth" => true,
            other => {
                return Err(ctx.err(
                    &v.span(),
                    &format!("{p}.shading"),
                    format!("unknown shading `{other}` (expected `flat` or `smooth`)"),
                ));
            }
        },
    };
    Ok((path, smoothing, levels, smooth_shading))
}

pub(super) fn mesh(ctx: &mut Ctx<'_>, name: &S<String>, field: &str) -> Result<Arc<MeshShape>> {
    let Some((_, loaded)) = ctx.meshes.get(name.get_ref()) else {
        let known: Vec<&str> = ctx.meshes.keys().map(String::as_str).collect();
        return Err(ctx.err(
            &name.span(),
            field,
            format!(
                "no mesh named `{}` (defined with [mesh.NAME]: {})",
                name.get_ref(),
                list(&known)
            ),
        ));
    };
    if let Some(m) = loaded {
        return Ok(m.clone());
    }
    let def = ctx.mesh_defs[name.get_ref()].get_ref();
    let (path, smoothing, levels, smooth_shading) = mesh_def(ctx, name.get_ref(), def)?;
    let p = format!("mesh.{}", name.get_ref());
    let shape = crate::scene::load_mesh(name.get_ref(), &path, smoothing, levels, smooth_shading)
        .map_err(|(field, e)| {
        // The setting the error belongs to, where the scene names it.
        let (span, key) = match (field, &def.smooth, &def.subdivide) {
            (MeshField::Smooth, Some(s), _) => (s.span(), "smooth"),
            (MeshField::Subdivide, _, Some(s)) => (s.span(), "subdivide"),
            _ => (def.file.span(), "file"),
        };
        let field = format!("{p}.{key}");
        match e {
            Error::Input { at, message } if at.line.is_none() => ctx.err(
                &span,
                &field,
                format!("{}: {message}", crate::text::path(&at.file)),
            ),
            // A line of the mesh file: named first, then where the scene names the file.
            Error::Input { at, message } => {
                let named_at = ctx.src.at(&def.file.span(), &format!("{p}.file"));
                Error::input(at, format!("{message} (the mesh of {named_at})"))
            }
            other => other,
        }
    })?;
    let shape = Arc::new(shape);
    ctx.loaded.push(shape.clone());
    ctx.mesh_files.push(path);
    if let Some(entry) = ctx.meshes.get_mut(name.get_ref()) {
        entry.1 = Some(shape.clone());
    }
    Ok(shape)
}
