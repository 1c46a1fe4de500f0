//! The `scene_file` target: arbitrary bytes as a scene file. Never a panic; an error names
//! the scene file (and a line for errors inside it); an accepted scene has a usable camera,
//! and the centre pixel's ray through every object answers inside its interval.
//!
//! The file is parsed as if it lived in `fuzz/scene_dir/` (small meshes only, so the target
//! stays fast): `meshes/cube.obj` and friends resolve there.

use super::*;
use halfray::error::Error;
use halfray::render::Mode;
use halfray::render::plan::EffectPlan;
use halfray::scene::geom::QueryCtx;
use std::path::Path;

/// Where the fuzzed scene pretends to live (absolute at compile time: the fuzz crate and
/// the replay test both sit one folder below the project root).
pub const SCENE_PATH: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../fuzz/scene_dir/input.toml"
);

/// Fuzz target `scene_file`: lossy UTF-8 text through [`check`].
pub fn scene_file(data: &[u8]) {
    check(&String::from_utf8_lossy(data));
}

/// `true` for a text that could name a file outside `fuzz/scene_dir/`: such a path could name
/// a device or a huge file, and the target reads only files it controls. [`check`] skips these
/// texts (a narrowing listed in `fuzz/README.md`); the paths inside the folder stay fuzzed.
///
/// Two tests, either enough to skip. On the text: `..`, a string starting with `/` (`"/`,
/// `'/`), an escape that could spell either (`\x`, `\u`, `\U`), or a multi-line string
/// (`"""`, `'''`), whose first line break and a line-ending backslash's white space TOML drops,
/// so that `"""⏎/dev/zero"""` is `/dev/zero`. On the values, whatever escapes the text spells:
/// when the text is a TOML document (read by the `toml` crate the scene parser uses), a string
/// value anywhere in it that is an absolute path or has a `..` component
/// ([`leaves_the_folder`]). A text that is not a TOML document is refused by the scene parser
/// before any mesh is read.
pub fn may_leave_scene_dir(text: &str) -> bool {
    spelling_may_leave(text) || a_value_leaves(text)
}

/// The test on the text (see [`may_leave_scene_dir`]).
fn spelling_may_leave(text: &str) -> bool {
    ["..", "\"/", "'/", "\\x", "\\u", "\\U", "\"\"\"", "'''"]
        .iter()
        .any(|p| text.contains(p))
}

/// The test on the values (see [`may_leave_scene_dir`]).
fn a_value_leaves(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| t.values().any(names_a_path_outside))
}

/// `true` when `v` is, or holds at any depth, a string that [`leaves_the_folder`].
fn names_a_path_outside(v: &toml::Value) -> bool {
    match v {
        toml::Value::String(s) => leaves_the_folder(s),
        toml::Value::Array(a) => a.iter().any(names_a_path_outside),
        toml::Value::Table(t) => t.values().any(names_a_path_outside),
        _ => false,
    }
}

/// `true` when the path `s`, joined to a folder, can name a file outside it: `s` is absolute
/// or has a `..` component.
fn leaves_the_folder(s: &str) -> bool {
    let p = Path::new(s);
    p.is_absolute()
        || p.components()
            .any(|c| matches!(c, std::path::Component::ParentDir))
}

/// How far from 1 the length of an accepted camera's `forward`, `right` and `up` may be
/// (unitless). `forward` and `right` are normalised in `f32` (a few ulps); `up = right ×
/// forward` is unit only as far as `right` is perpendicular to `forward`: `|up| = cos δ ≈
/// 1 − δ²/2`, where `right`'s deviation `δ ≈ 2u / sin θ` grows as the view direction nears the
/// scene's `up` (angle θ), which the camera accepts down to an exactly zero cross product.
/// `10⁻³` holds for `sin θ ≳ 3·10⁻⁶`, so no practical camera fails it; a tighter bound would
/// need θ.
pub const CAMERA_FRAME_UNIT_TOL: f32 = 1e-3;

