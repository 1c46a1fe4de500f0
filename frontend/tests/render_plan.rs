//! The effect plan: only what the scene calls for is simulated, and the picture is the same as
//! with every effect forced on.

use halfray::render::plan::EffectPlan;
use halfray::render::trace::Tracer;
use halfray::render::{Mode, RenderOptions, render};
use halfray::scene::{Scene, load};
use std::path::Path;

mod common;
use common::{
    camera, directional_light, example_scene_paths, material, parse_scene, plane, point_light,
    scenes_dir, sphere,
};

/// A floor and a red sphere, lit by two lights that cast no shadows.
fn matte() -> String {
    let camera = camera("[0, 2, 6]", "[0, 0.5, 0]", "50", [64, 48]);
    let point = point_light("[2, 5, 3]", "30");
    let directional = directional_light("[-1, -1, -1]");
    let floor = plane("[0, 0, 0]", "[0, 1, 0]", "matte");
    let red = sphere("[-1.2, 0.6, 0]", "0.6", "red");
    format!(
        r#"
ambient = [0.1, 0.1, 0.1]

{camera}
{point}cast_shadows = false

{directional}intensity = 0.5
cast_shadows = false

[material.matte]
diffuse = [0.7, 0.7, 0.7]

[material.red]
diffuse = [0.8, 0.1, 0.1]

{floor}
{red}"#
    )
}

/// A mirror sphere (its material and object), to add to [`matte`].
fn mirror_sphere() -> String {
    let mirror = sphere("[1.0, 0.7, 0.2]", "0.7", "mirror");
    format!("\n[material.mirror]\ndiffuse = [0.1, 0.1, 0.1]\nmirror = 0.8\n\n{mirror}")
}

#[test]
fn matte_scene_without_shadow_lights_casts_one_ray_per_pixel() {
    let s = parse_scene(&matte());
    let plan = EffectPlan::derive(&s, false);
    assert_eq!(plan.max_depth, 0);
    assert!(plan.shadow_rays.iter().all(|&b| !b));
    assert!(plan.specular.iter().all(|&b| !b));
    let out = render(&s, &RenderOptions::default());
    assert_eq!(out.counts.total(), 64 * 48);
    assert_eq!(out.counts.primary, 64 * 48);
    let explain = plan.explain(&s, Mode::Color, 1);
    assert!(explain.contains("shadow rays      none"), "{explain}");
    assert!(explain.contains("recursion depth  0"), "{explain}");
}

#[test]
fn one_mirror_sphere_adds_reflection_rays_only_where_it_is_seen() {
    let s = parse_scene(&format!("{}{}", matte(), mirror_sphere()));
    let plan = EffectPlan::derive(&s, false);
    assert_eq!(plan.max_depth, s.max_depth);
    let out = render(&s, &RenderOptions::default());
    // Pixels whose primary ray hits the mirror sphere.
    let tracer = Tracer {
        scene: &s,
        plan: &plan,
    };
    let mirror = s.materials.iter().position(|m| m.name == "mirror").unwrap() as u32;
    let mut ctx = tracer.ctx();
    let mut seen = 0u64;
    for j in 0..48 {
        for i in 0..64 {
            let ray = s.camera.pixel_ray(i, j);
            if tracer
                .closest(&ray, &mut ctx)
                .is_some_and(|h| h.material == mirror)
            {
                seen += 1;
            }
        }
    }
    assert!(seen > 100, "the mirror sphere covers {seen} pixels");
    assert_eq!(out.counts.primary, 64 * 48);
    assert_eq!(out.counts.reflection, seen);
    assert_eq!(out.counts.shadow, 0);
    assert_eq!(out.counts.refraction, 0);
}

/// A mirror or glass material that no object uses turns nothing on: the plan follows the
/// objects, not the declarations.
#[test]
fn unused_materials_turn_no_effect_on() {
    let extra = "\n[material.unused_mirror]\ndiffuse = [0.1, 0.1, 0.1]\nmirror = 0.9\nspecular = [1, 1, 1]\n\n[material.unused_glass]\ntransparency = 0.9\nior = 1.5\n";
    let s = parse_scene(&format!("{}{extra}", matte()));
    let plan = EffectPlan::derive(&s, false);
    assert_eq!(plan.max_depth, 0);
    assert!(
        plan.reflect
            .iter()
            .chain(&plan.refract)
            .chain(&plan.specular)
            .all(|&b| !b)
    );
    let explain = plan.explain(&s, Mode::Color, 1);
    assert!(
        explain.contains("unused materials unused_glass, unused_mirror"),
        "{explain}"
    );
    // The specular line names the used materials only: `unused_mirror` (ks 1) is not
    // "skipped where ks = 0".
    assert!(
        explain.contains("specular term    none (skipped where ks = 0: matte, red)\n"),
        "{explain}"
    );
    let out = render(&s, &RenderOptions::default());
    assert_eq!(out.counts.total(), 64 * 48);
    assert_same_picture(&s, "unused materials");
    // Control: the same mirror material on the sphere turns reflection on.
    let used = format!("{}{extra}", matte()).replacen(
        "material = \"red\"",
        "material = \"unused_mirror\"",
        1,
    );
    let plan = EffectPlan::derive(&parse_scene(&used), false);
    assert!(plan.max_depth > 0 && plan.reflect.iter().any(|&b| b));
}

