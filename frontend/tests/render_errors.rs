//! Bad scene files: every message names the file, line, column and field; exit code 1; never a
//! panic.

use halfray::scene::load;
use std::path::Path;
use std::process::Command;

const BASE: &str = r#"[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
fov = 40
width = 8
height = 6

[material.m]
diffuse = [1, 0, 0]
"#;

/// Writes `text` as `name` in a fresh folder (plus an open one-triangle OBJ) and loads it.
fn load_err(name: &str, text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("open.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    match load(&path) {
        Ok(_) => panic!("{name} loaded but should not"),
        Err(e) => {
            let msg = e.to_string();
            let shown = msg.replace(&format!("{}/", dir.path().display()), "");
            assert!(
                shown.starts_with(name),
                "message does not start with the file: {msg}"
            );
            assert_eq!(e.exit_code(), 1);
            shown
        }
    }
}

fn sphere_with(extra: &str) -> String {
    format!("{BASE}\n[[object]]\ntype = \"sphere\"\n{extra}\n")
}

#[track_caller]
fn check(name: &str, text: &str, line_col: &str, field: &str, what: &str) {
    let msg = load_err(name, text);
    let want = format!("{name}:{line_col}: field `{field}`");
    assert!(msg.starts_with(&want), "want `{want}`, got: {msg}");
    assert!(msg.contains(what), "want `{what}` in: {msg}");
}

#[test]
fn unknown_key() {
    check(
        "unknown.toml",
        &sphere_with("center = [0, 0, 0]\nradiuss = 1\nmaterial = \"m\""),
        "14:1",
        "object[0].radiuss",
        "unknown field `radiuss`",
    );
    check(
        "unknown_mat.toml",
        &BASE.replace("diffuse = [1, 0, 0]", "difuse = [1, 0, 0]"),
        "9:1",
        "material.m.difuse",
        "unknown field `difuse`",
    );
    check(
        "unknown_top.toml",
        &format!("ambiant = [1, 1, 1]\n{BASE}"),
        "1:1",
        "ambiant",
        "unknown field `ambiant`",
    );
}

#[test]
fn missing_fields() {
    check(
        "missing.toml",
        &sphere_with("center = [0, 0, 0]\nmaterial = \"m\""),
        "11:1",
        "object[0].radius",
        "missing field `radius` for type `sphere`",
    );
    check(
        "nocam.toml",
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\n",
        "1:1",
        "camera.height",
        "missing field `height`",
    );
    check(
        "nomat.toml",
        &sphere_with("center = [0, 0, 0]\nradius = 1"),
        "11:1",
        "object[0].material",
        "missing field `material`",
    );
}

/// A missing `[camera]` has no place in the file: the message names the field `camera` alone
/// (it was appended to the key at byte 0: `ambient.camera`).
#[test]
fn a_missing_camera_is_the_field_camera() {
    for top in ["ambient = [0.1, 0.1, 0.1]\n", "max_depth = 3\n", ""] {
        let text = format!("{top}[material.m]\ndiffuse = [1, 0, 0]\n");
        let msg = load_err("nocam.toml", &text);
        assert!(
            msg.starts_with("nocam.toml:1:1: field `camera`: missing field `camera`"),
            "{msg}"
        );
    }
}

/// A key nested past the TOML reader's limit (the reader gives no location) is found by its
/// line, column and dotted path: a header, a dotted key at byte 0, a material's header; keys
/// nested deep in other ways get the message alone, with no invented field.
#[test]
fn a_key_nested_too_deep_is_located() {
    let deep = vec!["a"; 100].join(".");
    // The path as a message quotes it: its first 40 characters and its length.
    let quoted = |key: String| format!("{}… ({} bytes in all)", &key[..40], key.len());
    check(
        "hdr.toml",
        &format!("ambient = [0.1, 0.1, 0.1]\n{BASE}\n[x.{deep}]\ny = 1\n"),
        "12:2",
        &quoted(format!("x.{deep}")),
        "the key has 101 dotted parts; at most 80 are read",
    );
    check(
        "dot.toml",
        &format!("  x.{deep} = 1\n{BASE}"),
        "1:3",
        &quoted(format!("x.{deep}")),
        "101 dotted parts",
    );
    check(
        "mat.toml",
        &format!("{BASE}\n[[ material.q.{deep} ]]\n"),
        "11:4",
        &quoted(format!("material.q.{deep}")),
        "102 dotted parts",
    );
    let msg = load_err("inline.toml", &format!("{BASE}y = {{ {deep} = 1 }}\n"));
    assert_eq!(
        msg,
        "inline.toml:1:1: somewhere in the file, keys or values nest too deep for the TOML \
         reader (recursion limit)"
    );
}