/// The properties (module documentation).
pub fn check(text: &str) {
    if may_leave_scene_dir(text) {
        return;
    }
    // Both outcomes below are judged (an accepted scene's camera and queries, an error's
    // kind and position).
    reached();
    let path = Path::new(SCENE_PATH);
    match halfray::scene::parse(text, path) {
        Ok(scene) => {
            let cam = &scene.camera;
            assert!(
                cam.width >= 1 && cam.height >= 1,
                "empty image accepted\n{text}"
            );
            for v in [cam.eye, cam.forward, cam.right, cam.up] {
                assert!(v.is_finite(), "non-finite camera {cam:?}\n{text}");
            }
            for v in [cam.forward, cam.right, cam.up] {
                assert!(
                    (v.length() - 1.0).abs() < CAMERA_FRAME_UNIT_TOL,
                    "camera frame not unit {cam:?}\n{text}"
                );
            }
            let ray = cam.pixel_ray(cam.width / 2, cam.height / 2);
            assert!(ray.is_valid(), "invalid centre ray {ray:?}\n{text}");
            let plan = EffectPlan::derive(&scene, false);
            // The explanation states the primary rays and names every light in its shadow
            // line, "none" exactly when the colour render casts no shadow rays (its plan flag).
            let explain = plan.explain(&scene, Mode::Color, 1);
            let (w, h) = (u64::from(cam.width), u64::from(cam.height));
            assert!(
                explain.contains(&format!("{w} × {h} = {}", w * h)),
                "explain: primary rays\n{explain}\n{text}"
            );
            let shadow_line = explain
                .lines()
                .find(|l| l.trim_start().starts_with("shadow rays"))
                .unwrap_or_default();
            for l in &scene.lights {
                assert!(
                    shadow_line.contains(&l.name),
                    "explain: light {} missing\n{explain}\n{text}",
                    l.name
                );
            }
            assert_eq!(
                shadow_line.contains("shadow rays      none"),
                !plan.flags(&scene, Mode::Color, 1).shadow,
                "explain: shadow line\n{explain}\n{text}"
            );
            let mut qc = QueryCtx::default();
            for o in &scene.objects {
                let closest = o.closest(&ray, &mut qc);
                if let Some(h) = closest {
                    assert!(
                        ray.contains(h.hit.t),
                        "object hit at t = {} outside the ray interval\n{text}",
                        h.hit.t
                    );
                }
                // The shadow query (a mesh's own any-hit traversal) agrees with closest hit.
                assert_eq!(
                    o.occludes(&ray, &mut qc),
                    closest.is_some(),
                    "occludes disagrees with closest hit on {ray:?}\n{text}"
                );
            }
        }
        Err(e) => {
            let msg = e.to_string();
            match &e {
                Error::Input { at, .. } if at.file == path => assert!(
                    at.line.is_some() && msg.starts_with(SCENE_PATH),
                    "scene error without a line: {msg:?}\n{text}"
                ),
                Error::Input { .. } | Error::Io { .. } => {
                    assert!(!msg.is_empty(), "empty message\n{text}")
                }
                other => panic!("unexpected error kind {other:?}\n{text}"),
            }
        }
    }
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let t = |name: &str, text: &str| {
        (
            "scene_file",
            format!("seed-{name}"),
            text.as_bytes().to_vec(),
        )
    };
    s.push(t("shadows", include_str!("../../../scenes/shadows.toml")));
    s.push(t("mirror", include_str!("../../../scenes/mirror.toml")));
    s.push(t("glass", include_str!("../../../scenes/glass.toml")));
    s.push(t("csg", include_str!("../../../scenes/csg.toml")));
    s.push(t(
        "subdivision",
        include_str!("../../../scenes/subdivision.toml"),
    ));
    // Two shared meshes (one smoothed and subdivided) as an object and a CSG operand.
    let small = include_str!("../seeds/small-meshes.toml");
    s.push(t("small-meshes", small));
    s.push(t("unknown-key", "bogus = 1\n"));
    s.push(t("not-toml", "[camera\nwidth = "));
    s.push(t("empty", ""));
    s.push(t(
        "open-mesh-in-csg",
        &small.replace("meshes/octahedron.obj", "meshes/open.obj"),
    ));
    s.push(t(
        "missing-mesh",
        &small.replace("meshes/cube.obj", "meshes/none.obj"),
    ));
    s.push(t("nan", &small.replace("fov = 45", "fov = nan")));
    s.push(t(
        "singular-transform",
        &small.replace("scale = [0.5, 0.5, 0.5]", "scale = [0.5, 0, 0.5]"),
    ));
}

#[cfg(test)]
mod tests {
    use super::{a_value_leaves, may_leave_scene_dir};

    #[test]
    fn paths_that_may_leave_the_scene_dir_are_recognised() {
        let spelled = [
            "mesh = \"../x.obj\"",
            "mesh = \"/dev/zero\"",
            "mesh = '/dev/zero'",
            "mesh = \"\"\"/dev/zero\"\"\"",
        ];
        // Escapes and multi-line strings: caught by the decoded values alone, whatever the
        // text test lists.
        let decoded = [
            "mesh = \"\\u002Fdev/zero\"",
            "mesh = \"\\U0000002Fdev/zero\"",
            // TOML 1.1's `\xHH`, which the toml crate decodes: `/tmp/x.obj`, `../x.obj` (the
            // text test let these through).
            "file = \"\\x2Ftmp\\x2Fx.obj\"",
            "file = \"\\x2E\\x2E/x.obj\"",
            "[mesh.a]\nfile = \"meshes/\\x2E\\x2E/\\x2E\\x2E/x.obj\"",
            "objects = [{ file = \"\\x2fdev\\x2fzero\" }]",
            // TOML drops a multi-line string's first line break, and a line-ending
            // backslash's white space: both spell `/dev/zero`.
            "mesh = \"\"\"\n/dev/zero\"\"\"",
            "mesh = '''\n/dev/zero'''",
            "mesh = \"\"\"\\\n  /dev/zero\"\"\"",
        ];
        for text in spelled.iter().chain(&decoded) {
            assert!(may_leave_scene_dir(text), "{text}");
        }
        for text in decoded {
            assert!(a_value_leaves(text), "{text}");
        }
        for text in [
            "mesh = \"meshes/cube.obj\"",
            "[mesh.a]\nfile = \"meshes/./cube.obj\"",
            "name = \"a.b\"",
            "width = 1.5",
            "",
        ] {
            assert!(!may_leave_scene_dir(text), "{text}");
        }
    }
}