/// The plan casts reflection and refraction rays only where the tracer can: a `mirror` or
/// `transparency` below the path-weight floor 2⁻¹³ (1e-4 < 1/8192 ≈ 1.22e-4) plans none (no
/// recursion depth, no secondary rays in the worst case) and the render casts none; 2e-4
/// plans and casts them; glass at `ior = 1` refracts every ray (Snell's `k = cos²θ ≥ 0`), so it
/// plans refraction and no reflection, and casts no reflection ray.
#[test]
fn factors_below_the_path_weight_floor_and_ior_1_plan_only_rays_that_run() {
    use halfray::render::budget::Estimate;
    let with = |fields: &str| {
        let s = parse_scene(&format!(
            "{}\n[material.m]\ndiffuse = [0.5, 0.5, 0.5]\n{fields}\n\n{}",
            matte(),
            sphere("[1.0, 0.7, 0.2]", "0.7", "m")
        ));
        let plan = EffectPlan::derive(&s, false);
        let flags = plan.flags(&s, Mode::Color, 1);
        let secondary = Estimate::of(&s, &plan, Mode::Color, 1).secondary;
        let counts = render(&s, &RenderOptions::default()).counts;
        (plan.explain(&s, Mode::Color, 1), flags, secondary, counts)
    };
    for fields in ["mirror = 1e-4", "transparency = 1e-4\nior = 1.5"] {
        let (explain, flags, secondary, counts) = with(fields);
        assert!(
            explain.contains("recursion depth  0 ("),
            "{fields}: {explain}"
        );
        assert!(
            !flags.reflection && !flags.refraction,
            "{fields}: {flags:?}"
        );
        assert_eq!(secondary, 0.0, "{fields}");
        assert_eq!(counts.reflection + counts.refraction, 0, "{fields}");
    }
    // Control: just above the floor the rays are planned and cast.
    let (_, flags, secondary, counts) = with("mirror = 2e-4");
    assert!(flags.reflection && secondary > 0.0);
    assert!(counts.reflection > 0, "{counts:?}");
    let (_, flags, _, counts) = with("transparency = 2e-4\nior = 1.5");
    assert!(flags.refraction && flags.reflection, "{flags:?}");
    assert!(counts.refraction > 0, "{counts:?}");
    // Glass at ior 1: refraction only.
    let (explain, flags, _, counts) = with("transparency = 0.9\nior = 1");
    assert!(flags.refraction && !flags.reflection, "{flags:?}");
    assert!(
        counts.refraction > 0 && counts.reflection == 0,
        "{counts:?}"
    );
    assert!(explain.contains("reflection rays  none\n"), "{explain}");
}

/// A CSG object's own material shows only through operands that inherit it: a mirror CSG
/// object whose operands both name a matte material casts no reflection ray and counts none in
/// the worst case, like the same object in matte; with an operand that inherits it, it does.
#[test]
fn a_csg_material_no_operand_inherits_turns_no_effect_on() {
    let csg = |second: &str| {
        format!(
            "{}{}\n[[object]]\ntype = \"csg\"\nop = \"union\"\nmaterial = \"mirror\"\noperands = [\n  {{ type = \"sphere\", center = [1, 0.7, 0], radius = 0.7, material = \"matte\" }},\n  {{ type = \"sphere\", center = [1.5, 0.7, 0], radius = 0.5{second} }},\n]\n",
            matte(),
            "\n[material.mirror]\ndiffuse = [0.1, 0.1, 0.1]\nmirror = 0.8\n"
        )
    };
    let s = parse_scene(&csg(", material = \"red\""));
    let plan = EffectPlan::derive(&s, false);
    assert_eq!(plan.max_depth, 0);
    assert!(plan.reflect.iter().chain(&plan.refract).all(|&b| !b));
    let explain = plan.explain(&s, Mode::Color, 1);
    assert!(explain.contains("unused materials mirror"), "{explain}");
    let estimate = halfray::render::budget::Estimate::of(&s, &plan, Mode::Color, 1);
    assert_eq!(estimate.secondary, 0.0);
    let out = render(&s, &RenderOptions::default());
    assert_eq!(out.counts.total(), 64 * 48);
    assert_same_picture(&s, "mirror CSG over matte operands");
    // Control: the second operand inherits the mirror, which is then simulated.
    let inherits = parse_scene(&csg(""));
    let plan = EffectPlan::derive(&inherits, false);
    assert!(plan.max_depth > 0 && plan.reflect.iter().any(|&b| b));
    assert!(
        render(&inherits, &RenderOptions::default())
            .counts
            .reflection
            > 0
    );
}

