//! `repeat` on an object: a grid of copies, each the object moved by its grid step after its own
//! transform, materials taken in turn; the same picture as the copies written out one by one;
//! errors name the file, line, column and field.

use halfray::render::{RenderOptions, render};
use halfray::scene::parse;
use std::path::Path;

mod common;
use common::{camera, directional_light, parse_scene, plane, scenes_dir};

/// The lit floor the copies stand on, and their materials `a`, `b`, `c`.
fn head() -> String {
    let camera = camera("[2, 6, 9]", "[2, 0, 1]", "50", [96, 72]);
    let light = directional_light("[-0.3, -1, -0.4]");
    let floor = plane("[0, 0, 0]", "[0, 1, 0]", "floor");
    format!(
        r#"
ambient = [0.1, 0.1, 0.1]

{camera}
{light}intensity = 0.9

[material.a]
diffuse = [0.8, 0.2, 0.2]

[material.b]
diffuse = [0.2, 0.8, 0.2]

[material.c]
diffuse = [0.2, 0.2, 0.8]

[material.floor]
diffuse = [0.6, 0.6, 0.6]

{floor}"#
    )
}

fn err(text: &str) -> String {
    match parse(text, Path::new("bad.toml")) {
        Ok(_) => panic!("loaded but should not"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn repeated_copies_render_like_the_copies_written_out() {
    // 3 × 1 × 2 boxes, each rotated then moved by its own transform, then by the grid step;
    // materials a, b, c in turn over the copies numbered i + 3·k.
    let head = head();
    let repeated = format!(
        "{head}
[[object]]
type = \"box\"
min = [-0.4, 0, -0.3]
max = [0.4, 0.7, 0.3]
material = \"a\"
transform = [{{ rotate = {{ axis = [0, 1, 0], degrees = 30 }} }}, {{ translate = [0.5, 0, 0] }}]
repeat = {{ count = [3, 1, 2], step = [1.5, 0, 2.0], materials = [\"a\", \"b\", \"c\"] }}
"
    );
    let mut written = head.clone();
    let names = ["a", "b", "c"];
    for k in 0..2 {
        for i in 0..3 {
            let n = i + 3 * k;
            let (x, z) = (0.5 + 1.5 * i as f32, 2.0 * k as f32);
            written += &format!(
                "
[[object]]
type = \"box\"
min = [-0.4, 0, -0.3]
max = [0.4, 0.7, 0.3]
material = \"{}\"
transform = [{{ rotate = {{ axis = [0, 1, 0], degrees = 30 }} }}, {{ translate = [{x}, 0, {z}] }}]
",
                names[n % 3]
            );
        }
    }
    let (r, w) = (parse_scene(&repeated), parse_scene(&written));
    assert_eq!(r.objects.len(), 7);
    assert_eq!(w.objects.len(), 7);
    let (ir, iw) = (
        render(&r, &RenderOptions::default()),
        render(&w, &RenderOptions::default()),
    );
    assert_eq!(ir.counts.primary, iw.counts.primary);
    assert_eq!(ir.counts.shadow, iw.counts.shadow);
    let differing = ir
        .pixels
        .iter()
        .zip(&iw.pixels)
        .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-6)
        .count();
    assert_eq!(
        differing, 0,
        "pixels differ between repeat and written-out copies"
    );
    // Every material shows up: the copies are not all one colour.
    let reds = ir
        .pixels
        .iter()
        .filter(|p| p.x > 2.0 * p.y && p.x > 2.0 * p.z)
        .count();
    let greens = ir
        .pixels
        .iter()
        .filter(|p| p.y > 2.0 * p.x && p.y > 2.0 * p.z)
        .count();
    let blues = ir
        .pixels
        .iter()
        .filter(|p| p.z > 2.0 * p.x && p.z > 2.0 * p.y)
        .count();
    assert!(
        reds > 20 && greens > 20 && blues > 20,
        "{reds} {greens} {blues}"
    );
}

#[test]
fn the_herd_scene_holds_ten_thousand_cows() {
    let path = scenes_dir().join("herd.toml");
    let s = halfray::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects.len(), 10_001, "the floor and 100 × 100 cows");
    assert_eq!(s.meshes.len(), 1, "one mesh shared by every copy");
}

#[test]
fn bad_repeats_name_their_field() {
    let head = head();
    let obj = |repeat: &str| {
        format!(
            "{head}\n[[object]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.5\nmaterial = \"a\"\nrepeat = {repeat}\n"
        )
    };
    let line = head.lines().count() + 7;
    let e = err(&obj("{ count = [2, 0, 2], step = [1, 0, 1] }"));
    assert!(
        e.starts_with(&format!("bad.toml:{line}:")) && e.contains("object[1].repeat.count"),
        "{e}"
    );
    assert!(e.contains("≥ 1"), "{e}");
    let e = err(&obj(
        "{ count = [2, 1, 2], step = [1, 0, 1], materials = [\"a\", \"z\"] }",
    ));
    assert!(
        e.contains("object[1].repeat.materials") && e.contains("`z`"),
        "{e}"
    );
    let e = err(&obj(
        "{ count = [2, 1, 2], step = [1, 0, 1], materials = [] }",
    ));
    assert!(e.contains("at least one material"), "{e}");
    let e = err(&obj("{ count = [2, 1], step = [1, 0, 1] }"));
    assert!(e.contains("bad.toml:") && e.contains("3 elements"), "{e}");
    let e = err(&obj("{ count = [2, 1, 2], step = [1, nan, 1] }"));
    assert!(e.contains("object[1].repeat.step"), "{e}");
    let e = err(&obj("{ count = [2, 1, 2], step = [1, 0, 1], jitter = 1 }"));
    assert!(e.contains("jitter"), "{e}");
    let e = err(&obj("{ count = [1000, 1000, 2], step = [1, 1, 1] }"));
    assert!(
        e.contains("object[1].repeat.count") && e.contains("1000000"),
        "{e}"
    );
    let csg = format!(
        "{head}\n[[object]]\ntype = \"csg\"\nop = \"union\"\nmaterial = \"a\"\noperands = [{{ type = \"sphere\", center = [0, 0, 0], radius = 1, repeat = {{ count = [2, 1, 1], step = [1, 0, 0] }} }}, {{ type = \"box\", min = [0, 0, 0], max = [1, 1, 1] }}]\n"
    );
    let e = err(&csg);
    assert!(
        e.contains("object[1].operands[0].repeat") && e.contains("top-level"),
        "{e}"
    );
}

/// A copy whose translation overflows `f32` is refused at `repeat.step`, naming the copy and
/// saying the translation overflows (not "singular": the object's own transform is
/// invertible and a translation leaves it so). Hand-worked: the sphere scaled by
/// `(0.25, 0.6, 0.4)` and turned 40° about z has the inverse translation
/// `−S⁻¹R⁻¹(t + (i·10³⁸, 0, 0))`, whose x is about `−4 · cos 40° · i·10³⁸ ≈ −3.06·10³⁸ · i`:
/// finite for copy 1, beyond `f32::MAX ≈ 3.40·10³⁸` for copy 2. Without a transform of its own,
/// copy 4 is the first moved beyond it (4·10³⁸).
#[test]
fn a_repeat_whose_translation_overflows_says_so() {
    let head = head();
    let line = head.lines().count() + 7;
    for (transform, copy) in [
        (
            "transform = [{ scale = [0.25, 0.6, 0.4] }, { rotate = { axis = [0, 0, 1], degrees = 40 } }, { translate = [-2, 0.7, -1] }]\n",
            "copy (2, 0, 0)",
        ),
        ("", "copy (4, 0, 0)"),
    ] {
        let e = err(&format!(
            "{head}\n[[object]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"a\"\n{transform}repeat = {{ count = [5, 1, 2], step = [1e38, 0, 1.2] }}\n"
        ));
        let line = line + usize::from(!transform.is_empty());
        assert!(
            e.starts_with(&format!("bad.toml:{line}:")) && e.contains("object[1].repeat.step"),
            "{e}"
        );
        assert!(
            e.contains(&format!("{copy}: the translation overflows")),
            "{e}"
        );
        assert!(!e.contains("singular"), "{e}");
    }
}

/// `repeat.materials` on a CSG object reaches every operand that inherits the object's
/// material (here a nested CSG object without one, and its spheres), while an operand with
/// its own material keeps it: each copy shows its material from the list, and red where the
/// red operand shows.
#[test]
fn repeated_csg_copies_take_their_material_down_to_the_inheriting_operands() {
    // A vertical field of view of 40° at distance 6 and a 3:1 image: the copies at x = −2, 0,
    // 2 lie in the columns below 41, 41 to 55 and above 55 (x = ±1 at column 48 ± 7.3).
    let camera = camera("[0, 0, 6]", "[0, 0, 0]", "40", [96, 32]);
    let scene = format!(
        r#"
{camera}
[[light]]
type = "directional"
direction = [0, 0, -1]
cast_shadows = false

[material.red]
diffuse = [1, 0, 0]
[material.green]
diffuse = [0, 1, 0]
[material.blue]
diffuse = [0, 0, 1]

[[object]]
type = "csg"
op = "union"
material = "red"
operands = [
  {{ type = "csg", op = "union", operands = [
    {{ type = "sphere", center = [-2, 0, 0], radius = 0.7 }},
    {{ type = "sphere", center = [-2, -0.5, 0.4], radius = 0.3 }},
  ] }},
  {{ type = "sphere", center = [-2, 0.5, 0.5], radius = 0.3, material = "red" }},
]
repeat = {{ count = [3, 1, 1], step = [2, 0, 0], materials = ["green", "blue"] }}
"#
    );
    let image = render(&parse_scene(&scene), &RenderOptions::default());
    // Per copy, the covered pixels whose red, green or blue channel is over twice the others.
    let mut dominant = [[0usize; 3]; 3];
    for j in 0..image.height {
        for i in 0..image.width {
            let p = image.pixel(i, j);
            let copy = match i {
                0..41 => 0,
                41..55 => 1,
                _ => 2,
            };
            for c in 0..3 {
                let (a, b) = (p[(c + 1) % 3], p[(c + 2) % 3]);
                if p.w > 0.0 && p[c] > 2.0 * a.max(b) {
                    dominant[copy][c] += 1;
                }
            }
        }
    }
    // Copies 0, 1, 2 take green, blue, green (channels 1, 2, 1); the other list colour never
    // shows on a copy, and the red operand shows on each.
    for (copy, (own, other)) in [(1, 2), (2, 1), (1, 2)].into_iter().enumerate() {
        let d = dominant[copy];
        assert!(d[own] > 40, "copy {copy}: {d:?}");
        assert_eq!(d[other], 0, "copy {copy}: {d:?}");
        assert!(
            d[0] > 3,
            "copy {copy}: the red operand keeps its material: {d:?}"
        );
    }
}