#[test]
fn unknown_material_and_mesh_names() {
    check(
        "mat.toml",
        &sphere_with("center = [0, 0, 0]\nradius = 1\nmaterial = \"nope\""),
        "15:12",
        "object[0].material",
        "no material named `nope` (defined: m)",
    );
    check(
        "mesh.toml",
        &format!("{BASE}\n[[object]]\ntype = \"mesh\"\nmesh = \"bun\"\nmaterial = \"m\"\n"),
        "13:8",
        "object[0].mesh",
        "no mesh named `bun`",
    );
}

/// A table written with the wrong brackets (`[[camera]]` for the one camera, `[light]` for the
/// list of lights) names the field and says which bracket is wanted; serde alone said
/// "invalid type: map, expected a string" with no field.
#[test]
fn a_header_with_the_wrong_brackets_names_its_table() {
    check(
        "cams.toml",
        &BASE.replace("[camera]", "[[camera]]"),
        "1:1",
        "camera",
        "this one is a single `[camera]` table",
    );
    check(
        "light.toml",
        &format!("[light]\ntype = \"point\"\nposition = [0, 0, 0]\n\n{BASE}"),
        "1:1",
        "light",
        "this one is a list: `[[light]]`",
    );
}

#[test]
fn missing_obj_file() {
    check(
        "obj.toml",
        &format!(
            "{BASE}\n[mesh.bun]\nfile = \"meshes/nothere.obj\"\n\n[[object]]\ntype = \"mesh\"\nmesh = \"bun\"\nmaterial = \"m\"\n"
        ),
        "12:8",
        "mesh.bun.file",
        "mesh file `meshes/nothere.obj` not found",
    );
}

/// A mesh path that is there but cannot be followed (a loop of symbolic links) says so, with
/// the system's words, not "not found".
#[cfg(unix)]
#[test]
fn a_mesh_path_in_a_symlink_loop_is_not_called_missing() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(dir.path().join("b.obj"), dir.path().join("a.obj")).unwrap();
    std::os::unix::fs::symlink(dir.path().join("a.obj"), dir.path().join("b.obj")).unwrap();
    let scene = dir.path().join("loop.toml");
    std::fs::write(
        &scene,
        format!(
            "{BASE}\n[mesh.bun]\nfile = \"a.obj\"\n\n[[object]]\ntype = \"mesh\"\nmesh = \"bun\"\nmaterial = \"m\"\n"
        ),
    )
    .unwrap();
    let Err(e) = load(&scene) else {
        panic!("a loop is an error")
    };
    let e = e.to_string();
    assert!(
        e.contains("loop.toml:12:8: field `mesh.bun.file`")
            && e.contains("cannot be read")
            && !e.contains("not found"),
        "{e}"
    );
}

#[test]
fn non_finite_numbers() {
    check(
        "nan.toml",
        &sphere_with("center = [0, nan, 0]\nradius = 1\nmaterial = \"m\""),
        "13:14",
        "object[0].center[1]",
        "NaN is not a finite number",
    );
    // A finite number beyond `f32` is named as written, not as the `inf` it reads as.
    check(
        "big.toml",
        &sphere_with("center = [0, 0, 0]\nradius = 1e300\nmaterial = \"m\""),
        "14:10",
        "object[0].radius",
        "1e300 is beyond the largest `f32` (±3.4e38)",
    );
    check(
        "inf.toml",
        &sphere_with("center = [0, 0, 0]\nradius = inf\nmaterial = \"m\""),
        "14:10",
        "object[0].radius",
        "inf is not a finite number",
    );
    check(
        "camnan.toml",
        &BASE.replace("fov = 40", "fov = -nan"),
        "4:7",
        "camera.fov",
        "not a finite number",
    );
}