/// A light of zero intensity (or colour) contributes nothing: no shadow rays are cast towards
/// it, `--explain` says why, and the picture equals the forced one (which does cast them).
#[test]
fn dark_lights_cast_no_shadow_rays() {
    let shadowed = matte().replacen("cast_shadows = false", "cast_shadows = true", 2);
    let dark = shadowed.replacen("intensity = 30", "intensity = 0", 1);
    let s = parse_scene(&dark);
    let plan = EffectPlan::derive(&s, false);
    assert_eq!(plan.shadow_rays, vec![false, true]);
    let explain = plan.explain(&s, Mode::Color, 1);
    assert!(explain.contains("zero intensity"), "{explain}");
    let out = render(&s, &RenderOptions::default());
    // Control: the same scene with the light lit casts shadow rays towards both.
    let lit = parse_scene(&shadowed);
    assert_eq!(
        EffectPlan::derive(&lit, false).shadow_rays,
        vec![true, true]
    );
    let lit_out = render(&lit, &RenderOptions::default());
    assert!(out.counts.shadow > 0 && lit_out.counts.shadow > out.counts.shadow);
    assert_same_picture(&s, "dark light");
    let zero_colour = shadowed.replacen("intensity = 30", "intensity = 30\ncolor = [0, 0, 0]", 1);
    assert_eq!(
        EffectPlan::derive(&parse_scene(&zero_colour), false).shadow_rays,
        vec![false, true]
    );
}

/// The modes whose picture `--force-all-effects` leaves the same (scenes/README.md, `render
/// --help`): every mode but the heat map, which shows the work done.
fn same_picture_modes() -> Vec<Mode> {
    let all = <Mode as clap::ValueEnum>::value_variants();
    all.iter()
        .copied()
        .filter(|&m| m != Mode::Heatmap)
        .collect()
}

/// `render --help` and scenes/README.md say for which modes the forced picture is the same:
/// each of [`same_picture_modes`] is named, and the heat map is said to differ.
#[test]
fn the_docs_name_the_modes_whose_forced_picture_is_the_same() {
    let help = common::halfray(&[&"render", &"--help"]);
    let help = String::from_utf8(help.stdout).unwrap();
    // As one line: the help is wrapped to the terminal's width.
    let help = help.split_whitespace().collect::<Vec<_>>().join(" ");
    let readme = std::fs::read_to_string(scenes_dir().join("README.md")).unwrap();
    let paragraph = readme
        .split("\n\n")
        .find(|p| p.starts_with("`--force-all-effects` turns everything on"))
        .unwrap();
    assert!(
        help.contains(
            "the picture is the same in every mode but `heatmap`, which shows the work done"
        ),
        "{help}"
    );
    for mode in same_picture_modes() {
        let name = clap::ValueEnum::to_possible_value(&mode).unwrap();
        assert!(
            paragraph.contains(&format!("`{}`", name.get_name())),
            "{paragraph}"
        );
    }
    assert!(
        paragraph.contains("`heatmap` is the exception"),
        "{paragraph}"
    );
}

fn assert_same_picture(s: &Scene, what: &str) {
    let modes = same_picture_modes();
    assert!(modes.contains(&Mode::Barycentric), "{modes:?}");
    for mode in modes {
        let opts = RenderOptions {
            mode,
            ..RenderOptions::default()
        };
        let planned = render(s, &opts);
        let forced = render(
            s,
            &RenderOptions {
                force_all: true,
                ..opts.clone()
            },
        );
        let a = planned.to_rgba8(mode, Default::default());
        let b = forced.to_rgba8(mode, Default::default());
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap_or(0);
        assert!(
            worst <= 1,
            "{what} ({mode:?}): plan vs forced differ by {worst}/255"
        );
        if mode == Mode::Color {
            assert!(
                forced.counts.total() >= planned.counts.total(),
                "{what}: forcing cast fewer rays"
            );
        }
    }
}

#[test]
fn plan_never_changes_the_picture_on_test_scenes() {
    assert_same_picture(&parse_scene(&matte()), "matte");
    assert_same_picture(
        &parse_scene(&format!("{}{}", matte(), mirror_sphere())),
        "mirror",
    );
}

#[test]
fn plan_never_changes_the_picture_on_example_scenes() {
    let mut n = 0;
    for path in example_scene_paths() {
        // bunny.toml reads ../shared/meshes beside the checkout (CI has it): every example
        // scene loads, none is skipped.
        let mut s = load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        s.camera.width = 48;
        s.camera.height = 36;
        assert_same_picture(&s, &path.display().to_string());
        n += 1;
    }
    assert!(n >= 8, "{n} example scenes checked");
}

/// The `--stats-json` of rendering `scene` at 24×16 with `extra` options (image and stats
/// written in `dir`); the render must succeed.
fn stats_of(dir: &Path, scene: &Path, extra: &[&str]) -> serde_json::Value {
    render_cli(dir, scene, extra).1
}

/// The standard output and the `--stats-json` of rendering `scene` at 24×16 with `extra`
/// options (image and stats written in `dir`); the render must succeed.
fn render_cli(dir: &Path, scene: &Path, extra: &[&str]) -> (String, serde_json::Value) {
    let json = dir.join("stats.json");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_halfray"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(dir.join("out.png"))
        .args(["--width", "24", "--height", "16", "-q", "--stats-json"])
        .arg(&json)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stats = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    (String::from_utf8_lossy(&o.stdout).into_owned(), stats)
}

