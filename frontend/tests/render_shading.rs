//! Shading options as a user sets them: Phong's `(v·r)^p` beside Blinn–Phong, the output
//! gamma (`--gamma`), and the calibration helper (`halfray gamma`).

use std::path::Path;
use std::process::Command;

mod common;
use common::{BIN, camera, directional_light, plane, point_light, scenes_dir, sphere};

fn scene(model: &str) -> String {
    let camera = camera("[0, 0, 4]", "[0, 0, 0]", "40", [96, 96]);
    let light = point_light("[2, 2, 4]", "30");
    let sphere = sphere("[0, 0, 0]", "1", "shiny");
    format!(
        r#"background = [0, 0, 0]
{camera}
[material.shiny]
diffuse = [0.2, 0.2, 0.2]
specular = [1, 1, 1]
shininess = 20
specular_model = "{model}"

{light}
{sphere}"#
    )
}

fn render(dir: &Path, name: &str, text: &str, extra: &[&str]) -> image::RgbaImage {
    render_stats(dir, name, text, extra).0
}

/// Writes `text` as `dir/name.toml` and renders it with `extra`: the image and the
/// `--stats-json`.
fn render_stats(
    dir: &Path,
    name: &str,
    text: &str,
    extra: &[&str],
) -> (image::RgbaImage, serde_json::Value) {
    let toml = dir.join(format!("{name}.toml"));
    std::fs::write(&toml, text).unwrap();
    run_cli(dir, &toml, name, extra)
}

