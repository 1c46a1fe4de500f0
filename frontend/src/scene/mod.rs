//! Scene files: TOML (documented in `scenes/README.md`), parsed with serde into spanned
//! definitions ([`def`]), then checked and turned into a render-ready [`Scene`] (`build`).
//!
//! Every error names the file, line, column and field (for example
//! `scene.toml:12:10: field object[2].radius: must be > 0`), and none panics.

mod build;
pub mod def;
pub mod geom;
mod mesh;
pub mod top;
pub mod xform;

use crate::error::{Error, Location, Result};
use geom::{MeshShape, Node};
use glam::Vec3;
use halfray_core::Ray;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use geom::boundary_edge_count;
pub use mesh::{MeshField, load_mesh};

/// Most samples per pixel a scene's `samples` or `--samples` may ask for.
pub const MAX_SAMPLES: u32 = 64;

/// Default recursion depth when the scene does not give `max_depth`.
pub const DEFAULT_MAX_DEPTH: u32 = 5;
/// Largest accepted image side, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// Deepest CSG a scene can write, in levels of `csg` objects, the top-level object included,
/// whether operands are inline tables or `[[object.operands]]` table headers: a CSG operand
/// deeper is an input error at its `type`. It is the TOML reader's own limit of nested inline
/// values (which stops inline operands at this depth first), so both forms share it; not a
/// limit of the renderer's.
pub const MAX_CSG_NESTING: usize = 39;

/// Most Laplacian smoothing steps a mesh may ask for: each is a pass over every vertex, and
/// far fewer already flatten any mesh (a bound keeps a typo from hanging the loader).
pub const MAX_SMOOTH_ITERATIONS: u32 = 10_000;

/// Camera projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with a vertical field of view in degrees.
    Perspective {
        /// Vertical field of view, degrees.
        fov: f32,
    },
    /// Orthographic with the view's vertical extent in world units.
    Orthographic {
        /// Height of the view, world units.
        view_size: f32,
    },
}

/// A pinhole or orthographic camera; pixel `(i, j)` (column, row from the top) is sampled at
/// its centre `(i + ½, j + ½)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit right vector.
    pub right: Vec3,
    /// Unit up vector (orthogonal to `forward`).
    pub up: Vec3,
    /// Projection.
    pub projection: Projection,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Thin lens for depth of field (perspective only); `None`: a pinhole.
    pub lens: Option<Lens>,
}

/// A thin lens: points at `focus_distance` along the view direction are sharp, others blur
/// in proportion to `aperture`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Lens radius, world units (> 0).
    pub aperture: f32,
    /// Distance of the plane in focus from the eye along the view direction, world units.
    pub focus_distance: f32,
    /// Rays per pixel, each through its own lens and sub-pixel position.
    pub samples: u32,
}

/// Most `lens_samples` a camera may ask for.
pub const MAX_LENS_SAMPLES: u32 = 256;

impl Camera {
    /// Builds the camera frame; `None` when `look_at − eye` is zero or parallel to `up`.
    pub fn new(
        eye: Vec3,
        look_at: Vec3,
        up: Vec3,
        projection: Projection,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let forward = (look_at - eye).normalize_or_zero();
        let right = forward.cross(up).normalize_or_zero();
        if forward == Vec3::ZERO || right == Vec3::ZERO || !right.is_finite() {
            return None;
        }
        Some(Self {
            eye,
            forward,
            right,
            up: right.cross(forward),
            projection,
            width,
            height,
            lens: None,
        })
    }

    /// The ray through image position `(x, y)` (as [`Camera::ray_at`]) and lens position
    /// `(lu, lv)` in the unit square, mapped to the lens disk (concentric mapping): the ray
    /// starts on the lens and passes through the point of the pinhole ray on the plane in
    /// focus. Without a lens, or for `(lu, lv)` at the disk's centre `(½, ½)`, the pinhole ray.
    pub fn ray_through_lens(&self, x: f32, y: f32, lu: f32, lv: f32) -> Ray {
        let pin = self.ray_at(x, y);
        let Some(lens) = self.lens else {
            return pin;
        };
        let (a, b) = (2.0 * lu - 1.0, 2.0 * lv - 1.0);
        let (r, phi) = if a == 0.0 && b == 0.0 {
            (0.0, 0.0)
        } else if a.abs() > b.abs() {
            (a, std::f32::consts::FRAC_PI_4 * (b / a))
        } else {
            (
                b,
                std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
            )
        };
        let offset = (self.right * phi.cos() + self.up * phi.sin()) * (r * lens.aperture);
        // The pinhole direction has unit component along `forward`.
        let focus = pin.origin + pin.direction * lens.focus_distance;
        let origin = pin.origin + offset;
        Ray::new(origin, focus - origin)
    }