#[test]
fn type_errors_and_wrong_fields() {
    check(
        "type.toml",
        &sphere_with("center = [0, 0, 0]\nradius = \"big\"\nmaterial = \"m\""),
        "14:10",
        "object[0].radius",
        "invalid type: string \"big\"",
    );
    check(
        "extra.toml",
        &sphere_with("center = [0, 0, 0]\nradius = 1\nradii = [1, 1, 1]\nmaterial = \"m\""),
        "15:9",
        "object[0].radii",
        "not used by type `sphere`",
    );
    check(
        "kind.toml",
        &sphere_with("material = \"m\"").replace("\"sphere\"", "\"cone\""),
        "12:8",
        "object[0].type",
        "unknown object type `cone`",
    );
}

#[test]
fn csg_operand_not_closed() {
    let csg = |operand: &str, mesh: &str| {
        format!(
            "{BASE}{mesh}\n[[object]]\ntype = \"csg\"\nop = \"union\"\nmaterial = \"m\"\noperands = [\n  {{ type = \"sphere\", center = [0, 0, 0], radius = 1 }},\n  {operand},\n]\n"
        )
    };
    let tri = csg(
        "{ type = \"triangle\", vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }",
        "",
    );
    check(
        "csgtri.toml",
        &tri,
        "17:12",
        "object[0].operands[1]",
        "a triangle is not closed",
    );
    let open = csg(
        "{ type = \"mesh\", mesh = \"o\" }",
        "\n[mesh.o]\nfile = \"open.obj\"\n",
    );
    check(
        "csgmesh.toml",
        &open,
        "20:12",
        "object[0].operands[1]",
        "mesh `o` is not closed (3 boundary or unpaired edges)",
    );
}

/// A serde error inside nested inline tables and arrays names the whole path, every array
/// index included: an operand of an operand, an element of a vector.
#[test]
fn errors_in_nested_csg_operands_name_every_index() {
    let nested = |inner: &str| {
        format!(
            "{BASE}\n[[object]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n\n\
             [[object]]\ntype = \"csg\"\nop = \"union\"\nmaterial = \"m\"\noperands = [\n  \
             {{ type = \"sphere\", center = [0, 0, 0], radius = 1 }},\n  \
             {{ type = \"csg\", op = \"union\", operands = [{{ type = \"sphere\", center = [0, 0, 1], radius = 1 }}, {inner}] }},\n]\n"
        )
    };
    // Line 23 holds the inner operands; columns count from its start.
    let line = "  { type = \"csg\", op = \"union\", operands = [{ type = \"sphere\", center = [0, 0, 1], radius = 1 }, ";
    let col = |within: &str| format!("23:{}", line.chars().count() + within.chars().count() + 1);
    let inner = "{ type = \"sphere\", center = [0, 0, 2], radius = \"x\" }";
    check(
        "type.toml",
        &nested(inner),
        &col("{ type = \"sphere\", center = [0, 0, 2], radius = "),
        "object[1].operands[1].operands[1].radius",
        "invalid type: string \"x\"",
    );
    let inner = "{ type = \"sphere\", center = [0, 0, 2], radius = 1, bogus = 3 }";
    check(
        "unknown.toml",
        &nested(inner),
        &col("{ type = \"sphere\", center = [0, 0, 2], radius = 1, "),
        "object[1].operands[1].operands[1].bogus",
        "unknown field `bogus`",
    );
    let inner = "{ type = \"sphere\", center = [0, 0, true], radius = 1 }";
    check(
        "element.toml",
        &nested(inner),
        &col("{ type = \"sphere\", center = [0, 0, "),
        "object[1].operands[1].operands[1].center[2]",
        "invalid type: boolean `true`",
    );
    let inner = "{ type = \"sphere\", center = [0, 0, 2] }";
    check(
        "missing.toml",
        &nested(inner),
        &col(""),
        "object[1].operands[1].operands[1].radius",
        "missing field `radius`",
    );
}

/// A direction or axis `f32` cannot normalise (zero, too short, too long) is refused with the
/// range that can be, not called zero: `[1e-30, 0, 0]` is no zero vector.
#[test]
fn directions_too_short_or_long_to_normalise() {
    for axis in ["[0, 0, 0]", "[1e-30, 0, 0]", "[3e19, 3e19, 0]"] {
        check(
            "axis.toml",
            &sphere_with(&format!(
                "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{{ rotate = {{ axis = {axis}, degrees = 30 }} }}]"
            )),
            "16:34",
            "object[0].transform[0].rotate.axis",
            "whose length f32 can normalise (a largest component from about 1e-22 to 1e19)",
        );
    }
    // Inside the range, both ends.
    for axis in ["[1e-22, 0, 0]", "[1e19, 0, 0]"] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ok.toml");
        std::fs::write(
            &path,
            sphere_with(&format!(
                "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{{ rotate = {{ axis = {axis}, degrees = 30 }} }}]"
            )),
        )
        .unwrap();
        load(&path).unwrap_or_else(|e| panic!("{axis}: {e}"));
    }
}