/// Writes `text` as `dir/bad.toml` and renders it, which must fail with exit code 1: the
/// error output.
fn render_refused(dir: &Path, text: &str) -> String {
    let toml = dir.join("bad.toml");
    std::fs::write(&toml, text).unwrap();
    let o = Command::new(BIN)
        .arg("render")
        .arg(&toml)
        .arg("-o")
        .arg(dir.join("b.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    err
}

/// `halfray render TOML -o dir/name.png --stats-json dir/name.json EXTRA…`: the image and the
/// statistics; the render must succeed.
fn run_cli(
    dir: &Path,
    toml: &Path,
    name: &str,
    extra: &[&str],
) -> (image::RgbaImage, serde_json::Value) {
    let png = dir.join(format!("{name}.png"));
    let json = dir.join(format!("{name}.json"));
    let o = Command::new(BIN)
        .arg("render")
        .arg(toml)
        .args(["--quiet", "-o"])
        .arg(&png)
        .arg("--stats-json")
        .arg(&json)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stats = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    (image::open(&png).unwrap().into_rgba8(), stats)
}

#[test]
fn phong_has_the_narrower_highlight_for_the_same_exponent() {
    let dir = tempfile::tempdir().unwrap();
    let blinn = render(dir.path(), "blinn", &scene("blinn-phong"), &[]);
    let phong = render(dir.path(), "phong", &scene("phong"), &[]);
    let bright = |img: &image::RgbaImage| img.pixels().filter(|p| p.0[0] > 200).count();
    let (b, p) = (bright(&blinn), bright(&phong));
    // Phong's lobe is about twice as narrow in angle (the angle between v and r is twice the
    // one between n and h), so its highlight covers fewer pixels; both have one.
    assert!(p > 0 && p < b, "bright pixels: phong {p}, blinn-phong {b}");
}

#[test]
fn gamma_encodes_the_same_radiance_with_a_power_law() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene("blinn-phong");
    let srgb = render(dir.path(), "srgb", &text, &[]);
    let power = render(dir.path(), "power", &text, &["--gamma", "2.2"]);
    assert_ne!(srgb, power);
    let srgb_to_linear = |v: f64| {
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut compared = 0;
    for (a, b) in srgb.pixels().zip(power.pixels()) {
        for k in 0..3 {
            let (x, y) = (f64::from(a.0[k]) / 255.0, f64::from(b.0[k]) / 255.0);
            // One 8-bit step of either encoding, in linear terms, near the value.
            let step = 2.2 * y.max(1.0 / 255.0).powf(1.2) / 255.0 + 3.0 / 255.0 / 12.92;
            assert!(
                (srgb_to_linear(x) - y.powf(2.2)).abs() <= step,
                "srgb {x} vs gamma-2.2 {y}"
            );
            compared += (a.0[k] > 20) as usize;
        }
    }
    assert!(compared > 100);
    // Not a gamma: a usage error naming the value.
    let o = Command::new(BIN)
        .arg("render")
        .arg(dir.path().join("srgb.toml"))
        .args(["--gamma", "22", "-o"])
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("22"));
}

#[test]
fn the_calibration_helper_turns_the_matching_grey_into_gamma() {
    let o = Command::new(BIN)
        .args(["gamma", "--match", "186"])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}");
    let g: f64 = out
        .split("= ")
        .nth(2)
        .and_then(|s| s.split(';').next())
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    // The display shows grey 186 at half luminance: (186/255)^γ = ½.
    assert!(((186.0f64 / 255.0).powf(g) - 0.5).abs() < 1e-3, "{out}");
    let o = Command::new(BIN)
        .args(["gamma", "--match", "0"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let dir = tempfile::tempdir().unwrap();
    let chart = dir.path().join("chart.png");
    let o = Command::new(BIN)
        .args(["gamma", "--chart"])
        .arg(&chart)
        .output()
        .unwrap();
    assert!(o.status.success());
    let img = image::open(&chart).unwrap().into_rgba8();
    assert_eq!((img.width(), img.height()), (7 * 96, 96));
    assert!(String::from_utf8_lossy(&o.stdout).contains("gamma is 2.2 if it matches"));
    // A bad `--match` beside `--chart` is a usage error before anything is written: the file
    // the chart would replace keeps its bytes (it was replaced, then the match refused).
    let kept = dir.path().join("kept.png");
    for bad in ["0", "300"] {
        std::fs::write(&kept, b"keep").unwrap();
        let o = Command::new(BIN)
            .args(["gamma", "--chart"])
            .arg(&kept)
            .args(["--match", bad])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--match {bad}");
        assert_eq!(std::fs::read(&kept).unwrap(), b"keep", "--match {bad}");
    }
}

/// Smooth shading on the octahedron: its area-weighted vertex normals are the axis directions
/// (every vertex sits on an axis, its four faces symmetric about it), so at each corner of
/// each face the shading normal is the corner's position, normalised; in a face's centre it is
/// the face normal (the three axes summed).
#[test]
fn octahedron_vertex_normals_are_its_axes() {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/meshes/octahedron.obj"
    ));
    let mesh = halfray::scene::load_mesh("o", path, None, 0, true).unwrap();
    let tris = mesh.accel.mesh.triangles.clone();
    let pos = mesh.accel.mesh.positions.clone();
    for (i, t) in tris.iter().enumerate() {
        let v = t.map(|k| pos[k as usize]);
        let geometric = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        for (k, corner) in [glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z]
            .into_iter()
            .enumerate()
        {
            let n = mesh.shading_normal(i, corner, geometric).unwrap();
            assert!(
                (n - v[k].normalize()).length() < 1e-6,
                "triangle {i} corner {k}: {n}"
            );
        }
        let centre = mesh
            .shading_normal(i, glam::Vec3::splat(1.0 / 3.0), geometric)
            .unwrap();
        assert!(
            (centre - geometric).length() < 1e-6,
            "triangle {i}: {centre} vs {geometric}"
        );
    }
    assert!(
        halfray::scene::load_mesh("o", path, None, 0, false)
            .unwrap()
            .normals
            .is_none()
    );
}

fn mesh_scene(dir: &Path, shading: &str) -> String {
    let obj = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/meshes/octahedron.obj"
    );
    let _ = dir;
    let camera = camera("[2.2, 1.6, 2.8]", "[0, 0, 0]", "22", [128, 128]);
    let light = directional_light("[-1, -2, -1.5]");
    format!(
        r#"background = [0, 0, 0]
{camera}
[material.m]
diffuse = [0.9, 0.9, 0.9]

{light}
[mesh.o]
file = "{obj}"
subdivide = 2
shading = "{shading}"

[[object]]
type = "mesh"
mesh = "o"
material = "m"
"#
    )
}