    /// Half extents of the image plane (at distance 1 for perspective).
    fn half_extents(&self) -> (f32, f32) {
        let half_h = match self.projection {
            Projection::Perspective { fov } => (fov.to_radians() * 0.5).tan(),
            Projection::Orthographic { view_size } => view_size * 0.5,
        };
        (half_h * self.width as f32 / self.height as f32, half_h)
    }

    /// The ray through image position `(x, y)` in pixel units (`x` right, `y` down; pixel
    /// centres at half-integers).
    pub fn ray_at(&self, x: f32, y: f32) -> Ray {
        let (hw, hh) = self.half_extents();
        let u = (x / self.width as f32 * 2.0 - 1.0) * hw;
        let v = (1.0 - y / self.height as f32 * 2.0) * hh;
        match self.projection {
            Projection::Perspective { .. } => {
                Ray::new(self.eye, self.forward + self.right * u + self.up * v)
            }
            Projection::Orthographic { .. } => {
                Ray::new(self.eye + self.right * u + self.up * v, self.forward)
            }
        }
    }

    /// The primary ray of pixel `(i, j)`, through its centre.
    pub fn pixel_ray(&self, i: u32, j: u32) -> Ray {
        self.ray_at(i as f32 + 0.5, j as f32 + 0.5)
    }
}

/// Light kinds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// A point light, intensity falling off as `1/r²`.
    Point {
        /// Position.
        position: Vec3,
    },
    /// A directional light (no falloff).
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3,
    },
}

/// A light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Name for reports (`light[i]` unless given).
    pub name: String,
    /// Kind and placement.
    pub kind: LightKind,
    /// `color · intensity`.
    pub intensity: Vec3,
    /// Whether it casts shadows.
    pub cast_shadows: bool,
    /// Radius of a point light's sphere, world units: `> 0` makes it an area light whose
    /// shadows are soft (`samples` shadow rays over its disk); 0 for a true point.
    pub radius: f32,
    /// Shadow rays per shading point for an area light.
    pub samples: u32,
}

/// Most `samples` an area light may ask for.
pub const MAX_LIGHT_SAMPLES: u32 = 256;

/// The specular lobe of a material (`specular_model` in the scene file).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecularModel {
    /// Blinn–Phong: `(n·h)^p` with the half vector `h = normalize(l + v)` (the default).
    #[default]
    BlinnPhong,
    /// Phong: `(v·r)^p` with `r` the mirror reflection of `l` about `n`.
    Phong,
}

/// A Blinn–Phong material with mirror reflection and transparency.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// `ka`.
    pub ambient: Vec3,
    /// `kd`.
    pub diffuse: Vec3,
    /// `ks`.
    pub specular: Vec3,
    /// Specular exponent `p`.
    pub shininess: f32,
    /// Which specular lobe `ks·(…)^p` uses.
    pub specular_model: SpecularModel,
    /// Mirror reflectance in `[0, 1]`.
    pub mirror: f32,
    /// Transparency in `[0, 1]`.
    pub transparency: f32,
    /// Index of refraction.
    pub ior: f32,
}

impl Material {
    /// A material with the format's defaults (the values of omitted fields).
    pub fn with_name(name: &str) -> Self {
        Self {
            name: name.to_string(),
            ambient: Vec3::splat(0.8),
            diffuse: Vec3::splat(0.8),
            specular: Vec3::ZERO,
            shininess: 32.0,
            specular_model: SpecularModel::BlinnPhong,
            mirror: 0.0,
            transparency: 0.0,
            ior: 1.5,
        }
    }

    /// `true` when `ks > 0` in any channel.
    pub fn has_specular(&self) -> bool {
        self.specular.max_element() > 0.0
    }
}