#[test]
fn singular_transform() {
    check(
        "sing.toml",
        &sphere_with(
            "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{ translate = [1, 0, 0] }, { scale = [1, 0, 1] }]",
        ),
        "16:51",
        "object[0].transform[1].scale",
        "singular",
    );
    check(
        "singm.toml",
        &sphere_with(
            "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{ matrix = [[1, 2, 0, 0], [2, 4, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }]",
        ),
        "16:25",
        "object[0].transform[0].matrix",
        "singular",
    );
    // Steps invertible alone whose product is not: the error names the step at which the
    // running product first fails (its column: the step's value), not the whole `transform`.
    // Two y scales of 10⁻³ make 10⁻⁶: condition number ‖L‖_F·‖L⁻¹‖_F = √(2 + 10⁻¹²)·√(2 + 10¹²)
    // ≈ 1.4·10⁶ > 2²⁰; two uniform scales of 10⁻²⁰ make 10⁻⁴⁰, whose inverse (10⁴⁰) overflows
    // f32; with a translation between the two y scales the product first fails at step 2.
    for (steps, column, step) in [
        (
            "[{ scale = [1, 1e-3, 1] }, { scale = [1, 1e-3, 1] }]",
            50,
            1,
        ),
        ("[{ scale = 1e-20 }, { scale = 1e-20 }]", 43, 1),
        (
            "[{ scale = [1, 1e-3, 1] }, { translate = [0, 1, 0] }, { scale = [1, 1e-3, 1] }]",
            77,
            2,
        ),
    ] {
        check(
            "singp.toml",
            &sphere_with(&format!(
                "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = {steps}"
            )),
            &format!("16:{column}"),
            &format!("object[0].transform[{step}].scale"),
            &format!(
                "steps 0 to {step} together: transform is singular (a zero or degenerate scale): it cannot be inverted"
            ),
        );
    }
    // Ill-conditioned is not singular: a rod of condition number 2 000, as a scale and as a
    // matrix, loads (a scaled-determinant test refused both).
    for rod in [
        "{ scale = [1, 5e-4, 5e-4] }",
        "{ matrix = [[1, 0, 0, 0], [0, 5e-4, 0, 0], [0, 0, 5e-4, 0], [0, 0, 0, 1]] }",
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rod.toml");
        std::fs::write(
            &path,
            sphere_with(&format!(
                "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{rod}]"
            )),
        )
        .unwrap();
        if let Err(e) = load(&path) {
            panic!("{rod} refused: {e}");
        }
    }
}

