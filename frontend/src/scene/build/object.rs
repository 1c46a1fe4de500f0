//! `[[object]]`: the object types, their fields and CSG operands.

use crate::error::Result;
use crate::scene::MAX_CSG_NESTING;
use crate::scene::def::{ObjectDef, S, V3};
use crate::scene::geom::{ClippedQuadric, CsgOp, Geometry, Node, POLYGON_MAX_VERTICES, Polygon};
use glam::{DMat3, DVec3, Vec3};
use halfray_core::plane::Plane;
use halfray_core::quadric::{Ellipsoid, Quadric};
use halfray_core::sphere::Sphere;
use halfray_core::tolerance::PLANARITY_REL;
use halfray_core::{Aabb, GeometryError};

use super::mesh_ref::mesh;
use super::transform::transform;
use super::{Ctx, Span, list};

/// The object types of `[[object]]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Sphere,
    Ellipsoid,
    Quadric,
    Box,
    Plane,
    Triangle,
    Polygon,
    Mesh,
    Csg,
}

impl Kind {
    /// Every type with its name in a scene file.
    const ALL: [(&'static str, Kind); 9] = [
        ("sphere", Kind::Sphere),
        ("ellipsoid", Kind::Ellipsoid),
        ("quadric", Kind::Quadric),
        ("box", Kind::Box),
        ("plane", Kind::Plane),
        ("triangle", Kind::Triangle),
        ("polygon", Kind::Polygon),
        ("mesh", Kind::Mesh),
        ("csg", Kind::Csg),
    ];

    /// The type named `name`, if any.
    fn parse(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(n, _)| *n == name).map(|&(_, k)| k)
    }

    /// Fields the type may use (besides `type`, `material`, `transform`).
    fn fields(self) -> &'static [&'static str] {
        match self {
            Kind::Sphere => &["center", "radius"],
            Kind::Ellipsoid => &["center", "radii"],
            Kind::Quadric => &["coefficients", "min", "max"],
            Kind::Box => &["min", "max"],
            Kind::Plane => &["point", "normal"],
            Kind::Triangle | Kind::Polygon => &["vertices"],
            Kind::Mesh => &["mesh"],
            Kind::Csg => &["op", "operands"],
        }
    }
}

