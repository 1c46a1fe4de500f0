//! Checks a parsed scene and builds the render-ready [`Scene`].

use super::def::{self, S, V3};
use super::{DEFAULT_MAX_DEPTH, Scene, Source};
use crate::error::{Error, Result};
use crate::scene::geom::MeshShape;
use glam::Vec3;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::sync::Arc;

mod camera;
mod light;
mod material;
mod mesh_ref;
mod object;
mod repeat;
mod transform;

use camera::camera;
use light::light;
use material::material;
use mesh_ref::mesh_def;
use object::object;

/// Why a direction or rotation axis is refused: `normalize` in `f32` needs its squared length
/// between the smallest subnormal and the largest finite `f32`, so a largest component from
/// about `4·10⁻²³` to `1.8·10¹⁹` (a zero vector, or `[1e-30, 0, 0]`, has no direction here).
pub(super) const NOT_NORMALISABLE: &str = "must be a vector whose length f32 can normalise (a largest component from about 1e-22 to 1e19)";
use repeat::{MAX_OBJECTS, repeat};

type Span = Range<usize>;

struct Ctx<'a> {
    src: &'a Source<'a>,
    materials: HashMap<String, u32>,
    meshes: BTreeMap<String, (Span, Option<Arc<MeshShape>>)>,
    mesh_defs: BTreeMap<String, S<def::MeshDef>>,
    loaded: Vec<Arc<MeshShape>>,
    mesh_files: Vec<std::path::PathBuf>,
}

impl Ctx<'_> {
    fn err(&self, span: &Span, field: &str, msg: impl Into<String>) -> Error {
        self.src.err(span, field, msg)
    }

    /// The number as the scene file writes it (trimmed), for a message about a value that
    /// `f32` cannot hold as written.
    fn written(&self, v: &S<f32>) -> &str {
        self.src
            .text
            .get(v.span())
            .map(str::trim)
            .unwrap_or_default()
    }

    fn f(&self, v: &S<f32>, field: &str) -> Result<f32> {
        let x = *v.get_ref();
        if !x.is_finite() {
            // A finite number beyond `f32` reads as infinity: say what was written.
            let written = self.written(v);
            let msg = if written.parse::<f64>().is_ok_and(f64::is_finite) {
                format!("{written} is beyond the largest `f32` (±3.4e38)")
            } else {
                format!("{x} is not a finite number")
            };
            return Err(self.err(&v.span(), field, msg));
        }
        Ok(x)
    }

    fn positive(&self, v: &S<f32>, field: &str) -> Result<f32> {
        let x = self.f(v, field)?;
        if !(x > 0.0) {
            // A positive number below `f32`'s smallest reads as 0: say what was written.
            let written = self.written(v);
            // Positive as written: above 0 in `f64`, or below even `f64`'s range (`1e-400`
            // parses as 0) with a non-zero digit before its exponent and no sign.
            let mantissa = written.split(['e', 'E']).next().unwrap_or_default();
            let underflows =
                !written.starts_with('-') && mantissa.bytes().any(|b| (b'1'..=b'9').contains(&b));
            let msg = if written
                .parse::<f64>()
                .is_ok_and(|w| w > 0.0 || (w == 0.0 && underflows))
            {
                format!(
                    "must be > 0 ({written} is below the smallest positive `f32`, 1.4e-45, and reads as 0)"
                )
            } else {
                format!("must be > 0 (got {x})")
            };
            return Err(self.err(&v.span(), field, msg));
        }
        Ok(x)
    }

    fn unit_range(&self, v: &S<f32>, field: &str) -> Result<f32> {
        let x = self.f(v, field)?;
        if !(0.0..=1.0).contains(&x) {
            return Err(self.err(&v.span(), field, format!("must be in [0, 1] (got {x})")));
        }
        Ok(x)
    }

    /// The vector `v`; a component that is not a finite `f32` is refused by [`Ctx::f`] at its
    /// own place, as `field[k]`.
    fn v3(&self, v: &V3, field: &str) -> Result<Vec3> {
        self.components(v.get_ref(), field)
    }

    /// The vector of the spanned components `xs`, each checked by [`Ctx::f`] as `field[k]`.
    fn components(&self, xs: &[S<f32>; 3], field: &str) -> Result<Vec3> {
        let mut a = [0.0; 3];
        for (k, (x, slot)) in xs.iter().zip(&mut a).enumerate() {
            *slot = self.f(x, &format!("{field}[{k}]"))?;
        }
        Ok(Vec3::from_array(a))
    }

    fn color(&self, v: &V3, field: &str) -> Result<Vec3> {
        let c = self.v3(v, field)?;
        if c.min_element() < 0.0 {
            return Err(self.err(&v.span(), field, "colour components must be ≥ 0"));
        }
        Ok(c)
    }

    fn dir(&self, v: &V3, field: &str) -> Result<Vec3> {
        let d = self.v3(v, field)?.normalize_or_zero();
        if d == Vec3::ZERO {
            return Err(self.err(&v.span(), field, NOT_NORMALISABLE));
        }
        Ok(d)
    }

    fn need<'b, T>(&self, v: &'b Option<T>, at: &Span, field: &str, kind: &str) -> Result<&'b T> {
        v.as_ref().ok_or_else(|| {
            self.err(
                at,
                field,
                format!("missing field `{}` for type `{kind}`", leaf(field)),
            )
        })
    }
}