/// Flat shading is constant on each face and jumps at every edge between faces; smooth shading
/// varies continuously. Along each row, a jump is a spike of the second difference
/// `|a − 2b + c|` of neighbouring covered pixels: many with flat shading, few with smooth.
#[test]
fn smooth_shading_removes_the_steps_between_faces() {
    let dir = tempfile::tempdir().unwrap();
    let steps = |shading: &str| {
        let img = render(
            dir.path(),
            shading,
            &mesh_scene(dir.path(), shading),
            &["--transparent-background"],
        );
        let mut n = 0;
        for y in 0..img.height() {
            for x in 2..img.width() {
                let p = [x - 2, x - 1, x].map(|x| img.get_pixel(x, y).0);
                if p.iter().all(|q| q[3] == 255) {
                    let second = i32::from(p[0][0]) - 2 * i32::from(p[1][0]) + i32::from(p[2][0]);
                    n += usize::from(second.abs() > 6);
                }
            }
        }
        n
    };
    let (flat, smooth) = (steps("flat"), steps("smooth"));
    assert!(
        flat > 200 && smooth * 3 < flat,
        "steps: flat {flat}, smooth {smooth}"
    );
    // An unknown shading is an error naming the field.
    let err = render_refused(dir.path(), &mesh_scene(dir.path(), "phong"));
    assert!(
        err.contains("mesh.o.shading") && err.contains("`flat` or `smooth`"),
        "{err}"
    );
}

/// Renders a shipped scene at 80 × 60 with `extra`: the image and the `--stats-json`.
fn shipped(
    dir: &Path,
    scene: &str,
    name: &str,
    extra: &[&str],
) -> (image::RgbaImage, serde_json::Value) {
    let toml = scenes_dir().join(scene);
    let size = ["--width", "80", "--height", "60"];
    let args: Vec<&str> = size.iter().chain(extra).copied().collect();
    run_cli(dir, &toml, name, &args)
}