#[test]
fn cli_exits_with_code_1_and_the_location() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.toml");
    std::fs::write(
        &scene,
        sphere_with("center = [0, 0, 0]\nradius = -1\nmaterial = \"m\""),
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_halfray"))
        .args(["render", scene.to_str().unwrap(), "-o"])
        .arg(dir.path().join("o.png"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml:14:10: field `object[0].radius`: must be > 0"),
        "{err}"
    );
    assert!(!dir.path().join("o.png").exists());
    assert!(!err.contains("panicked"));
    assert!(Path::new(&scene).exists());
}

/// Fixed-size arrays take exactly their length: serde's arrays read the first `N` elements and
/// ignored the rest, so `center = [0, 0, 0, "junk"]` and a 5×5 `matrix` were accepted.
#[test]
fn fixed_size_arrays_refuse_extra_elements() {
    check(
        "center4.toml",
        &sphere_with("center = [0, 0, 0, \"junk\"]\nradius = 1\nmaterial = \"m\""),
        "13:10",
        "object[0].center",
        "invalid length 4, expected an array of exactly 3 elements",
    );
    check(
        "center2.toml",
        &sphere_with("center = [0, 0]\nradius = 1\nmaterial = \"m\""),
        "13:10",
        "object[0].center",
        "invalid length 2, expected an array of exactly 3 elements",
    );
    let m5 = "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [0, 0, 0, 1]]";
    let msg = load_err(
        "matrix5.toml",
        &sphere_with(&format!(
            "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{{ matrix = {m5} }}]"
        )),
    );
    assert!(
        msg.contains("matrix") && msg.contains("invalid length 5, expected an array of exactly 4"),
        "{msg}"
    );
    let row5 = "[[1, 0, 0, 0, 9], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]";
    let msg = load_err(
        "row5.toml",
        &sphere_with(&format!(
            "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{{ matrix = {row5} }}]"
        )),
    );
    assert!(
        msg.contains("invalid length 5, expected an array of exactly 4"),
        "{msg}"
    );
    let msg = load_err(
        "vertex4.toml",
        &format!(
            "{BASE}\n[[object]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0, 7]]\nmaterial = \"m\"\n"
        ),
    );
    assert!(
        msg.contains("vertices") && msg.contains("invalid length 4"),
        "{msg}"
    );
    // Control: the same scene with exact arrays loads.
    let dir = tempfile::tempdir().unwrap();
    let ok = dir.path().join("ok.toml");
    std::fs::write(
        &ok,
        sphere_with(&format!(
            "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{{ matrix = {} }}]",
            "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]"
        )),
    )
    .unwrap();
    assert!(load(&ok).is_ok());
}

/// `[mesh.NAME]` definitions are checked whether or not an object uses them (the file is not
/// read when unused: nothing renders it), and a directory is named as such.
#[test]
fn unused_mesh_definitions_are_checked() {
    let scene = |mesh: &str| {
        format!(
            "{BASE}\n[mesh.ghost]\n{mesh}\n\n[[object]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
        )
    };
    check(
        "ghost.toml",
        &scene("file = \"nothere.obj\""),
        "12:8",
        "mesh.ghost.file",
        "not found",
    );
    check(
        "ghost_dir.toml",
        &scene("file = \".\""),
        "12:8",
        "mesh.ghost.file",
        "is a directory",
    );
    check(
        "ghost_levels.toml",
        &scene("file = \"open.obj\"\nsubdivide = 9"),
        "13:13",
        "mesh.ghost.subdivide",
        "at most 4 levels",
    );
    // Control: a valid unused definition loads.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("open.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let ok = dir.path().join("ok.toml");
    std::fs::write(&ok, scene("file = \"open.obj\"")).unwrap();
    assert!(load(&ok).is_ok());
}

/// Subdivision that would exceed the memory limit is refused before it starts, naming the
/// setting and the estimate (a 60 000-triangle grid at 4 levels: 15 million triangles).
#[test]
fn scene_subdivision_beyond_the_memory_limit_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let n = 174usize; // (n−1)² · 2 ≈ 59 858 triangles
    let mut obj = String::new();
    for j in 0..n {
        for i in 0..n {
            obj.push_str(&format!("v {i} {j} 0\n"));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i + 1;
            obj.push_str(&format!(
                "f {a} {} {}\nf {} {} {}\n",
                a + 1,
                a + n + 1,
                a,
                a + n + 1,
                a + n
            ));
        }
    }
    std::fs::write(dir.path().join("grid.obj"), obj).unwrap();
    let scene = format!(
        "{BASE}\n[mesh.g]\nfile = \"grid.obj\"\nsubdivide = 4\n\n[[object]]\ntype = \"mesh\"\nmesh = \"g\"\nmaterial = \"m\"\n"
    );
    let path = dir.path().join("big.toml");
    std::fs::write(&path, &scene).unwrap();
    let t0 = std::time::Instant::now();
    let msg = match load(&path) {
        Ok(_) => panic!("a 15-million-triangle subdivision was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        msg.contains("`subdivide = 4` on 59858 triangles needs about") && msg.contains("GiB"),
        "{msg}"
    );
    // Named at the setting that asks for it (line 13 of the scene, the value of `subdivide = 4`).
    let shown = msg.replace(&format!("{}/", dir.path().display()), "");
    assert!(
        shown.starts_with("big.toml:13:13:") && shown.contains("field `mesh.g.subdivide`"),
        "{shown}"
    );
    assert!(t0.elapsed().as_secs() < 20, "refused before subdividing");
    // Control: one level fits and loads.
    std::fs::write(&path, scene.replace("subdivide = 4", "subdivide = 1")).unwrap();
    assert!(load(&path).is_ok());
}

/// Messages name the right field and cause: an unknown top-level table is that table (not
/// `lights[0].lights`), a projective matrix is "not affine" (not "degenerate").
#[test]
fn fields_and_causes_are_named_right() {
    check(
        "lights.toml",
        &format!("{BASE}\n[[lights]]\ntype = \"point\"\n"),
        "11:3",
        "lights",
        "unknown field `lights`",
    );
    check(
        "projective.toml",
        &sphere_with(
            "center = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\ntransform = [{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]] }]",
        ),
        "16:25",
        "object[0].transform[0].matrix",
        "not an affine transform: the last row must be [0, 0, 0, 1]",
    );
}

#[test]
fn unknown_specular_model() {
    let text = BASE.replace(
        "diffuse = [1, 0, 0]",
        "diffuse = [1, 0, 0]\nspecular_model = \"cook-torrance\"",
    );
    check(
        "specular.toml",
        &format!(
            "{text}\n[[object]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
        ),
        "10:18",
        "material.m.specular_model",
        "expected `blinn-phong` or `phong`",
    );
    // Both models load.
    for model in ["phong", "blinn-phong"] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ok.toml");
        let text = BASE.replace(
            "diffuse = [1, 0, 0]",
            &format!("diffuse = [1, 0, 0]\nspecular = [1, 1, 1]\nspecular_model = \"{model}\""),
        );
        std::fs::write(&path, text).unwrap();
        assert!(load(&path).is_ok(), "{model}");
    }
}