/// `--stats-json` reports the plan, one boolean per effect, beside the ray counts it explains.
#[test]
fn stats_json_reports_the_plan_next_to_the_ray_counts() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("matte.toml");
    std::fs::write(&scene_path, matte()).unwrap();
    let run = |scene: &Path, extra: &[&str]| stats_of(dir.path(), scene, extra);
    // Matte, no shadow-casting light: every effect off, and no ray of any of them.
    let v = run(&scene_path, &[]);
    let plan = &v["plan"];
    for effect in [
        "shadow",
        "reflection",
        "refraction",
        "specular",
        "antialias",
        "csg_intervals",
    ] {
        assert_eq!(plan[effect], false, "{effect}: {v}");
    }
    for rays in ["shadow", "reflection", "refraction"] {
        assert_eq!(v[rays], 0, "{rays}: {v}");
    }
    assert_eq!(v["primary"], 24 * 16);
    // Forced: everything the renderer can simulate is on (and costs rays).
    let v = run(&scene_path, &["--force-all-effects"]);
    for effect in [
        "shadow",
        "reflection",
        "refraction",
        "specular",
        "csg_intervals",
    ] {
        assert_eq!(v["plan"][effect], true, "{effect}: {v}");
    }
    assert!(v["shadow"].as_u64().unwrap() > 0);
    // The glass scene: refraction and reflection on, because its objects use glass.
    let v = run(&scenes_dir().join("glass.toml"), &[]);
    assert_eq!(v["plan"]["refraction"], true, "{v}");
    assert_eq!(v["plan"]["reflection"], true, "{v}");
    assert!(v["refraction"].as_u64().unwrap() > 0);
    // Anti-aliasing from the scene's `samples`, overridden by `--samples`.
    let aa_path = dir.path().join("aa.toml");
    std::fs::write(&aa_path, format!("samples = 4\n{}", matte())).unwrap();
    let v = run(&aa_path, &[]);
    assert_eq!(v["plan"]["antialias"], true, "{v}");
    assert!(
        v["primary"].as_u64().unwrap() > 24 * 16,
        "edges get extra samples: {v}"
    );
    let v = run(&aa_path, &["--samples", "1"]);
    assert_eq!(v["plan"]["antialias"], false, "{v}");
    assert_eq!(v["primary"], 24 * 16);
    for bad in ["samples = 0", "samples = 65"] {
        let bad_path = dir.path().join("bad.toml");
        std::fs::write(&bad_path, format!("{bad}\n{}", matte())).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_halfray"))
            .arg("render")
            .arg(&bad_path)
            .arg("-o")
            .arg(dir.path().join("bad.png"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{bad}: {err}");
        assert!(
            err.contains("bad.toml:1:11: field `samples`: must be 1 to 64"),
            "{err}"
        );
        assert!(!dir.path().join("bad.png").exists());
    }
}

/// A floor lit by a point light straight above it, seen from above; `pane` adds a large
/// horizontal triangle of the given transparency between them (one surface crossing).
fn pane_scene(pane: Option<f32>) -> Scene {
    let camera = camera("[0, 10, 0.001]", "[0, 0, 0]", "10", [9, 9]);
    let light = point_light("[0, 4, 0]", "16");
    let floor = plane("[0, 0, 0]", "[0, 1, 0]", "floor");
    let black = "[0, 0, 0]";
    let floor_paint = material("floor", &[("diffuse", "[1, 1, 1]"), ("specular", black)]);
    let transparency = pane.unwrap_or(0.5).to_string();
    let glass = material(
        "glass",
        &[
            ("diffuse", black),
            ("specular", black),
            ("transparency", &transparency),
            ("ior", "1.0"),
        ],
    );
    let mut text = format!(
        r#"
ambient = [0, 0, 0]

{camera}
{light}
{floor_paint}
{glass}
{floor}"#,
    );
    if pane.is_some() {
        text.push_str(
            r#"
[[object]]
type = "triangle"
vertices = [[-50, 2, -50], [0, 2, 80], [50, 2, -50]]
material = "glass"
"#,
        );
    }
    parse_scene(&text)
}

/// Shadows through glass: the light reaching the floor under a pane of transparency `τ` is
/// `τ` times the light without it (the analytic expectation: one crossing, Lambert otherwise
/// unchanged); an opaque pane (`τ = 0`) blocks it; and a scene with no transparent material
/// casts exactly one shadow ray per lit point, as before.
#[test]
fn shadows_through_glass_are_attenuated_by_the_transmission() {
    let floor_only = render(&pane_scene(None), &RenderOptions::default());
    let plan = EffectPlan::derive(&pane_scene(None), false);
    assert!(
        !plan.shadow_transmission,
        "no transparent material: no transmission walk"
    );
    assert_eq!(floor_only.counts.shadow, 81, "one shadow ray per pixel");
    let centre = floor_only.pixel(4, 4);
    assert!(centre.x > 0.1, "{centre}");
    for tau in [0.25f32, 0.5, 0.8] {
        let s = pane_scene(Some(tau));
        assert!(EffectPlan::derive(&s, false).shadow_transmission);
        let lit = render(&s, &RenderOptions::default());
        // The camera looks through the pane too: the floor is seen through it (refraction
        // with ior 1, weight τ), lit through it (τ): τ² of the bare floor at the centre.
        let got = lit.pixel(4, 4);
        let want = centre.x * tau * tau;
        assert!(
            (got.x - want).abs() <= 1e-4 * centre.x,
            "τ = {tau}: {} vs {want}",
            got.x
        );
        // Two shadow segments per floor point under the pane (pane, then the light).
        assert!(lit.counts.shadow >= 2 * 81, "{:?}", lit.counts);
    }
    let opaque = render(&pane_scene(Some(0.0)), &RenderOptions::default());
    assert_eq!(opaque.pixel(4, 4).x, 0.0);
}

/// A floor under `panes` clear panes (`transparency = 1`, `ior = 1`, black), 0.2 apart, seen
/// from straight above by a 2 × 2 orthographic camera and lit straight down by a directional
/// light of intensity 0.5; no ambient term.
fn stacked_panes(panes: u32) -> Scene {
    parse_scene(&format!(
        r#"
max_depth = 64
ambient = [0, 0, 0]

[camera]
type = "orthographic"
eye = [0, 5, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
view_size = 1
width = 2
height = 2

{light}intensity = 0.5

[material.floor]
diffuse = [1, 1, 1]

[material.pane]
diffuse = [0, 0, 0]
ambient = [0, 0, 0]
transparency = 1.0
ior = 1.0

{floor}
[[object]]
type = "box"
min = [-1, 0.5, -1]
max = [1, 0.6, 1]
material = "pane"
repeat = {{ count = [1, {panes}, 1], step = [0, 0.2, 0] }}
"#,
        light = directional_light("[0, -1, 0]"),
        floor = plane("[0, 0, 0]", "[0, 1, 0]", "floor"),
    ))
}

/// A shadow ray crosses at most 16 transparent surfaces (`MAX_SHADOW_CROSSINGS`, 8 panes) and
/// a 17th blocks the light. Hand-worked: every pixel sees the floor through the clear panes, lit
/// through them by `kd · I · n·l · 1¹⁶ = 1 · 0.5 · 1 · 1 = 0.5` under 8 panes, and by 0 under 9;
/// both cast 17 shadow segments per pixel (16 crossings and the one that reaches the light or
/// meets the 17th surface), and the camera ray crosses every surface (2 per pane refraction
/// rays). The batched and the one-ray-at-a-time renders agree.
#[test]
fn sixteen_crossings_transmit_and_a_seventeenth_blocks() {
    for (panes, lit) in [(8u32, 0.5f32), (9, 0.0)] {
        let scene = stacked_panes(panes);
        for single_rays in [false, true] {
            let opts = RenderOptions {
                single_rays,
                ..RenderOptions::default()
            };
            let out = render(&scene, &opts);
            let what = format!("{panes} panes, single rays {single_rays}: {:?}", out.counts);
            assert!(out.plan.shadow_transmission, "{what}");
            for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = out.pixel(i, j);
                assert_eq!([p.x, p.y, p.z], [lit; 3], "pixel ({i}, {j}), {what}");
            }
            assert_eq!(out.counts.primary, 4, "{what}");
            assert_eq!(out.counts.shadow, 4 * 17, "{what}");
            assert_eq!(out.counts.refraction, 4 * 2 * u64::from(panes), "{what}");
            assert_eq!(out.counts.reflection, 0, "{what}");
        }
    }
}

/// Exact shadow-ray counts with mixed lights: a floor seen from straight above fills
/// all 9 × 9 pixels, so every pixel shades one floor point with normal `+y`. A shadow ray goes
/// to each light that casts shadows, is not dark and lies on the lit side (`n·l > 0`): here the
/// point light above and the downward directional light, 2 × 81 rays. Not to the light above
/// with `cast_shadows = false`, the dark one, the point light below the floor, nor the upward
/// directional one. The scene casts no other ray (no mirror, no glass).
#[test]
fn shadow_rays_are_counted_exactly_per_casting_light() {
    let camera = camera("[0, 10, 0.001]", "[0, 0, 0]", "10", [9, 9]);
    let floor = plane("[0, 0, 0]", "[0, 1, 0]", "floor");
    let lights = [
        point_light("[1, 4, 0]", "16"),
        point_light("[-1, 4, 0]", "16") + "cast_shadows = false\n",
        directional_light("[0.2, -1, 0.1]"),
        point_light("[0, 3, 1]", "0"),
        point_light("[0, -3, 0]", "16"),
        directional_light("[0, 1, 0]"),
    ]
    .concat();
    let text = format!(
        "ambient = [0, 0, 0]\n\n{camera}\n{lights}\n[material.floor]\ndiffuse = [1, 1, 1]\n\n{floor}"
    );
    let s = parse_scene(&text);
    let out = render(&s, &RenderOptions::default());
    assert_eq!(out.counts.primary, 81);
    assert_eq!(out.counts.shadow, 2 * 81, "{:?}", out.counts);
    assert_eq!(out.counts.total(), 3 * 81, "{:?}", out.counts);
    // Control: every light casting shadows (the dark one still casts none).
    let all = text.replace("cast_shadows = false\n", "");
    let out = render(&parse_scene(&all), &RenderOptions::default());
    assert_eq!(out.counts.shadow, 3 * 81, "{:?}", out.counts);
}

/// A material whose direct term is 0 whatever the light (`diffuse` 0, no specular: a pure
/// mirror) casts no shadow ray: a floor of it that fills the view under a shadow-casting light
/// costs one primary and one reflection ray (to the empty sky) per pixel and no shadow ray; the
/// same floor in grey casts one shadow ray per pixel. The picture is the forced one.
#[test]
fn surfaces_without_a_direct_term_cast_no_shadow_rays() {
    let camera = camera("[0, 10, 0.001]", "[0, 0, 0]", "10", [9, 9]);
    let floor = plane("[0, 0, 0]", "[0, 1, 0]", "floor");
    let light = point_light("[1, 4, 0]", "16");
    let text = |diffuse: &str| {
        format!(
            "ambient = [0, 0, 0]\n\n{camera}\n{light}\n[material.floor]\ndiffuse = {diffuse}\nmirror = 0.5\n\n{floor}"
        )
    };
    let black = parse_scene(&text("[0, 0, 0]"));
    let out = render(&black, &RenderOptions::default());
    assert_eq!(out.counts.primary, 81, "{:?}", out.counts);
    assert_eq!(out.counts.reflection, 81, "{:?}", out.counts);
    assert_eq!(out.counts.shadow, 0, "{:?}", out.counts);
    assert_same_picture(&black, "black mirror floor");
    // `--explain` says so: no shadow rays, though the light casts them.
    let shadow_line = |s: &Scene| {
        let text = EffectPlan::derive(s, false).explain(s, Mode::Color, 1);
        let line = text.lines().find(|l| l.contains("shadow rays")).unwrap();
        line.trim_start()["shadow rays".len()..].trim().to_string()
    };
    assert!(
        shadow_line(&black).starts_with("none "),
        "{}",
        shadow_line(&black)
    );
    let grey_scene = parse_scene(&text("[0.5, 0.5, 0.5]"));
    let grey = render(&grey_scene, &RenderOptions::default());
    assert_eq!(grey.counts.shadow, 81, "{:?}", grey.counts);
    assert!(shadow_line(&grey_scene).starts_with("towards "));
}

/// `--stats-json`'s plan says `true` only for effects that run: none of the shading effects
/// outside colour mode, no reflection with `max_depth = 0`; the ray counts agree.
#[test]
fn stats_json_plan_flags_effects_that_cannot_run_as_off() {
    let dir = tempfile::tempdir().unwrap();
    let run = |text: &str, extra: &[&str]| -> serde_json::Value {
        let scene = dir.path().join("scene.toml");
        std::fs::write(&scene, text).unwrap();
        stats_of(dir.path(), &scene, extra)
    };
    let mirror = std::fs::read_to_string(scenes_dir().join("mirror.toml")).unwrap();
    // Control: in colour, the mirror scene's shadows, reflections and specular run.
    let v = run(&mirror, &[]);
    for effect in ["shadow", "reflection", "specular"] {
        assert_eq!(v["plan"][effect], true, "{effect}: {v}");
    }
    let flat = mirror.replace("max_depth = 4", "max_depth = 0");
    assert_ne!(flat, mirror);
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, &flat).unwrap();
    let (out, v) = render_cli(dir.path(), &scene, &["--explain"]);
    assert_eq!(v["plan"]["reflection"], false, "{v}");
    assert_eq!(v["reflection"], 0, "{v}");
    assert_eq!(v["plan"]["shadow"], true, "{v}");
    // `--explain` gives the depth as the reason, not a missing mirror.
    assert!(
        out.contains("reflection rays  none\n")
            && out.contains("recursion depth  0 (scene max_depth 0)\n"),
        "{out}"
    );
    let lens = mirror.replace("height = 480\n", "height = 480\naperture = 0.1\n");
    for (text, mode) in [(&mirror, "depth"), (&mirror, "normal"), (&lens, "depth")] {
        let v = run(text, &["--mode", mode, "--samples", "4"]);
        let flags = v["plan"].as_object().unwrap();
        assert!(flags.len() >= 9, "{v}");
        for (effect, on) in flags {
            assert_eq!(on, false, "{effect} in --mode {mode}: {v}");
        }
        for rays in ["shadow", "reflection", "refraction"] {
            assert_eq!(v[rays], 0, "{rays}: {v}");
        }
    }
}