/// Names for a message, comma-separated; `none` for no names.
fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

fn leaf(field: &str) -> &str {
    field.rsplit('.').next().unwrap_or(field)
}

pub(super) fn build(src: &Source<'_>, d: def::SceneDef) -> Result<Scene> {
    let mut ctx = Ctx {
        src,
        materials: HashMap::new(),
        meshes: BTreeMap::new(),
        mesh_defs: d.mesh,
        loaded: Vec::new(),
        mesh_files: Vec::new(),
    };
    let ambient = match &d.ambient {
        Some(v) => ctx.color(v, "ambient")?,
        None => Vec3::ZERO,
    };
    let background = match &d.background {
        Some(v) => ctx.color(v, "background")?,
        None => Vec3::ZERO,
    };
    let max_depth = d
        .max_depth
        .as_ref()
        .map_or(DEFAULT_MAX_DEPTH, |v| *v.get_ref());
    if max_depth > 64 {
        let span = d.max_depth.as_ref().map(|v| v.span()).unwrap_or_default();
        return Err(ctx.err(&span, "max_depth", "must be ≤ 64"));
    }
    let samples = d.samples.as_ref().map_or(1, |v| *v.get_ref());
    if !(1..=super::MAX_SAMPLES).contains(&samples) {
        let span = d.samples.as_ref().map(|v| v.span()).unwrap_or_default();
        return Err(ctx.err(
            &span,
            "samples",
            format!("must be 1 to {}", super::MAX_SAMPLES),
        ));
    }
    let camera = camera(&ctx, &d.camera)?;
    let size_at = ctx.src.at(
        &d.camera.get_ref().width.span(),
        "camera.width, camera.height",
    );

    let mut lights = Vec::new();
    for (i, l) in d.light.iter().enumerate() {
        lights.push(light(&ctx, i, l)?);
    }

    let mut materials = Vec::new();
    for (name, m) in &d.material {
        ctx.materials.insert(name.clone(), materials.len() as u32);
        materials.push(material(&ctx, name, m)?);
    }
    let names: Vec<String> = ctx.mesh_defs.keys().cloned().collect();
    for name in names {
        let span = ctx.mesh_defs[&name].span();
        ctx.meshes.insert(name, (span, None));
    }

    let mut objects = Vec::new();
    let mut labels = Vec::new();
    for (i, o) in d.object.iter().enumerate() {
        let field = format!("object[{i}]");
        let label = format!("{field} ({})", o.get_ref().kind.get_ref());
        let node = object(&mut ctx, o, &field, None, 0)?;
        match &o.get_ref().repeat {
            None => {
                labels.push(label);
                objects.push(node);
            }
            Some(r) => {
                for (k, copy) in repeat(&ctx, &node, r, &field, objects.len())?
                    .into_iter()
                    .enumerate()
                {
                    labels.push(format!("{label} copy {k}"));
                    objects.push(copy);
                }
            }
        }
        if objects.len() > MAX_OBJECTS {
            return Err(ctx.err(
                &o.span(),
                &field,
                format!("more than {MAX_OBJECTS} objects in the scene"),
            ));
        }
    }
    // Definitions no object uses are still checked (not read: nothing renders them), and
    // their files are inputs all the same: no output may replace them.
    let mut unused = Vec::new();
    for (name, (_, loaded)) in &ctx.meshes {
        if let (None, Some(def)) = (loaded, ctx.mesh_defs.get(name)) {
            unused.push(mesh_def(&ctx, name, def.get_ref())?.0);
        }
    }
    ctx.mesh_files.extend(unused);
    Ok(Scene {
        path: src.path.to_path_buf(),
        camera,
        size_at,
        ambient,
        background,
        max_depth,
        samples,
        lights,
        materials,
        top: super::top::TopLevel::new(&objects),
        objects,
        object_labels: labels,
        meshes: ctx.loaded,
        mesh_files: ctx.mesh_files,
    })
}
