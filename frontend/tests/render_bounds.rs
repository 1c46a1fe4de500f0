//! What bounds the work of a render: the Whitted ray tree of mirror + transparent
//! materials is cut by path weight and a cap per camera ray ([`PathBound`]), checked against the
//! exhaustive tree; `--force-all-effects` stays bit-identical when radiance overflows.

use halfray::render::bound::{MAX_SECONDARY_RAYS_PER_CAMERA_RAY, PathBound};
use halfray::render::budget::Estimate;
use halfray::render::plan::EffectPlan;
use halfray::render::{Mode, RenderOptions, render};
use halfray::scene::{self, Scene};
use std::path::Path;
use std::time::{Duration, Instant};

mod common;
use common::{
    camera, example_scene_paths, halfray, material, plane, point_light, scenes_dir, sphere, stderr,
};

/// Largest difference, in 8-bit steps, between the bounded and the exhaustive tree: the
/// weight cut is chosen to stay under half a step per skipped subtree (see `MIN_PATH_WEIGHT`);
/// rounding of the two sums to 8 bits can still land on either side of a step.
const MAX_STEP_DIFFERENCE: u8 = 1;
/// Generous wall-clock limit for the max_depth 64 render that used never to finish.
const DEEP_RENDER_LIMIT: Duration = Duration::from_secs(120);