/// `--explain` states what the render in its mode simulates: outside colour mode (one ray per
/// pixel) the mirror scene, with a shadow-casting light, mirrors and a specular material, lists
/// no shadow, reflection or refraction rays and no specular term, each `none` with the mode as
/// the reason, as the ray counts and the plan of `--stats-json` have it; in colour it lists
/// them, and the render casts them.
#[test]
fn explain_lists_only_the_effects_of_the_render_mode() {
    let dir = tempfile::tempdir().unwrap();
    let mirror = scenes_dir().join("mirror.toml");
    // The text after the label of `--explain`'s line `label`.
    let line = |out: &str, label: &str| -> String {
        let l = out
            .lines()
            .find(|l| l.trim_start().starts_with(label))
            .unwrap_or_else(|| panic!("no {label} line in {out}"));
        l.trim_start()[label.len()..].trim().to_string()
    };
    // Line label, `--stats-json` plan flag and ray count (if the effect has rays of its own).
    let effects = [
        ("shadow rays", "shadow", Some("shadow")),
        ("reflection rays", "reflection", Some("reflection")),
        ("refraction rays", "refraction", Some("refraction")),
        ("specular term", "specular", None),
    ];
    for mode in ["depth", "normal", "barycentric", "heatmap"] {
        let (out, v) = render_cli(dir.path(), &mirror, &["--explain", "--mode", mode]);
        let why = format!("none (mode {mode}: one ray per pixel)");
        for (label, flag, rays) in effects {
            assert_eq!(line(&out, label), why, "{label}, --mode {mode}: {out}");
            assert_eq!(v["plan"][flag], false, "{flag}, --mode {mode}: {v}");
            if let Some(k) = rays {
                assert_eq!(v[k], 0, "{k}, --mode {mode}: {v}");
            }
        }
        assert_eq!(
            line(&out, "shadow transmission"),
            format!("off (mode {mode}: one ray per pixel)"),
            "{out}"
        );
        assert!(
            line(&out, "recursion depth").starts_with("0 (mode"),
            "{out}"
        );
        assert!(!out.contains("ray tree bound"), "--mode {mode}: {out}");
        assert!(!out.contains("direct lighting"), "--mode {mode}: {out}");
        assert_eq!(v["primary"], 24 * 16, "{v}");
    }
    // Colour: shadows towards the light, the mirror's reflections and the red material's
    // specular term are listed and run; refraction (no transparent material) does neither.
    let (out, v) = render_cli(dir.path(), &mirror, &["--explain"]);
    assert!(line(&out, "shadow rays").starts_with("towards "), "{out}");
    assert_eq!(
        line(&out, "reflection rays"),
        "mirror (mirror 0.9)",
        "{out}"
    );
    assert!(line(&out, "specular term").starts_with("red "), "{out}");
    assert_eq!(line(&out, "refraction rays"), "none", "{out}");
    assert!(out.contains("ray tree bound"), "{out}");
    for (label, flag, rays) in effects {
        let listed = !line(&out, label).starts_with("none");
        assert_eq!(v["plan"][flag], listed, "{flag}: {out}\n{v}");
        if let Some(k) = rays {
            assert_eq!(v[k].as_u64().unwrap() > 0, listed, "{k}: {out}\n{v}");
        }
    }
}