/// A TOML syntax error (an array left open) is reported at its line and column in the scene
/// file, counted from the text: `center = [0, 0, 0` runs into the next line, and the parser
/// finds `radius` (line of `radius`, column 1) where a `,` or `]` must come.
#[test]
fn toml_syntax_error_names_line_and_column() {
    let text = format!("{BASE}\n[[object]]\ntype = \"sphere\"\ncenter = [0, 0, 0\nradius = 1\n");
    let line = text.lines().position(|l| l.starts_with("radius")).unwrap() + 1;
    let msg = load_err("syntax.toml", &text);
    assert!(msg.starts_with(&format!("syntax.toml:{line}:1: ")), "{msg}");
    assert!(msg.contains("expected `,`"), "{msg}");
}

/// Writes `obj` as `name` in `dir` and a scene drawing it as mesh `b` (with the mesh fields
/// `fields`), and loads the scene.
fn load_mesh_scene(
    dir: &Path,
    name: &str,
    obj: &str,
    fields: &str,
) -> halfray::error::Result<halfray::scene::Scene> {
    std::fs::write(dir.join(name), obj).unwrap();
    let path = dir.join("mesh.toml");
    std::fs::write(
        &path,
        format!("{BASE}\n[mesh.b]\nfile = \"{name}\"\n{fields}\n\n[[object]]\ntype = \"mesh\"\nmesh = \"b\"\nmaterial = \"m\"\n"),
    )
    .unwrap();
    load(&path)
}

/// [`load_mesh_scene`]'s error, which it must give.
fn mesh_scene_err(dir: &Path, name: &str, obj: &str, fields: &str) -> halfray::error::Error {
    match load_mesh_scene(dir, name, obj, fields) {
        Ok(_) => panic!("{name} with `{fields}` loaded but should not"),
        Err(e) => e,
    }
}

/// An OBJ error inside a mesh the scene references names the OBJ file, its line and column,
/// then where the scene names that file.
#[test]
fn obj_error_in_a_referenced_mesh_names_its_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
    let msg = mesh_scene_err(dir.path(), "bad.obj", obj, "").to_string();
    // Line 4, column 7: the `9` of `f 1 2 9`.
    assert!(msg.contains("bad.obj:4:7: field `f`"), "{msg}");
    assert!(msg.contains("vertex index 9 out of range"), "{msg}");
    let shown = msg.replace(&format!("{}/", dir.path().display()), "");
    assert!(
        shown.contains("(the mesh of mesh.toml:") && shown.contains(": field `mesh.b.file`)"),
        "{shown}"
    );
}