/// One object (`p` its field path, `inherited` the material of an enclosing CSG object,
/// `depth` the number of CSG objects it is an operand in: 0 at the top level): its type and
/// fields checked, its shape built by the type's function. A CSG object at level
/// `depth + 1` beyond [`MAX_CSG_NESTING`] is an input error at its `type`.
pub(super) fn object(
    ctx: &mut Ctx<'_>,
    o: &S<ObjectDef>,
    p: &str,
    inherited: Option<u32>,
    depth: usize,
) -> Result<Node> {
    let span = o.span();
    let o = o.get_ref();
    let name = o.kind.get_ref().as_str();
    let Some(kind) = Kind::parse(name) else {
        return Err(ctx.err(
            &o.kind.span(),
            &format!("{p}.type"),
            format!(
                "unknown object type `{name}` (expected sphere, ellipsoid, quadric, box, plane, triangle, polygon, mesh or csg)"
            ),
        ));
    };
    if kind == Kind::Csg && depth >= MAX_CSG_NESTING {
        return Err(ctx.err(
            &o.kind.span(),
            p,
            format!(
                "CSG nests deeper than {MAX_CSG_NESTING} levels (the top-level object included; scene::MAX_CSG_NESTING)"
            ),
        ));
    }
    let ok = kind.fields();
    for (field, s) in o.present_fields() {
        if !ok.contains(&field) {
            return Err(ctx.err(
                &s,
                &format!("{p}.{field}"),
                format!(
                    "field `{field}` is not used by type `{name}` (it takes: {})",
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
    let at = At {
        span: &span,
        p,
        kind: name,
    };
    let shape = match kind {
        Kind::Sphere => sphere(ctx, o, &at)?,
        Kind::Ellipsoid => ellipsoid(ctx, o, &at)?,
        Kind::Quadric => quadric(ctx, o, &at)?,
        Kind::Box => {
            let lo = ctx.need(&o.min, &span, &at.f("min"), name)?;
            let hi = ctx.need(&o.max, &span, &at.f("max"), name)?;
            Geometry::Box(box_of(ctx, lo, hi, p)?)
        }
        Kind::Plane => plane(ctx, o, &at)?,
        Kind::Triangle | Kind::Polygon => vertices(ctx, o, &at, kind == Kind::Triangle)?,
        Kind::Mesh => {
            let m = ctx.need(&o.mesh, &span, &at.f("mesh"), name)?;
            Geometry::Mesh(mesh(ctx, m, &at.f("mesh"))?)
        }
        Kind::Csg => csg(ctx, o, &at, material, depth)?,
    };
    let mut node = Node::new(shape, material, transform);
    node.inherits_material = o.material.is_none();
    Ok(node)
}

/// Where an object's fields are reported: its span, field path and type name.
struct At<'a> {
    span: &'a Span,
    p: &'a str,
    kind: &'a str,
}

impl At<'_> {
    /// The path of field `name`.
    fn f(&self, name: &str) -> String {
        format!("{}.{name}", self.p)
    }
}

fn sphere(ctx: &Ctx<'_>, o: &ObjectDef, at: &At<'_>) -> Result<Geometry> {
    let (span, kind, f) = (at.span, at.kind, |n: &str| at.f(n));
    let c = ctx.need(&o.center, span, &f("center"), kind)?;
    let r = ctx.need(&o.radius, span, &f("radius"), kind)?;
    let center = ctx.v3(c, &f("center"))?;
    let radius = ctx.positive(r, &f("radius"))?;
    Ok(Geometry::Sphere(Sphere::new(center, radius).map_err(
        |e| ctx.err(&r.span(), &f("radius"), e.to_string()),
    )?))
}

fn ellipsoid(ctx: &Ctx<'_>, o: &ObjectDef, at: &At<'_>) -> Result<Geometry> {
    let (span, kind, f) = (at.span, at.kind, |n: &str| at.f(n));
    let c = ctx.need(&o.center, span, &f("center"), kind)?;
    let r = ctx.need(&o.radii, span, &f("radii"), kind)?;
    let radii = ctx.v3(r, &f("radii"))?;
    if !(radii.min_element() > 0.0) {
        return Err(ctx.err(&r.span(), &f("radii"), "every radius must be > 0"));
    }
    let center = ctx.v3(c, &f("center"))?;
    Ok(Geometry::Ellipsoid(Ellipsoid::new(center, radii).map_err(
        |e| ctx.err(&r.span(), &f("radii"), e.to_string()),
    )?))
}

fn quadric(ctx: &Ctx<'_>, o: &ObjectDef, at: &At<'_>) -> Result<Geometry> {
    let (span, kind, p, f) = (at.span, at.kind, at.p, |n: &str| at.f(n));
    let q = ctx.need(&o.coefficients, span, &f("coefficients"), kind)?;
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
        // Named at the one given, which the message says the other is missing from.
        (Some(s), None) => {
            return Err(ctx.err(
                &s.span(),
                &f("min"),
                "a clip box needs both `min` and `max`: `max` is missing",
            ));
        }
        (None, Some(s)) => {
            return Err(ctx.err(
                &s.span(),
                &f("max"),
                "a clip box needs both `min` and `max`: `min` is missing",
            ));
        }
    };
    Ok(Geometry::Quadric(ClippedQuadric { quadric, clip }))
}

fn plane(ctx: &Ctx<'_>, o: &ObjectDef, at: &At<'_>) -> Result<Geometry> {
    let (span, kind, f) = (at.span, at.kind, |n: &str| at.f(n));
    let pt = ctx.need(&o.point, span, &f("point"), kind)?;
    let n = ctx.need(&o.normal, span, &f("normal"), kind)?;
    let point = ctx.v3(pt, &f("point"))?;
    let normal = ctx.dir(n, &f("normal"))?;
    Ok(Geometry::Plane(Plane::new(point, normal).map_err(|e| {
        ctx.err(&n.span(), &f("normal"), e.to_string())
    })?))
}

/// A triangle (`triangle`) or a polygon from `vertices`.
fn vertices(ctx: &Ctx<'_>, o: &ObjectDef, at: &At<'_>, triangle: bool) -> Result<Geometry> {
    let (span, kind, f) = (at.span, at.kind, |n: &str| at.f(n));
    let vs = ctx.need(&o.vertices, span, &f("vertices"), kind)?;
    let pts = vs
        .get_ref()
        .iter()
        .enumerate()
        .map(|(i, v)| ctx.v3(v, &format!("{}[{i}]", f("vertices"))))
        .collect::<Result<Vec<Vec3>>>()?;
    if triangle {
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
        Ok(Geometry::Triangle([a, b, c]))
    } else {
        Ok(Geometry::Polygon(Box::new(polygon(
            ctx,
            pts,
            &vs.span(),
            &f("vertices"),
        )?)))
    }
}

/// A CSG object (inside `depth` others): its operation and its two solid operands (which
/// inherit `material`).
fn csg(
    ctx: &mut Ctx<'_>,
    o: &ObjectDef,
    at: &At<'_>,
    material: u32,
    depth: usize,
) -> Result<Geometry> {
    let (span, kind, p, f) = (at.span, at.kind, at.p, |n: &str| at.f(n));
    let op = ctx.need(&o.op, span, &f("op"), kind)?;
    let op_v = match op.get_ref().as_str() {
        "union" => CsgOp::Union,
        "intersection" => CsgOp::Intersection,
        "difference" => CsgOp::Difference,
        other => {
            return Err(ctx.err(
                &op.span(),
                &f("op"),
                format!(
                    "unknown CSG operation `{other}` (expected union, intersection or difference)"
                ),
            ));
        }
    };
    let ops = ctx.need(&o.operands, span, &f("operands"), kind)?;
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
        let n = object(ctx, od, &fp, Some(material), depth + 1)?;
        if !n.shape.is_solid() {
            let why = match &n.shape {
                Geometry::Mesh(m) => format!(
                    "mesh `{}` is not closed ({} boundary or unpaired edges): a CSG operand must bound a solid",
                    m.name,
                    m.boundary_edges()
                ),
                Geometry::Quadric(_) => {
                    "a clipped quadric is not closed: a CSG operand must bound a solid".to_string()
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
    let [a, b]: [Node; 2] = nodes.try_into().map_err(|_| {
        ctx.err(
            &ops.span(),
            &f("operands"),
            "a CSG object needs exactly 2 operands",
        )
    })?;
    Ok(Geometry::Csg(op_v, Box::new(a), Box::new(b)))
}

pub(super) fn box_of(ctx: &Ctx<'_>, lo: &V3, hi: &V3, p: &str) -> Result<Aabb> {
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

pub(super) fn polygon(ctx: &Ctx<'_>, pts: Vec<Vec3>, span: &Span, field: &str) -> Result<Polygon> {
    Polygon::new(&pts).map_err(|e| {
        let msg = match e {
            GeometryError::VertexCount => format!(
                "a polygon needs 3 to {POLYGON_MAX_VERTICES} vertices, got {}",
                pts.len()
            ),
            GeometryError::NonPlanar => format!(
                "polygon is not planar (a vertex is farther than {PLANARITY_REL:e} × its size from the plane)"
            ),
            GeometryError::Degenerate => "degenerate polygon (zero area)".to_string(),
            other => other.to_string(),
        };
        ctx.err(span, field, msg)
    })
}

#[cfg(test)]
mod tests {
    use crate::scene::geom::Geometry;
    use glam::DVec3;
    use std::path::Path;

    /// Relative agreement of the core's quadric evaluation with the polynomial, of
    /// `F(p) + 1` (`F` = `Quadric::eval_abs`, the sum of the terms' magnitudes): the
    /// evaluation's own bound is `γ₁₀·F ≈ 1.1e-15·F`, the centring of the form rounds the
    /// coefficients by a few ulps more; `1e-12` leaves room for both, and a wrong coefficient
    /// (a factor of 2 or 4 on a term) moves the value by far more at these points.
    const EVAL_AGREEMENT: f64 = 1e-12;

    /// A bad component of a vector written over several lines, and a bad vertex of a polygon,
    /// are reported at their own line and column and named by index (`center[2]`,
    /// `vertices[3][1]`), not at the array's start.
    #[test]
    fn a_bad_array_element_is_reported_at_its_place() {
        let head = "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\n\
                    height = 6\n\n[material.m]\n\n[[object]]\nmaterial = \"m\"\n";
        let err = |body: &str| {
            crate::scene::parse(&format!("{head}{body}"), Path::new("s.toml"))
                .err()
                .map(|e| e.to_string())
        };
        assert_eq!(
            err("type = \"sphere\"\nradius = 1\ncenter = [0,\n 0,\n 1e39]\n").as_deref(),
            Some(
                "s.toml:16:2: field `object[0].center[2]`: 1e39 is beyond the largest `f32` \
                 (±3.4e38)"
            )
        );
        assert_eq!(
            err(
                "type = \"polygon\"\nvertices = [\n [0, 0, 0],\n [1, 0, 0],\n [1, 1, 0],\n \
                 [0, nan, 0],\n]\n"
            )
            .as_deref(),
            Some("s.toml:17:6: field `object[0].vertices[3][1]`: NaN is not a finite number")
        );
    }

    /// CSG nests inline as deep as the TOML reader reads nested values:
    /// [`crate::scene::MAX_CSG_NESTING`] levels, the object's own included
    /// (`scenes/README.md`); one more is an input error at the file and line where the reader
    /// stopped, not a crash.
    #[test]
    fn csg_nests_to_the_documented_depth() {
        let scene = |levels: usize| {
            let mut s = String::from("{ type = \"sphere\", center = [0, 0, 0], radius = 1 }");
            for i in 0..levels {
                s = format!(
                    "{{ type = \"csg\", op = \"union\", operands = [{s}, {{ type = \"sphere\", center = [0, 0, {i}], radius = 1 }}] }}"
                );
            }
            let inner = s
                .strip_prefix("{ type = \"csg\", op = \"union\", operands = ")
                .and_then(|r| r.strip_suffix(" }"))
                .unwrap();
            format!(
                "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
                 [material.m]\ndiffuse = [1, 1, 1]\n\n[[object]]\ntype = \"csg\"\nop = \"union\"\n\
                 material = \"m\"\noperands = {inner}\n"
            )
        };
        use crate::scene::MAX_CSG_NESTING;
        let deepest = crate::scene::parse(&scene(MAX_CSG_NESTING), Path::new("c.toml"));
        assert!(deepest.is_ok(), "{:?}", deepest.err());
        let deeper = scene(MAX_CSG_NESTING + 1);
        let line = 1 + deeper
            .lines()
            .position(|l| l.starts_with("operands = "))
            .unwrap();
        let e = crate::scene::parse(&deeper, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("c.toml:{line}:")), "{e}");
    }

    /// CSG written with table headers (`[[object.operands]]`, `[[object.operands.operands]]`,
    /// …), which the TOML reader reads far deeper, nests to the same
    /// [`crate::scene::MAX_CSG_NESTING`] levels: one more is an input error at the `type` of
    /// the first CSG operand past the limit, naming its field and the limit.
    #[test]
    fn csg_in_table_headers_nests_to_the_same_depth() {
        // `levels` CSG objects, each the first operand of the one before, with a sphere as
        // each one's second operand and two spheres in the deepest.
        let scene = |levels: usize| {
            let mut s = String::from(
                "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
                 [material.m]\ndiffuse = [1, 1, 1]\n\n[[object]]\ntype = \"csg\"\nop = \"union\"\n\
                 material = \"m\"\n",
            );
            let sphere = "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
            let mut h = String::from("object");
            let mut seconds = Vec::new();
            for _ in 1..levels {
                h.push_str(".operands");
                s.push_str(&format!("[[{h}]]\ntype = \"csg\"\nop = \"union\"\n"));
                seconds.push(h.clone());
            }
            h.push_str(".operands");
            s.push_str(&format!("[[{h}]]\n{sphere}[[{h}]]\n{sphere}"));
            // The second operands, innermost first: a header after a deeper one goes back up.
            for h in seconds.iter().rev() {
                s.push_str(&format!("[[{h}]]\n{sphere}"));
            }
            s
        };
        use crate::scene::MAX_CSG_NESTING;
        let deepest = crate::scene::parse(&scene(MAX_CSG_NESTING), Path::new("c.toml"));
        assert!(deepest.is_ok(), "{:?}", deepest.err());
        let deeper = scene(MAX_CSG_NESTING + 1);
        // The `type = "csg"` after the header of the 40th level (the 39th operands header).
        let header = format!("[[object{}]]", ".operands".repeat(MAX_CSG_NESTING));
        let line = 2 + deeper.lines().position(|l| l == header).unwrap();
        let field = format!("object[0]{}", ".operands[0]".repeat(MAX_CSG_NESTING));
        let e = crate::scene::parse(&deeper, Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            format!(
                "c.toml:{line}:8: field `{field}`: CSG nests deeper than 39 levels (the top-level object included; scene::MAX_CSG_NESTING)"
            )
        );
    }

    /// A `quadric` object is the surface its coefficients write (`scenes/README.md`):
    /// `xx·x² + yy·y² + zz·z² + xy·xy + xz·xz + yz·yz + x·x + y·y + z·z + c`, every
    /// coefficient set, evaluated at a few points against that polynomial (the core's form
    /// halves the cross and linear terms), within [`EVAL_AGREEMENT`].
    #[test]
    fn a_quadric_is_the_polynomial_its_coefficients_write() {
        let text = "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
            [material.m]\ndiffuse = [1, 1, 1]\n\n[[object]]\ntype = \"quadric\"\nmaterial = \"m\"\n\
            coefficients = { xx = 1, yy = 2, zz = 3, xy = 0.5, xz = -0.25, yz = 0.75, x = -4, y = 1, z = 2, c = -3 }\n";
        let scene = crate::scene::parse(text, Path::new("q.toml")).unwrap();
        let Some(Geometry::Quadric(q)) = scene.objects.first().map(|o| &o.shape) else {
            panic!("one quadric object");
        };
        let poly = |p: DVec3| {
            let (x, y, z) = (p.x, p.y, p.z);
            x * x + 2.0 * y * y + 3.0 * z * z + 0.5 * x * y - 0.25 * x * z + 0.75 * y * z - 4.0 * x
                + y
                + 2.0 * z
                - 3.0
        };
        for p in [
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, -2.0, 0.5),
            DVec3::new(3.0, 1.5, -1.0),
            DVec3::new(-0.7, 0.2, 2.0),
        ] {
            let (got, want) = (q.quadric.eval(p), poly(p));
            let tol = EVAL_AGREEMENT * (q.quadric.eval_abs(p) + 1.0);
            assert!((got - want).abs() <= tol, "{p}: {got} against {want}");
        }
    }
}