/// `--explain`'s primary-ray line is the render's: the thin-lens scene casts `lens_samples`
/// rays a pixel (as many as `--stats-json` counts, its `depth_of_field` on), its area light is
/// named with its disk's shadow rays (`area_lights` on); `--samples 8` on the mirror scene is
/// adaptive anti-aliasing (`antialias` on), at most 8 a pixel, at least one (the counts).
#[test]
fn explain_names_the_camera_rays_and_area_lights_of_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let primary = |out: &str| -> String {
        out.lines()
            .find_map(|l| l.trim_start().strip_prefix("primary rays"))
            .unwrap_or_else(|| panic!("no primary rays line in {out}"))
            .trim()
            .to_string()
    };
    let (out, v) = render_cli(dir.path(), &scenes_dir().join("soft.toml"), &["--explain"]);
    assert_eq!(v["plan"]["depth_of_field"], true, "{v}");
    assert_eq!(v["plan"]["area_lights"], true, "{v}");
    let line = primary(&out);
    let count = 24 * 16 * 16u64;
    assert!(
        line.starts_with(&format!("24 × 16 × 16 = {count} (depth of field")),
        "{out}"
    );
    assert_eq!(v["primary"].as_u64(), Some(count), "{v}");
    assert!(
        out.contains("softbox (point, area: radius 0.9, 16 shadow rays over its disk)"),
        "{out}"
    );
    let mirror = scenes_dir().join("mirror.toml");
    let (out, v) = render_cli(dir.path(), &mirror, &["--explain", "--samples", "8"]);
    assert_eq!(v["plan"]["antialias"], true, "{v}");
    let line = primary(&out);
    assert!(
        line.starts_with("24 × 16 = 384 through the pixel centres, then up to 7 more")
            && line.contains("at most 8 a pixel"),
        "{out}"
    );
    let rays = v["primary"].as_u64().unwrap();
    assert!((384..=384 * 8).contains(&rays), "{v}");
}