/// A render-ready scene.
#[derive(Debug)]
pub struct Scene {
    /// The file it came from.
    pub path: PathBuf,
    /// Camera.
    pub camera: Camera,
    /// Where the file sets the image size (`camera.width`), for a refusal of the size as a
    /// whole (the image's memory) when the command line does not override it.
    pub size_at: crate::error::Location,
    /// Ambient light `Ia`.
    pub ambient: Vec3,
    /// Colour of rays that leave the scene (and of uncovered pixels, with alpha 0).
    pub background: Vec3,
    /// Largest recursion depth the scene allows.
    pub max_depth: u32,
    /// Most samples per pixel of the adaptive anti-aliasing (top-level `samples`, default 1;
    /// `render --samples` overrides it).
    pub samples: u32,
    /// Lights.
    pub lights: Vec<Light>,
    /// Materials (objects refer to them by index).
    pub materials: Vec<Material>,
    /// Top-level objects.
    pub objects: Vec<Node>,
    /// The objects arranged for queries (a BVH over the bounded ones), built with them.
    pub top: top::TopLevel,
    /// `object[i] (type)` labels, parallel to `objects`.
    pub object_labels: Vec<String>,
    /// Named meshes (shared by their instances).
    pub meshes: Vec<Arc<MeshShape>>,
    /// Every mesh file the scene names, read or declared by an unused `[mesh.*]` (inputs a
    /// render must not overwrite).
    pub mesh_files: Vec<PathBuf>,
}

impl Scene {
    /// Per material: whether some surface shows it, i.e. some object or CSG operand (at any
    /// depth) that is not itself a CSG object uses it. A CSG object's own material shows only
    /// through the operands that inherit it, and a hit takes the material of the operand hit.
    pub fn used_materials(&self) -> Vec<bool> {
        use crate::scene::geom::Geometry;
        let mut used = vec![false; self.materials.len()];
        let mut stack: Vec<&crate::scene::geom::Node> = self.objects.iter().collect();
        while let Some(n) = stack.pop() {
            if let Geometry::Csg(_, a, b) = &n.shape {
                stack.push(a);
                stack.push(b);
            } else if let Some(u) = used.get_mut(n.material as usize) {
                *u = true;
            }
        }
        used
    }

    /// Number of top-level CSG objects.
    pub fn csg_objects(&self) -> Vec<&str> {
        self.objects
            .iter()
            .zip(&self.object_labels)
            .filter(|(o, _)| matches!(o.shape, crate::scene::geom::Geometry::Csg(..)))
            .map(|(_, l)| l.as_str())
            .collect()
    }
}

/// Reads and checks a scene file. Mesh paths are relative to the file's folder (to the
/// current directory for a scene read from a stream, such as `/dev/stdin`).
pub fn load(path: &Path) -> Result<Scene> {
    let text = crate::input::read_text(path, "a scene (TOML text)")?;
    parse(&text, path)
}

/// Parses and checks scene text; `path` names the file in messages and anchors mesh paths.
pub fn parse(text: &str, path: &Path) -> Result<Scene> {
    let src = Source { text, path };
    let def: def::SceneDef = toml::from_str(text).map_err(|e| src.toml_error(&e))?;
    build::build(&src, def)
}

/// The file text and path, for turning byte spans into `file:line:column` locations.
pub(crate) struct Source<'a> {
    pub text: &'a str,
    pub path: &'a Path,
}