#[test]
fn antialiasing_samples_only_where_neighbours_differ() {
    let dir = tempfile::tempdir().unwrap();
    let (one, s1) = shipped(
        dir.path(),
        "bunny.toml",
        "one",
        &["--transparent-background"],
    );
    let (aa, s8) = shipped(
        dir.path(),
        "bunny.toml",
        "aa",
        &["--transparent-background", "--samples", "8"],
    );
    let pixels = 80 * 60u64;
    assert_eq!(s1["primary"], pixels);
    assert_eq!(s1["plan"]["antialias"], false);
    assert_eq!(s8["plan"]["antialias"], true);
    // One centre ray per pixel plus 7 in each refined pixel: a multiple of 7 on top, and far
    // fewer than 8 per pixel (flat regions keep one).
    let extra = s8["primary"].as_u64().unwrap() - pixels;
    assert!(extra > 0 && extra.is_multiple_of(7), "{extra}");
    let refined = extra / 7;
    assert!(refined < pixels / 2, "{refined} of {pixels} pixels refined");
    // Unrefined pixels are unchanged; silhouettes get partial coverage.
    let changed = one
        .pixels()
        .zip(aa.pixels())
        .filter(|(a, b)| a != b)
        .count() as u64;
    assert!(
        changed > 0 && changed <= refined,
        "{changed} changed, {refined} refined"
    );
    let partial = aa.pixels().filter(|p| p.0[3] > 0 && p.0[3] < 255).count();
    assert!(partial > 10, "{partial} partly covered pixels");
    assert_eq!(
        one.pixels().filter(|p| p.0[3] > 0 && p.0[3] < 255).count(),
        0
    );
    // Deterministic, and the same with every effect forced on.
    let (again, _) = shipped(
        dir.path(),
        "bunny.toml",
        "again",
        &["--transparent-background", "--samples", "8"],
    );
    assert_eq!(again, aa);
    let (forced, _) = shipped(
        dir.path(),
        "bunny.toml",
        "forced",
        &[
            "--transparent-background",
            "--samples",
            "8",
            "--force-all-effects",
        ],
    );
    assert_eq!(forced, aa);
    // Opaque output blends the partly covered pixels with the background colour.
    let (opaque, _) = shipped(dir.path(), "bunny.toml", "opaque", &["--samples", "8"]);
    assert!(opaque.pixels().all(|p| p.0[3] == 255));
    let o = Command::new(BIN)
        .args([
            "render",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/bunny.toml"),
            "--samples",
            "65",
            "-o",
        ])
        .arg(dir.path().join("x.png"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

/// Two spheres of the same size at 4 and 9 units, seen against an empty background; the
/// camera's lens (`aperture > 0`, 24 samples) focuses at `focus`, `aperture = 0` is a pinhole
/// (without the lens's other fields, which it refuses).
fn dof_scene(aperture: f32, focus: f32) -> String {
    let camera = camera("[0, 0, 0]", "[0, 0, -1]", "50", [96, 64]);
    let lens = if aperture > 0.0 {
        format!("aperture = {aperture}\nfocus_distance = {focus}\nlens_samples = 24")
    } else {
        format!("aperture = {aperture}")
    };
    let light = directional_light("[0, 0, -1]");
    let near = sphere("[-1.2, 0, -4]", "0.8", "m");
    let far = sphere("[2.7, 0, -9]", "1.8", "m");
    format!(
        r#"background = [0, 0, 0]
{camera}{lens}

[material.m]
diffuse = [0.9, 0.9, 0.9]

{light}
{near}
{far}"#
    )
}

/// Partly covered pixels (a blurred silhouette) in the left and right halves of an image.
fn blur(img: &image::RgbaImage) -> (usize, usize) {
    let half = img.width() / 2;
    let mut n = (0, 0);
    for (x, _, p) in img.enumerate_pixels() {
        if p.0[3] > 10 && p.0[3] < 245 {
            if x < half { n.0 += 1 } else { n.1 += 1 }
        }
    }
    n
}

#[test]
fn depth_of_field_blurs_what_is_out_of_focus() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, text: &str| {
        render_stats(dir.path(), name, text, &["--transparent-background"])
    };
    let (near, s_near) = run("near", &dof_scene(0.15, 4.0));
    let (far, _) = run("far", &dof_scene(0.15, 9.0));
    let (pinhole, s_pin) = run("pinhole", &dof_scene(0.0, 4.0));
    assert_eq!(s_near["plan"]["depth_of_field"], true);
    assert_eq!(s_pin["plan"]["depth_of_field"], false);
    assert_eq!(s_near["primary"], 96 * 64 * 24);
    assert_eq!(s_pin["primary"], 96 * 64);
    // Focused on the near sphere (left): its edge stays sharp (partly covered pixels only
    // from the sub-pixel positions, about its perimeter), the far one (right) blurs over more
    // than twice as many; focused on the far one, the other way round. The pinhole blurs
    // nothing.
    let (nl, nr) = blur(&near);
    let (fl, fr) = blur(&far);
    assert!(nr > 2 * nl.max(1), "focus near: left {nl}, right {nr}");
    assert!(fl > 2 * fr.max(1), "focus far: left {fl}, right {fr}");
    assert_eq!(blur(&pinhole), (0, 0));
    // A lens on an orthographic camera is refused, naming the field.
    let text = dof_scene(0.1, 4.0).replace("fov = 50", "type = \"orthographic\"\nview_size = 4");
    let toml = dir.path().join("ortho.toml");
    std::fs::write(&toml, text).unwrap();
    let o = Command::new(BIN)
        .arg("render")
        .arg(&toml)
        .arg("-o")
        .arg(dir.path().join("o.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("camera.aperture"), "{err}");
}

/// Thin lens: every ray of a pixel starts on the lens disk (within `aperture` of the eye, in
/// the plane across the view) and meets the pinhole ray on the plane in focus.
#[test]
fn lens_rays_meet_on_the_plane_in_focus() {
    use glam::Vec3;
    use halfray::scene::{Camera, Lens, Projection};
    let mut cam = Camera::new(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        Projection::Perspective { fov: 40.0 },
        64,
        48,
    )
    .unwrap();
    let lens = Lens {
        aperture: 0.3,
        focus_distance: 5.0,
        samples: 16,
    };
    cam.lens = Some(lens);
    for (x, y) in [(0.5, 0.5), (31.7, 20.2), (63.9, 47.1)] {
        let pin = cam.ray_at(x, y);
        let focus =
            pin.origin + pin.direction * (lens.focus_distance / pin.direction.dot(cam.forward));
        for k in 0..16 {
            let (lu, lv) = (k as f32 / 16.0, ((k * 7) % 16) as f32 / 16.0);
            let r = cam.ray_through_lens(x, y, lu, lv);
            let off = r.origin - cam.eye;
            assert!(off.dot(cam.forward).abs() < 1e-6 && off.length() <= lens.aperture + 1e-6);
            let t = lens.focus_distance / r.direction.dot(cam.forward) - off.dot(cam.forward);
            let p = r.origin + r.direction * t;
            assert!(
                (p - focus).length() < 1e-4,
                "({x}, {y}) lens ({lu}, {lv}): {p} vs {focus}"
            );
        }
    }
    // The lens centre is the pinhole.
    let (pin, c) = (
        cam.ray_at(10.5, 7.5),
        cam.ray_through_lens(10.5, 7.5, 0.5, 0.5),
    );
    assert_eq!(pin.origin, c.origin);
    assert!((pin.direction.normalize() - c.direction.normalize()).length() < 1e-6);
}

/// A sphere over a plane lit from above by a point light of `radius` (32 shadow rays per
/// shading point when `radius > 0`).
fn shadow_scene(radius: f32) -> String {
    let samples = if radius > 0.0 { "samples = 32" } else { "" };
    let camera = camera("[0, 6, 6]", "[0, 0, 0]", "40", [80, 60]);
    let light = point_light("[0, 5, 0]", "30");
    let sphere = sphere("[0, 1.2, 0]", "1", "m");
    let plane = plane("[0, 0, 0]", "[0, 1, 0]", "m");
    format!(
        r#"background = [0, 0, 0]
ambient = [0, 0, 0]
{camera}
[material.m]
diffuse = [0.8, 0.8, 0.8]
ambient = [0, 0, 0]

{light}radius = {radius}
{samples}

{sphere}
{plane}"#
    )
}

#[test]
fn an_area_light_casts_soft_shadows() {
    let dir = tempfile::tempdir().unwrap();
    let (hard, s_hard) = render_stats(dir.path(), "hard", &shadow_scene(0.0), &[]);
    let (soft, s_soft) = render_stats(dir.path(), "soft", &shadow_scene(1.5), &[]);
    assert_eq!(s_hard["plan"]["area_lights"], false);
    assert_eq!(s_soft["plan"]["area_lights"], true);
    // 32 shadow rays per lit shading point instead of one, but for the disk points below a
    // point's tangent plane (on the sphere near its terminator: fewer than 1 %).
    let (sh, ss) = (
        s_hard["shadow"].as_u64().unwrap(),
        s_soft["shadow"].as_u64().unwrap(),
    );
    assert!(
        ss <= 32 * sh && ss * 100 >= 32 * sh * 99,
        "shadow rays {sh} vs {ss}"
    );
    // Penumbra: pixels of the plane between full shadow and full light. Along the image's
    // middle column, below the sphere, a hard shadow jumps; a soft one passes through
    // intermediate values.
    let column = |img: &image::RgbaImage| -> Vec<u8> {
        (0..img.height())
            .map(|y| img.get_pixel(40, y).0[0])
            .collect()
    };
    let jumps = |c: &[u8]| c.windows(2).map(|w| w[0].abs_diff(w[1])).max().unwrap();
    let (ch, cs) = (column(&hard), column(&soft));
    assert!(
        jumps(&cs) * 2 < jumps(&ch),
        "largest step: soft {} vs hard {}",
        jumps(&cs),
        jumps(&ch)
    );
    // Radius on a directional light is refused.
    let bad = shadow_scene(1.0).replace(
        "type = \"point\"\nposition = [0, 5, 0]",
        "type = \"directional\"\ndirection = [0, -1, 0]",
    );
    let err = render_refused(dir.path(), &bad);
    assert!(
        err.contains("light[0].radius") || err.contains(".radius"),
        "{err}"
    );
}

/// A lens without `focus_distance` focuses on `look_at`: the distance from the eye to it.
#[test]
fn a_lens_focuses_on_look_at_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lens.toml");
    let text = "[camera]\neye = [1, 2, 3]\nlook_at = [4, 6, 3]\nfov = 40\nwidth = 8\nheight = 6\naperture = 0.1\n";
    std::fs::write(&path, text).unwrap();
    let scene = halfray::scene::load(&path).unwrap();
    let lens = scene.camera.lens.expect("an aperture: a lens");
    assert_eq!(lens.focus_distance, 5.0);
}

/// An area light of radius 1 whose centre is at height `y` above the floor `y = 0` lights the
/// floor point `P = (2, 0, 0)`, computed by hand from the documented rule (scenes/README.md): the
/// mean over the disk facing `P` of `max(0, n·l)` for each of its points (`l` towards the point;
/// a point on or below the floor adds nothing and casts no ray), integrated on a 1000×1000 grid
/// over the disk. Returns that mean and the share of the disk above the floor.
fn sunk_disk(y: f64) -> (f64, f64) {
    let (p, c) = ([2.0f64, 0.0, 0.0], [0.0f64, y, 0.0]);
    let d = [c[0] - p[0], c[1] - p[1], c[2] - p[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let a = d.map(|x| x / len);
    // Two unit vectors across the axis: z, and a × z.
    let t1 = [0.0, 0.0, 1.0];
    let t2 = [a[1], -a[0], 0.0];
    let (mut sum, mut above, mut all) = (0.0, 0.0, 0.0);
    let n = 1000;
    for i in 0..n {
        for j in 0..n {
            let (u, v) = (
                (i as f64 + 0.5) / n as f64 * 2.0 - 1.0,
                (j as f64 + 0.5) / n as f64 * 2.0 - 1.0,
            );
            if u * u + v * v > 1.0 {
                continue;
            }
            all += 1.0;
            let q: Vec<f64> = (0..3)
                .map(|k| c[k] + u * t1[k] + v * t2[k] - p[k])
                .collect();
            if q[1] > 0.0 {
                above += 1.0;
                sum += q[1] / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            }
        }
    }
    (sum / all, above / all)
}

/// One pixel looking straight down at the floor at `P = (2, 0, 0)`, lit by a light of radius 1
/// and 256 samples centred at `(0, y, 0)`, at gamma 1: its value over 255 and the stats.
fn sunk_light_pixel(
    dir: &Path,
    y: f64,
    intensity: &str,
    shadows: bool,
) -> (f64, serde_json::Value) {
    let text = format!(
        r#"background = [0, 0, 0]
ambient = [0, 0, 0]
[camera]
type = "orthographic"
eye = [2, 5, 0]
look_at = [2, 0, 0]
up = [0, 0, -1]
view_size = 0.001
width = 1
height = 1
[material.m]
diffuse = [1, 1, 1]
ambient = [0, 0, 0]
{light}radius = 1
samples = 256
cast_shadows = {shadows}
{plane}"#,
        light = point_light(&format!("[0, {y}, 0]"), intensity),
        plane = plane("[0, 0, 0]", "[0, 1, 0]", "m"),
    );
    let name = format!("sunk{y}{shadows}");
    let (img, stats) = render_stats(dir, &name, &text, &["--gamma", "1"]);
    (f64::from(img.get_pixel(0, 0).0[0]) / 255.0, stats)
}

/// An area light's points below a shaded point's tangent plane add no light and cast no ray:
/// the surface hides them, as `n·l ≤ 0` hides a point light ([`sunk_disk`] gives the light and
/// the share of rays by hand). Half sunk (centre at `y = 0.3`): the pixel over the same light
/// without shadows (a point light at the centre, `n·l` = 0.148) is the disk's mean `n·l` over
/// that, within the 256 samples' spread and 8-bit rounding.
#[test]
fn an_area_light_sunk_into_the_floor_lights_it_from_above_only() {
    let dir = tempfile::tempdir().unwrap();
    let (a, _) = sunk_light_pixel(dir.path(), 0.3, "20", false);
    let (b, stats) = sunk_light_pixel(dir.path(), 0.3, "20", true);
    assert!((100.0 / 255.0..1.0).contains(&a), "unshadowed pixel {a}");
    let cos_centre = 0.3 / (4.0f64 + 0.09).sqrt();
    let (mean, above) = sunk_disk(0.3);
    assert!((above - 0.690).abs() < 1e-3, "{above}");
    assert!(
        (b / a - mean / cos_centre).abs() < 0.03,
        "{b} / {a} vs {mean} / {cos_centre}"
    );
    let shadow = stats["shadow"].as_u64().unwrap() as f64;
    assert!(
        (shadow / 256.0 - above).abs() < 0.03,
        "{shadow} shadow rays"
    );
}

/// The disk decides, not its centre: with the centre just below the floor (`y = −0.05`) 47 % of
/// the disk facing `P` is above it, and lights `P` as [`sunk_disk`] gives by hand (`E = I/r²` at
/// the centre, `I = 20`), with a shadow ray to each point above; so does the same light just
/// above the floor (`y = 0.05`, 53 %). (Culled by its centre, the sunk light gave 0 and cast no
/// ray.)
#[test]
fn an_area_light_whose_centre_is_below_the_plane_lights_it_with_the_disk_above() {
    let dir = tempfile::tempdir().unwrap();
    for y in [-0.05, 0.05] {
        let (b, stats) = sunk_light_pixel(dir.path(), y, "20", true);
        let (mean, above) = sunk_disk(y);
        let e = 20.0 / (4.0 + y * y);
        assert!((0.45..0.55).contains(&above), "{above}");
        assert!(
            (b - e * mean).abs() < 0.03 * e * mean + 1.0 / 255.0,
            "y {y}: pixel {b}, by hand {}",
            e * mean
        );
        let shadow = stats["shadow"].as_u64().unwrap() as f64;
        assert!(
            (shadow / 256.0 - above).abs() < 0.03,
            "y {y}: {shadow} shadow rays, {above} of the disk above"
        );
    }
}