/// Names from the scene reach `--explain` escaped: a light and a material whose names hold a
/// terminal escape, a bell and a line break print as `\u{1b}`, `\u{7}`, `\n`, so no line of the
/// plan starts with a forged `error:`, and no control character but the line breaks is printed.
#[test]
fn explain_escapes_names_from_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let camera = camera("[0, 2, 6]", "[0, 0.5, 0]", "50", [64, 48]);
    let light = point_light("[2, 5, 3]", "30");
    let floor = plane("[0, 0, 0]", "[0, 1, 0]", "m\\u001b[31mRED");
    let scene = format!(
        "{camera}\n{light}name = \"L\\u001b]0;T\\u0007\\nerror: forged\"\n\n[material.\"m\\u001b[31mRED\"]\ndiffuse = [0.5, 0.5, 0.5]\nspecular = [0.5, 0.5, 0.5]\n\n{floor}"
    );
    let path = dir.path().join("esc.toml");
    std::fs::write(&path, scene).unwrap();
    let (out, _) = render_cli(dir.path(), &path, &["--explain"]);
    assert!(!out.chars().any(|c| c.is_control() && c != '\n'), "{out:?}");
    assert!(!out.lines().any(|l| l.starts_with("error:")), "{out}");
    assert!(
        out.contains("L\\u{1b}]0;T\\u{7}\\nerror: forged (point)"),
        "{out}"
    );
    assert!(out.contains("m\\u{1b}[31mRED"), "{out}");
}

