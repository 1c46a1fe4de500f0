//! Checks a parsed scene and builds the render-ready [`Scene`].

use super::def::{self, ObjectDef, S, V3};
use super::{
    Camera, DEFAULT_MAX_DEPTH, Light, LightKind, MAX_IMAGE_SIDE, Material, Projection, Scene,
    Source,
};
use crate::error::{Error, Result};
use crate::render::geom::{
    ClippedQuadric, CsgOp, MeshShape, Node, POLYGON_MAX_VERTICES, Polygon, Shape,
};
use crate::render::xform;
use glam::{DMat3, DVec3, Mat4, Vec3, Vec4};
use halfray_core::plane::Plane;
use halfray_core::quadric::{Ellipsoid, Quadric};
use halfray_core::sphere::Sphere;
use halfray_core::transform::Transform;
use halfray_core::{Aabb, GeometryError};
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::sync::Arc;

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

    fn f(&self, v: &S<f32>, field: &str) -> Result<f32> {
        let x = *v.get_ref();
        if !x.is_finite() {
            return Err(self.err(&v.span(), field, format!("{x} is not a finite number")));
        }
        Ok(x)
    }

    fn positive(&self, v: &S<f32>, field: &str) -> Result<f32> {
        let x = self.f(v, field)?;
        if !(x > 0.0) {
            return Err(self.err(&v.span(), field, format!("must be > 0 (got {x})")));
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

    fn v3(&self, v: &V3, field: &str) -> Result<Vec3> {
        let a = **v.get_ref();
        if a.iter().any(|x| !x.is_finite()) {
            return Err(self.err(
                &v.span(),
                field,
                format!("{a:?} has a non-finite component"),
            ));
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
            return Err(self.err(&v.span(), field, "must be a non-zero vector"));
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
    if !(1..=crate::render::antialias::MAX_SAMPLES).contains(&samples) {
        let span = d.samples.as_ref().map(|v| v.span()).unwrap_or_default();
        return Err(ctx.err(
            &span,
            "samples",
            format!("must be 1 to {}", crate::render::antialias::MAX_SAMPLES),
        ));
    }
    let camera = camera(&ctx, &d.camera)?;

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
        let node = object(&mut ctx, o, &field, None)?;
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
    // Definitions no object uses are still checked (not read: nothing renders them).
    for (name, (_, loaded)) in &ctx.meshes {
        if loaded.is_none() {
            mesh_def(&ctx, name)?;
        }
    }
    Ok(Scene {
        path: src.path.to_path_buf(),
        camera,
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

fn camera(ctx: &Ctx<'_>, c: &S<def::CameraDef>) -> Result<Camera> {
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
    if let Some(a) = &c.aperture {
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
        let focus_distance = match &c.focus_distance {
            Some(f) => ctx.positive(f, "camera.focus_distance")?,
            None => (look_at - eye).length(),
        };
        let samples = match &c.lens_samples {
            Some(n) if *n.get_ref() == 0 || *n.get_ref() > super::MAX_LENS_SAMPLES => {
                return Err(ctx.err(
                    &n.span(),
                    "camera.lens_samples",
                    format!("must be in 1..={}", super::MAX_LENS_SAMPLES),
                ));
            }
            Some(n) => *n.get_ref(),
            None => 16,
        };
        if aperture > 0.0 {
            camera.lens = Some(super::Lens {
                aperture,
                focus_distance,
                samples,
            });
        }
    } else if let Some(f) = c.focus_distance.as_ref().or(None) {
        return Err(ctx.err(&f.span(), "camera.focus_distance", "only with `aperture`"));
    }
    Ok(camera)
}

fn light(ctx: &Ctx<'_>, i: usize, l: &S<def::LightDef>) -> Result<Light> {
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
        Some(n) if *n.get_ref() == 0 || *n.get_ref() > super::MAX_LIGHT_SAMPLES => {
            return Err(ctx.err(
                &n.span(),
                &format!("{p}.samples"),
                format!("must be in 1..={}", super::MAX_LIGHT_SAMPLES),
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

fn material(ctx: &Ctx<'_>, name: &str, m: &S<def::MaterialDef>) -> Result<Material> {
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
            "blinn-phong" => super::SpecularModel::BlinnPhong,
            "phong" => super::SpecularModel::Phong,
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

/// Fields each object type may use (besides `type`, `material`, `transform`).
fn allowed(kind: &str) -> Option<&'static [&'static str]> {
    Some(match kind {
        "sphere" => &["center", "radius"],
        "ellipsoid" => &["center", "radii"],
        "quadric" => &["coefficients", "min", "max"],
        "box" => &["min", "max"],
        "plane" => &["point", "normal"],
        "triangle" | "polygon" => &["vertices"],
        "mesh" => &["mesh"],
        "csg" => &["op", "operands"],
        _ => return None,
    })
}

fn object(ctx: &mut Ctx<'_>, o: &S<ObjectDef>, p: &str, inherited: Option<u32>) -> Result<Node> {
    let span = o.span();
    let o = o.get_ref();
    let kind = o.kind.get_ref().as_str();
    let Some(ok) = allowed(kind) else {
        return Err(ctx.err(
            &o.kind.span(),
            &format!("{p}.type"),
            format!(
                "unknown object type `{kind}` (expected sphere, ellipsoid, quadric, box, plane, triangle, polygon, mesh or csg)"
            ),
        ));
    };
    for (name, s) in o.present_fields() {
        if !ok.contains(&name) {
            return Err(ctx.err(
                &s,
                &format!("{p}.{name}"),
                format!(
                    "field `{name}` is not used by type `{kind}` (it takes: {})",
                    ok.join(", ")
                ),
            ));
        }
    }
    let material = match &o.material {
        Some(m) => *ctx.materials.get(m.get_ref()).ok_or_else(|| {
            let known: Vec<&str> = ctx.materials.keys().map(String::as_str).collect();
            ctx.err(
                &m.span(),
                &format!("{p}.material"),
                format!(
                    "no material named `{}` (defined: {})",
                    m.get_ref(),
                    list(&known)
                ),
            )
        })?,
        None => match inherited {
            Some(m) => m,
            None => {
                return Err(ctx.err(&span, &format!("{p}.material"), "missing field `material`"));
            }
        },
    };
    let transform = match &o.transform {
        Some(t) => Some(transform(ctx, t, &format!("{p}.transform"))?),
        None => None,
    };
    let f = |name: &str| format!("{p}.{name}");
    let shape = match kind {
        "sphere" => {
            let c = ctx.need(&o.center, &span, &f("center"), kind)?;
            let r = ctx.need(&o.radius, &span, &f("radius"), kind)?;
            let center = ctx.v3(c, &f("center"))?;
            let radius = ctx.positive(r, &f("radius"))?;
            Shape::Sphere(
                Sphere::new(center, radius)
                    .map_err(|e| ctx.err(&r.span(), &f("radius"), e.to_string()))?,
            )
        }
        "ellipsoid" => {
            let c = ctx.need(&o.center, &span, &f("center"), kind)?;
            let r = ctx.need(&o.radii, &span, &f("radii"), kind)?;
            let radii = ctx.v3(r, &f("radii"))?;
            if !(radii.min_element() > 0.0) {
                return Err(ctx.err(&r.span(), &f("radii"), "every radius must be > 0"));
            }
            let center = ctx.v3(c, &f("center"))?;
            Shape::Ellipsoid(
                Ellipsoid::new(center, radii)
                    .map_err(|e| ctx.err(&r.span(), &f("radii"), e.to_string()))?,
            )
        }
        "quadric" => {
            let q = ctx.need(&o.coefficients, &span, &f("coefficients"), kind)?;
            let qd = q.get_ref();
            let g = |v: &Option<S<f32>>, n: &str| -> Result<f64> {
                v.as_ref().map_or(Ok(0.0), |x| {
                    ctx.f(x, &f(&format!("coefficients.{n}"))).map(f64::from)
                })
            };
            let (xy, xz, yz) = (
                g(&qd.xy, "xy")? / 2.0,
                g(&qd.xz, "xz")? / 2.0,
                g(&qd.yz, "yz")? / 2.0,
            );
            // The core's form is xᵀAx + 2bᵀx + c.
            let a = DMat3::from_cols(
                DVec3::new(g(&qd.xx, "xx")?, xy, xz),
                DVec3::new(xy, g(&qd.yy, "yy")?, yz),
                DVec3::new(xz, yz, g(&qd.zz, "zz")?),
            );
            let b = DVec3::new(g(&qd.x, "x")?, g(&qd.y, "y")?, g(&qd.z, "z")?) / 2.0;
            let quadric = Quadric::new(a, b, g(&qd.c, "c")?).map_err(|e| match e {
                GeometryError::Degenerate => ctx.err(
                    &q.span(),
                    &f("coefficients"),
                    "all quadratic and linear coefficients are 0",
                ),
                other => ctx.err(&q.span(), &f("coefficients"), other.to_string()),
            })?;
            let clip = match (&o.min, &o.max) {
                (Some(lo), Some(hi)) => Some(box_of(ctx, lo, hi, p)?),
                (None, None) => None,
                (Some(s), None) | (None, Some(s)) => {
                    return Err(ctx.err(
                        &s.span(),
                        &f("min"),
                        "a clip box needs both `min` and `max`",
                    ));
                }
            };
            Shape::Quadric(ClippedQuadric { quadric, clip })
        }
        "box" => {
            let lo = ctx.need(&o.min, &span, &f("min"), kind)?;
            let hi = ctx.need(&o.max, &span, &f("max"), kind)?;
            Shape::Box(box_of(ctx, lo, hi, p)?)
        }
        "plane" => {
            let pt = ctx.need(&o.point, &span, &f("point"), kind)?;
            let n = ctx.need(&o.normal, &span, &f("normal"), kind)?;
            let point = ctx.v3(pt, &f("point"))?;
            let normal = ctx.dir(n, &f("normal"))?;
            Shape::Plane(
                Plane::new(point, normal)
                    .map_err(|e| ctx.err(&n.span(), &f("normal"), e.to_string()))?,
            )
        }
        "triangle" | "polygon" => {
            let vs = ctx.need(&o.vertices, &span, &f("vertices"), kind)?;
            let pts: Vec<Vec3> = vs.get_ref().iter().map(|a| Vec3::from_array(**a)).collect();
            if pts.iter().any(|v| !v.is_finite()) {
                return Err(ctx.err(
                    &vs.span(),
                    &f("vertices"),
                    "a vertex has a non-finite coordinate",
                ));
            }
            if kind == "triangle" {
                let [a, b, c] = pts[..] else {
                    return Err(ctx.err(
                        &vs.span(),
                        &f("vertices"),
                        format!("a triangle needs 3 vertices, got {}", pts.len()),
                    ));
                };
                if (b - a).cross(c - a) == Vec3::ZERO {
                    return Err(ctx.err(
                        &vs.span(),
                        &f("vertices"),
                        "degenerate triangle (zero area)",
                    ));
                }
                Shape::Triangle([a, b, c])
            } else {
                Shape::Polygon(Box::new(polygon(ctx, pts, &vs.span(), &f("vertices"))?))
            }
        }
        "mesh" => {
            let m = ctx.need(&o.mesh, &span, &f("mesh"), kind)?;
            Shape::Mesh(mesh(ctx, m, &f("mesh"))?)
        }
        "csg" => {
            let op = ctx.need(&o.op, &span, &f("op"), kind)?;
            let op_v = match op.get_ref().as_str() {
                "union" => CsgOp::Union,
                "intersection" => CsgOp::Intersection,
                "difference" => CsgOp::Difference,
                other => {
                    return Err(ctx.err(
                        &op.span(),
                        &f("op"),
                        format!("unknown CSG operation `{other}` (expected union, intersection or difference)"),
                    ));
                }
            };
            let ops = ctx.need(&o.operands, &span, &f("operands"), kind)?;
            if ops.get_ref().len() != 2 {
                return Err(ctx.err(
                    &ops.span(),
                    &f("operands"),
                    format!(
                        "a CSG object needs exactly 2 operands, got {} (nest CSG objects for more)",
                        ops.get_ref().len()
                    ),
                ));
            }
            let mut nodes = Vec::new();
            for (k, od) in ops.get_ref().iter().enumerate() {
                let fp = format!("{p}.operands[{k}]");
                if let Some(r) = &od.get_ref().repeat {
                    return Err(ctx.err(
                        &r.span(),
                        &format!("{fp}.repeat"),
                        "`repeat` is for top-level objects, not CSG operands",
                    ));
                }
                let n = object(ctx, od, &fp, Some(material))?;
                if !n.shape.is_solid() {
                    let why = match &n.shape {
                        Shape::Mesh(m) => format!(
                            "mesh `{}` is not closed ({} boundary or unpaired edges): a CSG operand must bound a solid",
                            m.name, m.boundary_edges
                        ),
                        Shape::Quadric(_) => {
                            "a clipped quadric is not closed: a CSG operand must bound a solid"
                                .to_string()
                        }
                        _ => format!(
                            "a {} is not closed: a CSG operand must bound a solid",
                            od.get_ref().kind.get_ref()
                        ),
                    };
                    return Err(ctx.err(&od.get_ref().kind.span(), &fp, why));
                }
                nodes.push(n);
            }
            let b = nodes.pop().map(Box::new);
            let a = nodes.pop().map(Box::new);
            match (a, b) {
                (Some(a), Some(b)) => Shape::Csg(op_v, a, b),
                _ => unreachable!("checked: two operands"),
            }
        }
        _ => unreachable!("checked by `allowed`"),
    };
    Ok(Node::new(shape, material, transform))
}

/// Most objects a scene may hold, repeated copies included: 10⁶ (a copy costs a few hundred
/// bytes and one top-level BVH leaf; a mesh's triangles are shared by its copies).
pub const MAX_OBJECTS: usize = 1_000_000;

/// The copies `repeat` makes of `node` (object `p`): copy `(i, j, k)`, numbered
/// `i + nx·(j + ny·k)`, is `node` moved by `(i·dx, j·dy, k·dz)` after its own transform, with
/// material `materials[number mod len]` when given. `before` objects exist already (for
/// [`MAX_OBJECTS`]).
fn repeat(
    ctx: &Ctx<'_>,
    node: &Node,
    r: &S<def::RepeatDef>,
    p: &str,
    before: usize,
) -> Result<Vec<Node>> {
    let rd = r.get_ref();
    let f = |name: &str| format!("{p}.repeat.{name}");
    let [nx, ny, nz] = rd.count.get_ref().0;
    let total = u64::from(nx) * u64::from(ny) * u64::from(nz);
    if total == 0 {
        return Err(ctx.err(&rd.count.span(), &f("count"), "every count must be ≥ 1"));
    }
    if total + before as u64 > MAX_OBJECTS as u64 {
        return Err(ctx.err(
            &rd.count.span(),
            &f("count"),
            format!("{total} copies: more than {MAX_OBJECTS} objects in the scene"),
        ));
    }
    let step = ctx.v3(&rd.step, &f("step"))?;
    let materials = match &rd.materials {
        None => vec![node.material],
        Some(names) if names.get_ref().is_empty() => {
            return Err(ctx.err(
                &names.span(),
                &f("materials"),
                "must name at least one material",
            ));
        }
        Some(names) => names
            .get_ref()
            .iter()
            .map(|m| {
                ctx.materials.get(m.get_ref()).copied().ok_or_else(|| {
                    let known: Vec<&str> = ctx.materials.keys().map(String::as_str).collect();
                    ctx.err(
                        &m.span(),
                        &f("materials"),
                        format!(
                            "no material named `{}` (defined: {})",
                            m.get_ref(),
                            list(&known)
                        ),
                    )
                })
            })
            .collect::<Result<Vec<u32>>>()?,
    };
    let mut out = Vec::with_capacity(total as usize);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let offset = step * Vec3::new(i as f32, j as f32, k as f32);
                let moved = Transform::translate(offset)
                    .and_then(|t| match &node.transform {
                        Some(own) => own.then(&t),
                        None => Ok(t),
                    })
                    .map_err(|e| ctx.err(&rd.step.span(), &f("step"), e.to_string()))?;
                let material = materials[out.len() % materials.len()];
                out.push(Node::new(node.shape.clone(), material, Some(moved)));
            }
        }
    }
    Ok(out)
}

fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

fn box_of(ctx: &Ctx<'_>, lo: &V3, hi: &V3, p: &str) -> Result<Aabb> {
    let a = ctx.v3(lo, &format!("{p}.min"))?;
    let b = ctx.v3(hi, &format!("{p}.max"))?;
    if !(a.cmplt(b).all()) {
        return Err(ctx.err(
            &hi.span(),
            &format!("{p}.max"),
            "must be > `min` on every axis",
        ));
    }
    Ok(Aabb::new(a, b))
}

fn polygon(ctx: &Ctx<'_>, pts: Vec<Vec3>, span: &Span, field: &str) -> Result<Polygon> {
    Polygon::new(&pts).map_err(|e| {
        let msg = match e {
            GeometryError::VertexCount => format!(
                "a polygon needs 3 to {POLYGON_MAX_VERTICES} vertices, got {}",
                pts.len()
            ),
            GeometryError::NonPlanar => {
                "polygon is not planar (a vertex is farther than 1e-5 × its size from the plane)"
                    .to_string()
            }
            GeometryError::Degenerate => "degenerate polygon (zero area)".to_string(),
            other => other.to_string(),
        };
        ctx.err(span, field, msg)
    })
}

/// A checked `[mesh.NAME]`: the file's path, the smoothing `(step, iterations)` and the
/// subdivision levels.
/// A mesh's file, Laplacian smoothing `(step, iterations)`, Loop levels and smooth shading.
type MeshSettings = (std::path::PathBuf, Option<(f32, u32)>, u32, bool);

/// Checks `[mesh.NAME]` without reading the file: it exists and is a file, the smoothing and
/// subdivision settings are in range. Returns the path, the smoothing `(step, iterations)` and
/// the subdivision levels. Run for every mesh definition, used or not.
fn mesh_def(ctx: &Ctx<'_>, name: &str) -> Result<MeshSettings> {
    let Some(def) = ctx.mesh_defs.get(name).map(|d| d.get_ref()) else {
        return Err(Error::Other(format!("no mesh named `{name}`")));
    };
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
                def.file.get_ref(),
                path.display()
            ),
        ));
    }
    if !path.is_file() {
        return Err(ctx.err(
            &def.file.span(),
            &format!("{p}.file"),
            format!(
                "mesh file `{}` not found (looked for {})",
                def.file.get_ref(),
                path.display()
            ),
        ));
    }
    let smoothing = match &def.smooth {
        Some(s) => {
            let sd = s.get_ref();
            let step = ctx.f(&sd.step, &format!("{p}.smooth.step"))?;
            if *sd.iterations.get_ref() > super::MAX_SMOOTH_ITERATIONS {
                return Err(ctx.err(
                    &sd.iterations.span(),
                    &format!("{p}.smooth.iterations"),
                    format!("at most {} iterations", super::MAX_SMOOTH_ITERATIONS),
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

fn mesh(ctx: &mut Ctx<'_>, name: &S<String>, field: &str) -> Result<Arc<MeshShape>> {
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
    let (path, smoothing, levels, smooth_shading) = mesh_def(ctx, name.get_ref())?;
    let def = ctx.mesh_defs[name.get_ref()].get_ref();
    let p = format!("mesh.{}", name.get_ref());
    let shape = super::load_mesh(name.get_ref(), &path, smoothing, levels, smooth_shading)
        .map_err(|e| match e {
            Error::Input { at, message } if at.line.is_none() => ctx.err(
                &def.file.span(),
                &format!("{p}.file"),
                format!("{}: {message}", at.file.display()),
            ),
            other => other,
        })?;
    let shape = Arc::new(shape);
    ctx.loaded.push(shape.clone());
    ctx.mesh_files.push(path);
    if let Some(entry) = ctx.meshes.get_mut(name.get_ref()) {
        entry.1 = Some(shape.clone());
    }
    Ok(shape)
}

fn transform(ctx: &Ctx<'_>, t: &S<Vec<S<def::TransformDef>>>, p: &str) -> Result<Transform> {
    let mut m = Mat4::IDENTITY;
    for (k, step) in t.get_ref().iter().enumerate() {
        let f = format!("{p}[{k}]");
        let s = step.get_ref();
        let set = usize::from(s.translate.is_some())
            + usize::from(s.rotate.is_some())
            + usize::from(s.scale.is_some())
            + usize::from(s.matrix.is_some());
        if set != 1 {
            return Err(ctx.err(
                &step.span(),
                &f,
                "each transform step needs exactly one of `translate`, `rotate`, `scale`, `matrix`",
            ));
        }
        let (step_m, span, name) = if let Some(v) = &s.translate {
            (
                Mat4::from_translation(ctx.v3(v, &format!("{f}.translate"))?),
                v.span(),
                "translate",
            )
        } else if let Some(r) = &s.rotate {
            let rd = r.get_ref();
            let axis = ctx.v3(&rd.axis, &format!("{f}.rotate.axis"))?;
            let deg = ctx.f(&rd.degrees, &format!("{f}.rotate.degrees"))?;
            let rm = xform::rotation(axis, deg).ok_or_else(|| {
                ctx.err(
                    &rd.axis.span(),
                    &format!("{f}.rotate.axis"),
                    "must be a non-zero vector",
                )
            })?;
            (rm, r.span(), "rotate")
        } else if let Some(sc) = &s.scale {
            let v = Vec3::from_array(sc.get_ref().0);
            if !v.is_finite() {
                return Err(ctx.err(&sc.span(), &format!("{f}.scale"), "non-finite scale"));
            }
            (Mat4::from_scale(v), sc.span(), "scale")
        } else if let Some(mx) = &s.matrix {
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
        } else {
            unreachable!("exactly one is set")
        };
        // Check each step, so the error points at the step that is singular.
        Transform::new(step_m)
            .map_err(|e| ctx.err(&span, &format!("{f}.{name}"), e.to_string()))?;
        m = step_m * m;
    }
    Transform::new(m).map_err(|e| ctx.err(&t.span(), p, e.to_string()))
}