/// A mesh the half-edge core rejects (smoothing, subdivision, smooth shading) is named as
/// `mesh check` names it: the OBJ's line, and triangles and vertices numbered from 1.
#[test]
fn a_mesh_the_half_edge_core_rejects_is_numbered_as_mesh_check_numbers_it() {
    let dir = tempfile::tempdir().unwrap();
    // The second `f` (line 6) uses vertex 1 twice.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nf 1 2 1\n";
    let path = dir.path().join("twice.obj");
    std::fs::write(&path, obj).unwrap();
    let check = Command::new(env!("CARGO_BIN_EXE_halfray"))
        .args(["mesh", "check"])
        .arg(&path)
        .output()
        .unwrap();
    let checked = String::from_utf8_lossy(&check.stdout).into_owned();
    assert!(
        checked.contains("triangle 2 uses vertex 1 twice"),
        "{checked}"
    );
    for treatment in [
        "subdivide = 1",
        "smooth = { step = 0.5, iterations = 1 }",
        "shading = \"smooth\"",
    ] {
        let e = mesh_scene_err(dir.path(), "twice.obj", obj, treatment);
        let msg = e.to_string();
        assert!(msg.contains("twice.obj:6: "), "{treatment}: {msg}");
        assert!(
            msg.contains("triangle 2 uses vertex 1 twice"),
            "{treatment}: {msg}"
        );
        assert_eq!(e.exit_code(), 1);
    }
}

/// An `eye` and `look_at` whose distance overflows `f32` are named as such, not as equal.
#[test]
fn a_camera_whose_distance_overflows_is_named_so() {
    let camera = |eye: &str, look_at: &str| {
        format!("[camera]\neye = {eye}\nlook_at = {look_at}\nfov = 40\nwidth = 8\nheight = 6\n")
    };
    check(
        "far.toml",
        &camera("[3e38, 0, 0]", "[-3e38, 0, 0]"),
        "3:11",
        "camera.look_at",
        "too far from `eye`",
    );
    check(
        "same.toml",
        &camera("[1, 2, 3]", "[1, 2, 3]"),
        "3:11",
        "camera.look_at",
        "must differ from `eye`",
    );
}

/// A referenced mesh file that holds no triangle is named at the scene's `file` field (the
/// scene's line and column), with the OBJ's path and the reason.
#[test]
fn a_referenced_mesh_without_triangles_is_named_at_its_file_field() {
    let dir = tempfile::tempdir().unwrap();
    let msg = mesh_scene_err(dir.path(), "points.obj", "v 0 0 0\nv 1 0 0\n", "").to_string();
    let shown = msg.replace(&format!("{}/", dir.path().display()), "");
    assert!(
        shown.starts_with("mesh.toml:") && shown.contains("field `mesh.b.file`"),
        "{shown}"
    );
    assert!(
        shown.contains("points.obj: mesh has no triangles"),
        "{shown}"
    );
}

/// Smoothing that moves a vertex outside the coordinate domain the OBJ reader enforces
/// (`obj::MAX_COORDINATE`, 2¹²⁵) is refused at the scene's `smooth` field, as `mesh smooth`
/// refuses it: a tetrahedron smoothed by `step = 2e38` (its vertices pulled to about
/// ±2.7·10³⁸, where the intersection test overflows) let most camera rays from inside it
/// through. A step that keeps it inside the domain (`3e37`) loads.
#[test]
fn smoothing_out_of_the_coordinate_domain_is_refused_at_its_field() {
    let dir = tempfile::tempdir().unwrap();
    let tet = "v 1 1 1\nv -1 -1 1\nv -1 1 -1\nv 1 -1 -1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
    for step in ["2e38", "-1e38"] {
        let fields = format!("smooth = {{ step = {step}, iterations = 1 }}");
        let msg = mesh_scene_err(dir.path(), "tet.obj", tet, &fields).to_string();
        let shown = msg.replace(&format!("{}/", dir.path().display()), "");
        assert!(
            shown.starts_with("mesh.toml:")
                && shown.contains("field `mesh.b.smooth`")
                && shown.contains("outside the coordinate domain"),
            "step {step}: {shown}"
        );
    }
    let inside = "smooth = { step = 3e37, iterations = 1 }";
    if let Err(e) = load_mesh_scene(dir.path(), "tet.obj", tet, inside) {
        panic!("a smoothing inside the domain refused: {e}");
    }
}