impl Source<'_> {
    /// 1-based line and column (in characters) of byte offset `at`.
    pub fn line_col(&self, at: usize) -> (usize, usize) {
        let at = at.min(self.text.len());
        let before = &self.text[..floor_boundary(self.text, at)];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let col = before[line_start..].chars().count() + 1;
        (line, col)
    }

    /// A location at the start of `span`, naming `field`.
    pub fn at(&self, span: &Range<usize>, field: &str) -> Location {
        let (line, col) = self.line_col(span.start);
        Location::file(self.path)
            .line(line)
            .column(col)
            .field(field)
    }

    /// An input error at `span`.
    pub fn err(&self, span: &Range<usize>, field: &str, msg: impl Into<String>) -> Error {
        Error::input(self.at(span, field), msg)
    }

    /// A TOML/serde error with its location; the field is taken from the message
    /// (`unknown field`/`missing field`), from the key in front of the span, or from the
    /// header the span starts on (`[[camera]]` where a `[camera]` table is wanted). An error
    /// without a place in the file is located by what it says, never by the key at byte 0: a
    /// missing top-level field is named alone (`camera`, at the document's start, 1:1), and a
    /// key nested past the parser's limit ([`TOML_MAX_KEY_PARTS`]) by its line, column and
    /// dotted path ([`Source::too_deep_key`]), or, found nowhere, at 1:1 with no field.
    fn toml_error(&self, e: &toml::de::Error) -> Error {
        // An error of the document's own table (a missing top-level field) comes with the
        // empty span at byte 0: the document as a whole, as an error with no span.
        let Some(span) = e.span().filter(|s| !(s.is_empty() && s.start == 0)) else {
            return self.spanless_toml_error(e.message().trim());
        };
        let mut msg = e.message().trim().to_string();
        if msg == "duplicate key" {
            // The span covers the repeated key (or header name): quote it.
            if let Some(key) = self
                .text
                .get(span.clone())
                .map(str::trim)
                .filter(|k| !k.is_empty())
            {
                msg = format!("duplicate key `{}`", crate::text::excerpt(key));
            }
        }
        // The `[table]` or `[[array]]` header the span starts on, and whether it is an array's.
        let header = self.header_at(span.start);
        let missing = msg.starts_with("missing field `");
        let mut field = self.field_at(span.start, backticked_field(&msg), missing);
        if field.is_none() && msg.starts_with("duplicate key") {
            // A key repeated inside a table: the table's path and the key.
            let key = self.text.get(span.clone()).map_or("", str::trim);
            field = Some(match self.enclosing_table(span.start) {
                Some(table) => format!("{table}.{key}"),
                None => key.to_string(),
            });
        }
        // A header of the wrong kind: serde says only "map" or "sequence"; say which bracket.
        if let Some((h, double)) = &header {
            if *double && msg.starts_with("invalid type: map") {
                // The list as a whole is wrong, not its first table (`camera`, not `camera[0]`).
                field = Some(h.clone());
                msg.push_str(&format!(
                    " (`[[{h}]]` starts one of a list of tables; this one is a single `[{h}]` table)"
                ));
            } else if !double && msg.ends_with("expected a sequence") {
                msg.push_str(&format!(
                    " (`[{h}]` is a single table; this one is a list: `[[{h}]]`, once per entry)"
                ));
            }
        }
        let (line, col) = self.line_col(span.start);
        let mut at = Location::file(self.path).line(line).column(col);
        if let Some(f) = field {
            at = at.field(f);
        }
        // The message may quote the file's own text (an unknown key): escaped whole.
        Error::input(at, crate::text::escaped(&msg))
    }

    /// [`Source::toml_error`] for a message `msg` that comes without a span.
    /// Such an error is of the document as a whole (a missing top-level field, or nesting too
    /// deep that no line shows): it is located at line 1, column 1, where the document starts,
    /// with the field the message names, never the key that happens to stand there.
    fn spanless_toml_error(&self, msg: &str) -> Error {
        let document = Location::file(self.path).line(1).column(1);
        if msg == "recursion limit" {
            return match self.too_deep_key() {
                Some((start, key)) => self.err(
                    &(start..start),
                    &crate::text::excerpt(&key),
                    format!(
                        "the key has {} dotted parts; at most {TOML_MAX_KEY_PARTS} are read",
                        key_parts(&key).len()
                    ),
                ),
                None => Error::input(
                    document,
                    "somewhere in the file, keys or values nest too deep for the TOML reader \
                     (recursion limit)",
                ),
            };
        }
        let at = document;
        let at = match backticked_field(msg) {
            Some(f) => at.field(f),
            None => at,
        };
        Error::input(at, crate::text::escaped(msg))
    }

    /// The first `[header]`, `[[header]]` or line-leading `key =` whose dotted key has more
    /// than [`TOML_MAX_KEY_PARTS`] parts: its byte offset and its text.
    fn too_deep_key(&self) -> Option<(usize, String)> {
        let mut offset = 0;
        for line in self.text.split_inclusive('\n') {
            let start = offset;
            offset += line.len();
            let body = line.trim_start();
            let lead = line.len() - body.len();
            let (skip, key) = if let Some(h) = body.strip_prefix("[[") {
                (2, h.split("]]").next().unwrap_or(""))
            } else if let Some(h) = body.strip_prefix('[') {
                (1, h.split(']').next().unwrap_or(""))
            } else {
                (0, body.split('=').next().unwrap_or(""))
            };
            let key_lead = key.len() - key.trim_start().len();
            let key = key.trim();
            if key_parts(key).len() > TOML_MAX_KEY_PARTS {
                return Some((start + lead + skip + key_lead, key.to_string()));
            }
        }
        None
    }

    /// The field path of the table whose `[table]` or `[[array]]` header is the last one
    /// before byte `at` (`camera`, `material.m`, `object[1]`); `None` before any header.
    fn enclosing_table(&self, at: usize) -> Option<String> {
        let at = floor_boundary(self.text, at);
        let mut offset = 0;
        let mut last = None;
        for line in self.text[..at].split_inclusive('\n') {
            // A header's name is a key (no `,`): a line `[0, 1, 2]` inside an array is not one.
            if self
                .header_at(offset)
                .is_some_and(|(name, _)| !name.contains([',', '[', ']']))
            {
                last = Some(offset + line.len() - line.trim_start().len());
            }
            offset += line.len();
        }
        self.field_at(last?, None, false)
    }

    /// The dotted name of the `[table]` or `[[array]]` header on the line holding byte `at`,
    /// if that line is one, and `true` for an `[[array]]` header.
    fn header_at(&self, at: usize) -> Option<(String, bool)> {
        let at = floor_boundary(self.text, at);
        let start = self.text[..at].rfind('\n').map_or(0, |i| i + 1);
        let rest = self.text.get(start..)?;
        let line = rest.split('\n').next()?.split('#').next()?.trim();
        let array = line.strip_prefix("[[").and_then(|r| r.strip_suffix("]]"));
        let name = array.or_else(|| line.strip_prefix('[').and_then(|r| r.strip_suffix(']')))?;
        Some((name.trim().to_string(), array.is_some()))
    }

    /// The field path of byte `at` (`object[0].operands[1].radius`), from the document's
    /// keys and values: the innermost key or value whose span holds `at` (tables of
    /// `[header]`s span their header). `named` is the field a message names (`unknown
    /// field`/`missing field`): the path ends with it, appended to the table at `at`; an
    /// unknown field (not `missing`) is the key at `at` itself when that key already has its
    /// name. Read with the TOML parser's recovery, so a syntax error
    /// gets the path of what parsed up to it; `None` only when nothing holds `at` and no field
    /// is named.
    fn field_at(&self, at: usize, named: Option<String>, missing: bool) -> Option<String> {
        let (doc, _) = toml::de::DeTable::parse_recoverable(self.text);
        let mut best: Option<(usize, String)> = None;
        path_in(doc.get_ref(), "", at, &mut best);
        let path = best.map(|(_, p)| p);
        let Some(f) = named else { return path };
        Some(match path {
            Some(p) => {
                // `lights[0]` at an unknown `[[lights]]` is the field `lights` itself.
                let mut base = p.as_str();
                while let Some(b) = base.strip_suffix(']').and_then(|b| b.rsplit_once('[')) {
                    base = b.0;
                }
                if !missing && base.rsplit('.').next() == Some(f.as_str()) {
                    base.to_string()
                } else {
                    format!("{p}.{f}")
                }
            }
            None => f,
        })
    }
}

