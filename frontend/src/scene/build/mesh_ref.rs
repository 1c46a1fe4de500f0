//! `[mesh.NAME]` and the objects that name a mesh: read, smoothed, subdivided once, shared.

use crate::error::{Error, Result};
use crate::scene::MeshField;
use crate::scene::def::{MeshDef, S};
use crate::scene::geom::MeshShape;
use std::path::Path;
use std::sync::Arc;

use super::Ctx;
use super::list;

/// A checked `[mesh.NAME]`: the file's path, the Laplacian smoothing `(step, iterations)`,
/// the Loop levels and smooth shading.
type MeshSettings = (std::path::PathBuf, Option<(f32, u32)>, u32, bool);

/// The folder relative mesh `file`s of the scene read from `scene` are resolved against: the
/// scene file's folder, or the current directory (the empty path) when the scene is a stream
/// (a pipe such as `/dev/stdin` or a shell's `<(...)`), whose folder (`/dev`, `/dev/fd`) holds
/// no meshes. A stream: a path under `/dev/` or `/proc/self/fd/`, or one that exists but is
/// not a regular file (a FIFO, a device).
fn mesh_base(scene: &Path) -> &Path {
    let stream = scene.starts_with("/dev") && scene != Path::new("/dev")
        || scene.starts_with("/proc/self/fd")
        || std::fs::metadata(scene).is_ok_and(|m| !m.is_file());
    match scene.parent() {
        Some(folder) if !stream => folder,
        _ => Path::new(""),
    }
}

/// Checks `[mesh.NAME]` without reading the file: it exists and is a file, the smoothing and
/// subdivision settings are in range. Returns the path, the smoothing `(step, iterations)` and
/// the subdivision levels. Run for every mesh definition, used or not.
pub(super) fn mesh_def(ctx: &Ctx<'_>, name: &str, def: &MeshDef) -> Result<MeshSettings> {
    let p = format!("mesh.{name}");
    let file = Path::new(def.file.get_ref());
    let base = mesh_base(ctx.src.path);
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
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && base == Path::new("") => {
                "not found (relative to the current directory: the scene is read from a stream)"
                    .to_string()
            }
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
        let (span, key) = match (field, &def.smooth, &def.subdivide, &def.shading) {
            (MeshField::Smooth, Some(s), _, _) => (s.span(), "smooth"),
            (MeshField::Subdivide, _, Some(s), _) => (s.span(), "subdivide"),
            (MeshField::Shading, _, _, Some(s)) => (s.span(), "shading"),
            _ => (def.file.span(), "file"),
        };
        let field = format!("{p}.{key}");
        match e {
            Error::Input { at, message } if at.line.is_none() => ctx.err(
                &span,
                &field,
                format!("{}: {message}", crate::text::path(&at.file)),
            ),
            // A line of the mesh file: named first, then the setting in the scene.
            Error::Input { at, message } => {
                let named_at = ctx.src.at(&span, &field);
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

#[cfg(test)]
mod tests {
    use super::mesh_base;
    use std::path::Path;

    /// Mesh files are relative to the scene's folder, except for a scene read from a stream:
    /// a device (`/dev/null`), a shell's `<(...)` (`/dev/fd/63`), `/proc/self/fd/0`, or an
    /// existing path that is not a regular file (a folder here); those resolve against the
    /// current directory, the empty path.
    #[test]
    fn a_streamed_scene_resolves_meshes_against_the_current_directory() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("s.toml");
        std::fs::write(&file, "").unwrap();
        assert_eq!(mesh_base(&file), dir.path());
        assert_eq!(mesh_base(Path::new("scenes/x.toml")), Path::new("scenes"));
        for stream in ["/dev/null", "/dev/stdin", "/dev/fd/63", "/proc/self/fd/0"] {
            assert_eq!(mesh_base(Path::new(stream)), Path::new(""), "{stream}");
        }
        assert_eq!(mesh_base(&dir.path().join(".")), Path::new(""));
    }

    /// The not-found error of a streamed scene says where the relative path was looked for.
    #[test]
    fn a_streamed_scenes_missing_mesh_says_it_looked_in_the_current_directory() {
        let text = "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
                    [mesh.b]\nfile = \"no-such-mesh.obj\"\n";
        let e = crate::scene::parse(text, Path::new("/dev/null"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("not found (relative to the current directory: the scene is read from a stream) (looked for no-such-mesh.obj)"),
            "{e}"
        );
    }

    /// A mesh the half-edge core rejects for a setting is blamed on that setting: the OBJ's
    /// line first, the message saying which setting needs a manifold mesh, then the setting's
    /// place in the scene (not the `file` key). The edge 1–2 of this OBJ has three triangles.
    #[test]
    fn a_non_manifold_mesh_is_blamed_on_the_setting_that_needs_a_manifold_one() {
        let dir = tempfile::tempdir().unwrap();
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n";
        std::fs::write(dir.path().join("fan.obj"), obj).unwrap();
        let path = dir.path().join("s.toml");
        for (setting, key, column, what) in [
            ("subdivide = 1", "subdivide", 13, "subdivide"),
            (
                "smooth = { step = 0.5, iterations = 1 }",
                "smooth",
                10,
                "smooth",
            ),
            ("shading = \"smooth\"", "shading", 11, "smooth shading"),
        ] {
            let text = format!(
                "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
                 [mesh.b]\nfile = \"fan.obj\"\n{setting}\n\n[material.m]\n\n\
                 [[object]]\ntype = \"mesh\"\nmesh = \"b\"\nmaterial = \"m\"\n"
            );
            let e = crate::scene::parse(&text, &path).unwrap_err().to_string();
            let e = e.replace(&format!("{}/", dir.path().display()), "");
            // The OBJ line is that of the edge's third triangle, which made it non-manifold.
            let after_line = e
                .strip_prefix("fan.obj:")
                .and_then(|r| r.split_once(": "))
                .filter(|(line, _)| *line == "8");
            assert!(
                after_line.is_some_and(|(_, m)| m.starts_with(&format!(
                    "{what} needs a manifold mesh; the half-edge core rejects this one: "
                ))),
                "{e}"
            );
            assert!(
                e.ends_with(&format!(
                    "(the mesh of s.toml:10:{column}: field `mesh.b.{key}`)"
                )),
                "{e}"
            );
        }
    }
}