/// The specular term is evaluated per light: a scene without lights, whose material has a
/// specular colour, evaluates none, so `--stats-json`'s `plan.specular` is `false` and
/// `--explain` says why; one light turns it on.
#[test]
fn no_lights_no_specular_term() {
    let dir = tempfile::tempdir().unwrap();
    let camera = camera("[0, 2, 6]", "[0, 0.5, 0]", "50", [64, 48]);
    let shiny = material(
        "shiny",
        &[
            ("diffuse", "[0.5, 0.5, 0.5]"),
            ("specular", "[0.5, 0.5, 0.5]"),
        ],
    );
    let ball = sphere("[0, 0.5, 0]", "0.5", "shiny");
    let path = dir.path().join("dark.toml");
    std::fs::write(
        &path,
        format!("ambient = [0.2, 0.2, 0.2]\n\n{camera}\n{shiny}\n{ball}"),
    )
    .unwrap();
    let (out, v) = render_cli(dir.path(), &path, &["--explain"]);
    assert_eq!(v["plan"]["specular"], false, "{v}");
    assert!(out.contains("specular term    none (no lights)"), "{out}");
    let light = point_light("[2, 5, 3]", "30");
    std::fs::write(
        &path,
        format!("ambient = [0.2, 0.2, 0.2]\n\n{camera}\n{light}\n{shiny}\n{ball}"),
    )
    .unwrap();
    let (out, v) = render_cli(dir.path(), &path, &["--explain"]);
    assert_eq!(v["plan"]["specular"], true, "{v}");
    assert!(out.contains("specular term    shiny"), "{out}");
}

/// The README's render example (`render scenes/mirror.toml … --explain --stats-json …`) is
/// what the command prints: each plan line it shows is a line of the command's output, in
/// order, and its ray counts are the run's (`--stats-json`).
#[test]
fn the_readmes_render_example_is_what_the_command_prints() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md"))
            .unwrap();
    let block: Vec<&str> = readme
        .lines()
        .skip_while(|l| !l.starts_with("effect plan for scenes/mirror.toml:"))
        .take_while(|l| !l.starts_with("```"))
        .collect();
    let (plan, rays): (Vec<&str>, Vec<&str>) = block
        .iter()
        .filter(|l| l.trim() != "…")
        .partition(|l| !l.starts_with("rays: "));
    assert!(
        plan.len() > 5 && rays.len() == 1,
        "the README's block: {block:?}"
    );
    let dir = tempfile::tempdir().unwrap();
    let (png, json) = (
        dir.path().join("mirror.png"),
        dir.path().join("mirror.json"),
    );
    let o = common::halfray(&[
        &"render",
        &scenes_dir().join("mirror.toml"),
        &"-o",
        &png,
        &"--explain",
        &"--stats-json",
        &json,
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    let printed: Vec<&str> = out.lines().collect();
    let mut at = 0;
    for want in &plan {
        let want = want.replace(
            "scenes/mirror.toml",
            &scenes_dir().join("mirror.toml").display().to_string(),
        );
        let found = printed[at..].iter().position(|l| *l == want);
        at += found.unwrap_or_else(|| panic!("README: `{want}` not printed in order:\n{out}")) + 1;
    }
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let count = |k: &str| stats[k].as_u64().unwrap();
    let (p, s, r, t) = (
        count("primary"),
        count("shadow"),
        count("reflection"),
        count("refraction"),
    );
    let want = format!(
        "rays: primary {p} shadow {s} reflection {r} refraction {t} (total {})",
        p + s + r + t
    );
    assert!(
        rays[0].starts_with(&want),
        "README: {}\nrun: {want}",
        rays[0]
    );
}
