//! Shading options as a user sets them: Phong's `(v·r)^p` beside Blinn–Phong, the output
//! gamma (`--gamma`), and the calibration helper (`halfray gamma`).

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_halfray");

fn scene(model: &str) -> String {
    format!(
        r#"background = [0, 0, 0]
[camera]
eye = [0, 0, 4]
look_at = [0, 0, 0]
fov = 40
width = 96
height = 96

[material.shiny]
diffuse = [0.2, 0.2, 0.2]
specular = [1, 1, 1]
shininess = 20
specular_model = "{model}"

[[light]]
type = "point"
position = [2, 2, 4]
intensity = 30

[[object]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "shiny"
"#
    )
}

fn render(dir: &Path, name: &str, text: &str, extra: &[&str]) -> image::RgbaImage {
    let toml = dir.join(format!("{name}.toml"));
    std::fs::write(&toml, text).unwrap();
    let png = dir.join(format!("{name}.png"));
    let o = Command::new(BIN)
        .arg("render")
        .arg(&toml)
        .args(["--quiet", "-o"])
        .arg(&png)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    image::open(&png).unwrap().into_rgba8()
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
}