/// Records in `best` the path of the innermost key or value of `table` (at path `prefix`)
/// whose span holds byte `at`: the one of the shortest span.
fn path_in(
    table: &toml::de::DeTable<'_>,
    prefix: &str,
    at: usize,
    best: &mut Option<(usize, String)>,
) {
    fn visit(
        v: &toml::Spanned<toml::de::DeValue<'_>>,
        path: String,
        at: usize,
        best: &mut Option<(usize, String)>,
    ) {
        let span = v.span();
        if span.contains(&at) && best.as_ref().is_none_or(|(len, _)| span.len() <= *len) {
            *best = Some((span.len(), path.clone()));
        }
        match v.get_ref() {
            toml::de::DeValue::Table(t) => path_in(t, &path, at, best),
            toml::de::DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    visit(e, format!("{path}[{i}]"), at, best);
                }
            }
            _ => {}
        }
    }
    for (k, v) in table.iter() {
        let path = if prefix.is_empty() {
            k.get_ref().to_string()
        } else {
            format!("{prefix}.{}", k.get_ref())
        };
        let span = k.span();
        if span.contains(&at) && best.as_ref().is_none_or(|(len, _)| span.len() <= *len) {
            *best = Some((span.len(), path.clone()));
        }
        visit(v, path, at, best);
    }
}

/// Most parts of a dotted key (`a.b.c` has 3) that the TOML reader accepts: the `toml` crate
/// (1.x) refuses a key whose path before its last part has 80 parts or more, with the message
/// "recursion limit" and no span (a count of key parts; the crate does not export it, so a
/// test checks it against the crate).
pub(crate) const TOML_MAX_KEY_PARTS: usize = 80;