/// `smooth.iterations` is bounded by `MAX_SMOOTH_ITERATIONS` (10 000): exactly that many
/// load, one more is refused at the field.
#[test]
fn smoothing_iterations_are_bounded_at_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let e = mesh_scene_err(
        dir.path(),
        "tri.obj",
        tri,
        "smooth = { step = 0.1, iterations = 10001 }",
    );
    let msg = e.to_string();
    assert!(
        msg.contains("field `mesh.b.smooth.iterations`")
            && msg.contains("at most 10000 iterations"),
        "{msg}"
    );
    let at_limit = "smooth = { step = 0.1, iterations = 10000 }";
    if let Err(e) = load_mesh_scene(dir.path(), "tri.obj", tri, at_limit) {
        panic!("10 000 iterations refused: {e}");
    }
}

/// The fields of an effect the scene does not have are refused at their value: the lens's
/// `focus_distance` and `lens_samples` without a lens (no `aperture`, or `aperture = 0`: a
/// pinhole), and light `samples` on a directional light or on a point light without
/// `radius > 0` (no area light).
#[test]
fn samples_of_an_effect_that_is_off_are_refused() {
    let camera = |field: &str| BASE.replace("height = 6\n", &format!("height = 6\n{field}\n"));
    let lens = "only with `aperture` > 0";
    check(
        "focus.toml",
        &camera("focus_distance = 4"),
        "7:18",
        "camera.focus_distance",
        lens,
    );
    check(
        "lens.toml",
        &camera("lens_samples = 64"),
        "7:16",
        "camera.lens_samples",
        lens,
    );
    check(
        "focus0.toml",
        &camera("aperture = 0\nfocus_distance = 4"),
        "8:18",
        "camera.focus_distance",
        lens,
    );
    check(
        "lens0.toml",
        &camera("aperture = 0\nlens_samples = 64"),
        "8:16",
        "camera.lens_samples",
        lens,
    );
    let light = |fields: &str| format!("{BASE}\n[[light]]\n{fields}\nsamples = 8\n");
    let area = "only for point lights with `radius` > 0";
    check(
        "directional.toml",
        &light("type = \"directional\"\ndirection = [0, -1, 0]"),
        "14:11",
        "light[0].samples",
        area,
    );
    check(
        "point.toml",
        &light("type = \"point\"\nposition = [0, 4, 0]"),
        "14:11",
        "light[0].samples",
        area,
    );
    check(
        "radius0.toml",
        &light("type = \"point\"\nposition = [0, 4, 0]\nradius = 0"),
        "15:11",
        "light[0].samples",
        area,
    );
    // Control: with the effect on, the same fields load; a pinhole written as `aperture = 0`
    // too.
    let on = [
        camera("aperture = 0.1\nfocus_distance = 4\nlens_samples = 64"),
        camera("aperture = 0"),
        light("type = \"point\"\nposition = [0, 4, 0]\nradius = 0.5"),
    ];
    for text in on {
        halfray::scene::parse(&text, Path::new("on.toml")).unwrap_or_else(|e| panic!("{e}"));
    }
}

/// A quadric clipped by only one corner is named at the corner it has, with the missing one
/// said: `max` alone is `max` (it was reported as `min`, at `max`'s place), `min` alone `min`.
#[test]
fn a_half_clip_box_is_named_at_the_corner_given() {
    let quadric = |corner: &str| {
        format!(
            "{BASE}\n[[object]]\ntype = \"quadric\"\ncoefficients = {{ xx = 1, yy = 1, zz = 1, c = -1 }}\nmaterial = \"m\"\n{corner} = [1, 1, 1]\n"
        )
    };
    check(
        "max.toml",
        &quadric("max"),
        "15:7",
        "object[0].max",
        "`min` is missing",
    );
    check(
        "min.toml",
        &quadric("min"),
        "15:7",
        "object[0].min",
        "`max` is missing",
    );
}

/// A positive radius too small for `f32` is refused with what was written, not a `0` the
/// scene never says; zero itself with its value.
#[test]
fn a_positive_number_below_f32_is_named_as_written() {
    let sphere = |r: &str| {
        sphere_with(&format!(
            "center = [0, 0, 0]\nradius = {r}\nmaterial = \"m\""
        ))
    };
    check(
        "tiny.toml",
        &sphere("1e-400"),
        "14:10",
        "object[0].radius",
        "1e-400 is below the smallest positive `f32`",
    );
    check(
        "zero.toml",
        &sphere("0"),
        "14:10",
        "object[0].radius",
        "must be > 0 (got 0)",
    );
}