fn glass(max_depth: u32) -> Scene {
    let path = scenes_dir().join("glass.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("max_depth = 8", &format!("max_depth = {max_depth}"))
        .replace("width = 640", "width = 64")
        .replace("height = 480", "height = 48");
    assert!(text.contains(&format!("max_depth = {max_depth}")));
    scene::parse(&text, &path).unwrap()
}

fn opts(bound: PathBound) -> RenderOptions {
    RenderOptions {
        bound,
        ..RenderOptions::default()
    }
}

fn max_step_difference(a: &[u8], b: &[u8]) -> u8 {
    a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap()
}

#[test]
fn deep_glass_finishes_and_matches_the_exhaustive_tree() {
    let t0 = Instant::now();
    let deep = render(&glass(64), &opts(PathBound::RENDER));
    assert!(t0.elapsed() < DEEP_RENDER_LIMIT, "{:?}", t0.elapsed());
    let pixels = u64::from(deep.width * deep.height);
    let secondary = deep.counts.reflection + deep.counts.refraction;
    assert!(secondary <= pixels * u64::from(MAX_SECONDARY_RAYS_PER_CAMERA_RAY));
    // The oracle: every ray of the tree down to depth 24, where deeper trees give
    // the same bytes.
    let exact = render(&glass(24), &opts(PathBound::EXHAUSTIVE));
    assert!(
        exact.counts.total() > deep.counts.total(),
        "the bound cut something"
    );
    let d = max_step_difference(
        &deep.to_rgba8(Mode::Color, Default::default()),
        &exact.to_rgba8(Mode::Color, Default::default()),
    );
    assert!(d <= MAX_STEP_DIFFERENCE, "bounded vs exhaustive: {d}/255");
}

/// A camera inside two nested spheres that reflect everything, the inner one transmitting
/// everything and the outer one `outer_transparency`; with `light`, a point light at the
/// centre. Weights never fall: with an outer transparency of 1 both rays of every hit go on,
/// the tree is 2^64 without the cap per camera ray.
fn hall_of_mirrors(outer_transparency: &str, light: bool) -> String {
    let camera = camera("[0, 0, 0]", "[0, 0, -1]", "60", [4, 4]);
    let light = if light {
        point_light("[0, 0, 0]", "1.0")
    } else {
        String::new()
    };
    let glass = |name: &str, transparency: &str| {
        let fields = [
            ("diffuse", "[0.1, 0.1, 0.1]"),
            ("mirror", "1.0"),
            ("transparency", transparency),
            ("ior", "1.5"),
        ];
        material(name, &fields)
    };
    format!(
        "\nmax_depth = 64\nbackground = [0.2, 0.3, 0.4]\n{camera}{light}{}{}{}{}",
        glass("both", "1.0"),
        glass("outer", outer_transparency),
        sphere("[0, 0, 0]", "1.0", "both"),
        sphere("[0, 0, 0]", "2.0", "outer"),
    )
}

#[test]
fn weights_that_never_fall_stop_at_the_cap_per_camera_ray() {
    let s = scene::parse(&hall_of_mirrors("1.0", true), Path::new("hall.toml")).unwrap();
    let r = render(&s, &opts(PathBound::RENDER));
    let pixels = u64::from(r.width * r.height);
    let secondary = r.counts.reflection + r.counts.refraction;
    let cap = pixels * u64::from(MAX_SECONDARY_RAYS_PER_CAMERA_RAY);
    assert!(secondary <= cap, "{secondary} > {cap}");
    assert!(
        secondary >= cap / 2,
        "the cap is what stopped it: {secondary}"
    );
}

/// The cap on secondary rays is per camera ray, as `--explain` and `docs/bad-input.md` say,
/// not per pixel: one pixel of 4 lens samples inside the hall of mirrors (both shells reflect
/// and transmit everything, weights never fall) casts more than 4096 reflection + refraction
/// rays (`--stats-json`), and at most 4 × 4096. `--explain` prints the cap per camera ray and
/// the worst case as 4 camera rays × (1 + 4096 secondary).
#[test]
fn the_secondary_ray_cap_is_per_camera_ray() {
    const LENS_SAMPLES: u64 = 4;
    let dir = tempfile::tempdir().unwrap();
    let text = hall_of_mirrors("1.0", false).replace(
        "width = 4\nheight = 4\n",
        &format!("width = 1\nheight = 1\naperture = 0.1\nlens_samples = {LENS_SAMPLES}\n"),
    );
    assert!(text.contains("lens_samples"), "{text}");
    let scene = dir.path().join("hall.toml");
    std::fs::write(&scene, text).unwrap();
    let (png, stats) = (dir.path().join("o.png"), dir.path().join("stats.json"));
    let o = halfray(&[
        &"render",
        &scene,
        &"-o",
        &png,
        &"--stats-json",
        &stats,
        &"--explain",
        &"--quiet",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(json["primary"], LENS_SAMPLES, "{json}");
    let secondary = json["reflection"].as_u64().unwrap() + json["refraction"].as_u64().unwrap();
    let cap = 4096;
    assert!(secondary > cap, "more than {cap} in one pixel: {json}");
    assert!(secondary <= LENS_SAMPLES * cap, "{json}");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("at most 4096 reflection + refraction rays per camera ray"),
        "{out}"
    );
    assert!(
        out.contains("× 4 camera rays × (1 + 4096 secondary)"),
        "{out}"
    );
    let docs =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/bad-input.md"))
            .unwrap();
    assert!(
        docs.split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .contains("at most 4096 secondary rays per camera ray"),
        "docs/bad-input.md states the cap per camera ray"
    );
}

#[test]
fn forced_effects_stay_bit_identical_when_radiance_overflows() {
    // Three lights of 3e38 at distance ~1 from the floor: each term is finite, their sum +∞. The sphere
    // has no mirror; forced reflection rays from its underside see the floor (0·∞ = NaN if
    // their result were weighted by zero instead of discarded).
    let lights: String = ["[0, 1, 0]", "[0.2, 1, 0]", "[-0.2, 1, 0]"]
        .map(|p| point_light(p, "3e38"))
        .concat();
    let text = format!(
        "\nbackground = [0.1, 0.1, 0.1]\n{}{lights}[material.matte]\ndiffuse = [1, 1, 1]\n{}{}",
        camera("[0, 1, 5]", "[0, 0.5, 0]", "40", [32, 24]),
        plane("[0, 0, 0]", "[0, 1, 0]", "matte"),
        sphere("[1.5, 0.6, 1]", "0.5", "matte"),
    );
    let s = scene::parse(&text, Path::new("hot.toml")).unwrap();
    let planned = render(&s, &RenderOptions::default());
    let forced = render(
        &s,
        &RenderOptions {
            force_all: true,
            ..RenderOptions::default()
        },
    );
    assert!(forced.counts.reflection > 0, "forced rays were cast");
    assert!(
        planned.pixels.iter().any(|p| p.x.is_infinite()),
        "the scene overflows"
    );
    assert_eq!(
        planned.to_rgba8(Mode::Color, Default::default()),
        forced.to_rgba8(Mode::Color, Default::default())
    );
}

#[test]
fn explain_states_the_bound() {
    let s = glass(64);
    let text = EffectPlan::derive(&s, false).explain(&s, Mode::Color, 1);
    assert!(
        text.contains("ray tree bound") && text.contains("1/8192") && text.contains("4096"),
        "{text}"
    );
}

/// The rays the renderer counts (the counts `--stats-json` reports) rendering `s` in `mode`,
/// forced or not, with at most `samples` samples per pixel; panics, naming `what`, unless
/// they are within the work estimate of that render.
fn counted_within_estimate(
    s: &Scene,
    mode: Mode,
    force_all: bool,
    samples: u32,
    what: &str,
) -> u64 {
    let plan = EffectPlan::derive(s, force_all);
    let worst = Estimate::of(s, &plan, mode, samples).rays();
    let opts = RenderOptions {
        mode,
        force_all,
        samples,
        ..RenderOptions::default()
    };
    let counts = render(s, &opts).counts;
    let cast = counts.total();
    assert!(
        cast as f64 <= worst,
        "{what} ({mode:?}, forced {force_all}, {samples} samples): {cast} rays ({counts:?}) over the worst case {worst}"
    );
    cast
}

/// The work estimate is an upper bound of the rays every example scene casts (at 8×6, with
/// its own samples and with 4) in every mode, with and without `--force-all-effects`.
#[test]
fn the_work_estimate_bounds_the_rays_of_every_example_scene() {
    for path in example_scene_paths() {
        let mut s = scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        s.camera.width = 8;
        s.camera.height = 6;
        for &mode in <Mode as clap::ValueEnum>::value_variants() {
            for force_all in [false, true] {
                for samples in [s.samples, 4] {
                    counted_within_estimate(
                        &s,
                        mode,
                        force_all,
                        samples,
                        &path.display().to_string(),
                    );
                }
            }
        }
    }
}

/// Under `--force-all-effects` every node of the ray tree that expands also casts the ray of
/// the effect its material does not have, as a leaf outside the cap: from the
/// hall of mirrors whose outer sphere transmits nothing, each outer hit casts a leaf
/// refraction ray beside its traced reflection, so every pixel casts more secondary rays
/// than the 4096 the cap allows traced. No light, so the estimate's 17 segments per shadow
/// ray leave no slack to hide them in. The work estimate counts them.
#[test]
fn the_work_estimate_counts_forced_leaf_rays() {
    let s = scene::parse(&hall_of_mirrors("0", false), Path::new("hall.toml")).unwrap();
    let pixels = u64::from(s.camera.width * s.camera.height);
    let traced = pixels * (1 + u64::from(MAX_SECONDARY_RAYS_PER_CAMERA_RAY));
    let planned = counted_within_estimate(&s, Mode::Color, false, 1, "hall");
    assert_eq!(planned, traced, "every pixel traces the full 4096 rays");
    let forced = counted_within_estimate(&s, Mode::Color, true, 1, "hall, forced");
    assert!(forced > traced, "leaf rays beyond the cap: {forced}");
}