/// The parts of the dotted key `key` (`a."b.c".d` has 3: dots inside quotes do not split).
fn key_parts(key: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut start, mut quote, mut escaped) = (0, None, false);
    for (i, c) in key.char_indices() {
        let was_escaped = std::mem::replace(&mut escaped, false);
        match (quote, c) {
            (None, '"' | '\'') => quote = Some(c),
            (Some('"'), '\\') if !was_escaped => escaped = true,
            (Some('"'), '"') if was_escaped => {}
            (Some(q), _) if c == q => quote = None,
            (None, '.') => {
                parts.push(key[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    if !key.trim().is_empty() {
        parts.push(key[start..].trim());
    }
    parts
}

/// `x` from messages like "unknown field `x`, expected ..." or "missing field `x`".
fn backticked_field(msg: &str) -> Option<String> {
    for pat in ["unknown field `", "missing field `"] {
        if let Some(i) = msg.find(pat) {
            let rest = &msg[i + pat.len()..];
            return rest.find('`').map(|j| rest[..j].to_string());
        }
    }
    None
}

/// The largest char boundary `≤ at` (clamped to the text).
fn floor_boundary(s: &str, at: usize) -> usize {
    let mut i = at.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `a.a.…` with `n` parts.
    fn dotted(n: usize) -> String {
        vec!["a"; n].join(".")
    }

    /// [`TOML_MAX_KEY_PARTS`] is the `toml` crate's own limit, for a dotted key and a header.
    #[test]
    fn the_key_part_limit_is_the_toml_crates() {
        for form in [|k: &str| format!("{k} = 1\n"), |k: &str| format!("[{k}]\n")] {
            let ok = form(&dotted(TOML_MAX_KEY_PARTS));
            assert!(toml::from_str::<toml::Table>(&ok).is_ok(), "{ok}");
            let deep = form(&dotted(TOML_MAX_KEY_PARTS + 1));
            let e = toml::from_str::<toml::Table>(&deep).unwrap_err();
            assert_eq!((e.message(), e.span()), ("recursion limit", None));
        }
    }

    /// The error of scene `text` (read as `d.toml`), shown.
    fn error_of(text: &str) -> String {
        parse(text, Path::new("d.toml")).unwrap_err().to_string()
    }

    /// A key repeated inside a table is named by the table's path and the key: the table's
    /// own `[header]`, `[a.b]` or the `n`-th `[[array]]` entry (counted by hand here).
    #[test]
    fn a_duplicate_key_names_its_table_and_key() {
        let camera =
            "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n";
        let dup_fov = camera.replace("fov = 40\n", "fov = 40\nfov = 40\n");
        assert_eq!(
            error_of(&dup_fov),
            "d.toml:5:1: field `camera.fov`: duplicate key `fov`"
        );
        let mat = format!("{camera}\n[material.m]\ndiffuse = [1, 1, 1]\ndiffuse = [1, 1, 1]\n");
        assert_eq!(
            error_of(&mat),
            "d.toml:10:1: field `material.m.diffuse`: duplicate key `diffuse`"
        );
        let sphere = "[[object]]\ntype = \"sphere\"\ncenter = [\n  0,\n  0,\n  0,\n]\nradius = 1\n";
        let objects = format!(
            "{camera}\n{sphere}material = \"m\"\n{sphere}material = \"m\"\nmaterial = \"m\"\n"
        );
        assert_eq!(
            error_of(&objects),
            "d.toml:26:1: field `object[1].material`: duplicate key `material`"
        );
        assert_eq!(
            error_of(&format!("samples = 1\nsamples = 2\n{camera}")),
            "d.toml:2:1: field `samples`: duplicate key `samples`"
        );
    }

    /// A table that lacks a field is named with that field appended, even when the table's
    /// own name is the field's (`[mesh.file]` without `file` is `mesh.file.file`).
    #[test]
    fn a_missing_field_is_appended_to_its_tables_path() {
        let camera =
            "[camera]\neye = [0, 0, 9]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n";
        for (name, field) in [("file", "mesh.file.file"), ("cube", "mesh.cube.file")] {
            let e = error_of(&format!("{camera}\n[mesh.{name}]\nsubdivide = 1\n"));
            assert_eq!(
                e,
                format!("d.toml:8:1: field `{field}`: missing field `file`"),
                "{name}"
            );
        }
    }

    #[test]
    fn key_parts_split_on_dots_outside_quotes() {
        assert_eq!(key_parts("a . \"b.c\".'d.e'"), ["a", "\"b.c\"", "'d.e'"]);
        assert_eq!(key_parts("\"x\\\".y\".z"), ["\"x\\\".y\"", "z"]);
        assert_eq!(key_parts(""), Vec::<&str>::new());
    }
}
