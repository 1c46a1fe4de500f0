//! `halfray composite A B --op OP` and `halfray render --background IMG --op OP` on exact
//! pixel values: each of the twelve operators against Porter and Duff's table written out here
//! in straight (non-premultiplied) closed form, independent of the code's `Fa·A + Fb·B`.

use image::{Rgba, RgbaImage};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

mod common;
use common::{halfray, header_only_png, stderr};

/// Four pixels: opaque, half, a little and no coverage.
fn image(rgb: [u8; 3], alphas: [u8; 4]) -> RgbaImage {
    RgbaImage::from_fn(4, 1, |x, _| {
        Rgba([rgb[0], rgb[1], rgb[2], alphas[x as usize]])
    })
}

/// Straight-alpha result of `a OP b` (alphas in [0, 1]), from the operator's region rules:
/// `(coverage of A only, of B only, of both)` → which colour shows there.
fn expected(op: &str, a: [f64; 4], b: [f64; 4]) -> [u8; 4] {
    let (aa, ab) = (a[3], b[3]);
    // Areas of the three regions of a pixel.
    let (only_a, only_b, both) = (aa * (1.0 - ab), ab * (1.0 - aa), aa * ab);
    // Per region: 0 nothing, 1 A, 2 B.
    let (ra, rb, rboth) = match op {
        "clear" => (0, 0, 0),
        "src" => (1, 0, 1),
        "dst" => (0, 2, 2),
        "over" => (1, 2, 1),
        "dst-over" => (1, 2, 2),
        "in" => (0, 0, 1),
        "dst-in" => (0, 0, 2),
        "out" => (1, 0, 0),
        "dst-out" => (0, 2, 0),
        "atop" => (0, 2, 1),
        "dst-atop" => (1, 0, 2),
        "xor" => (1, 2, 0),
        _ => unreachable!(),
    };
    let mut alpha = 0.0;
    let mut rgb = [0.0f64; 3];
    for (area, who) in [(only_a, ra), (only_b, rb), (both, rboth)] {
        let c = match who {
            1 => a,
            2 => b,
            _ => continue,
        };
        alpha += area;
        for k in 0..3 {
            rgb[k] += area * c[k];
        }
    }
    let q = |x: f64| (x * 255.0).round().clamp(0.0, 255.0) as u8;
    if alpha <= 0.0 {
        return [0, 0, 0, 0];
    }
    [
        q(rgb[0] / alpha),
        q(rgb[1] / alpha),
        q(rgb[2] / alpha),
        q(alpha),
    ]
}

const OPS: [&str; 12] = [
    "clear", "src", "dst", "over", "dst-over", "in", "dst-in", "out", "dst-out", "atop",
    "dst-atop", "xor",
];

fn save(img: &RgbaImage, path: &Path) {
    img.save(path).unwrap();
}

#[test]
fn every_operator_gives_porter_and_duffs_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let (pa, pb) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let a = image([240, 30, 10], [255, 153, 40, 0]);
    let b = image([20, 60, 200], [255, 128, 255, 77]);
    save(&a, &pa);
    save(&b, &pb);
    for op in OPS {
        let out = dir.path().join(format!("{op}.png"));
        let o = halfray(&[&"composite", &pa, &pb, &"--op", &op, &"-o", &out]);
        assert!(o.status.success(), "{op}: {}", stderr(&o));
        let got = image::open(&out).unwrap().into_rgba8();
        for x in 0..4 {
            let f = |p: &Rgba<u8>| p.0.map(|c| f64::from(c) / 255.0);
            let want = expected(op, f(a.get_pixel(x, 0)), f(b.get_pixel(x, 0)));
            let g = got.get_pixel(x, 0).0;
            let close = g.iter().zip(want).all(|(&g, w)| g.abs_diff(w) <= 1);
            // Colour is undefined where alpha is 0: compare alpha only there.
            assert!(
                close || (g[3] == 0 && want[3] == 0),
                "{op} pixel {x}: {g:?}, expected {want:?}"
            );
        }
    }
}

/// Cairo's operator names (`cairo_operator_t`: `CAIRO_OPERATOR_SOURCE` is `source`) and
/// ImageMagick's (`-compose`, any case) give the image of the operator they name.
#[test]
fn cairo_and_imagemagick_names_are_the_same_operators() {
    const NAMES: [(&str, &str); 24] = [
        ("source", "src"),
        ("dest", "dst"),
        ("dest-over", "dst-over"),
        ("dest-in", "dst-in"),
        ("dest-out", "dst-out"),
        ("dest-atop", "dst-atop"),
        ("copy", "src"),
        ("src-over", "over"),
        ("src-in", "in"),
        ("src-out", "out"),
        ("src-atop", "atop"),
        ("Clear", "clear"),
        ("Src", "src"),
        ("Dst", "dst"),
        ("Over", "over"),
        ("SrcOver", "over"),
        ("DstOver", "dst-over"),
        ("SrcIn", "in"),
        ("DstIn", "dst-in"),
        ("SrcOut", "out"),
        ("DstOut", "dst-out"),
        ("SrcAtop", "atop"),
        ("DstAtop", "dst-atop"),
        ("Xor", "xor"),
    ];
    let dir = tempfile::tempdir().unwrap();
    let (pa, pb) = (dir.path().join("a.png"), dir.path().join("b.png"));
    save(&image([240, 30, 10], [255, 153, 40, 0]), &pa);
    save(&image([20, 60, 200], [255, 128, 255, 77]), &pb);
    let run = |op: &str| {
        let out = dir.path().join("out.png");
        let o = halfray(&[
            &"composite",
            &pa,
            &pb,
            &"--op",
            &op,
            &"-o",
            &out,
            &"--force",
        ]);
        assert!(o.status.success(), "{op}: {}", stderr(&o));
        image::open(&out).unwrap().into_rgba8().into_raw()
    };
    for (name, ours) in NAMES {
        assert_eq!(run(name), run(ours), "--op {name} is not {ours}");
    }
}

#[test]
fn mismatched_sizes_and_an_input_as_output_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (pa, pb) = (dir.path().join("a.png"), dir.path().join("b.png"));
    save(&image([1, 2, 3], [255; 4]), &pa);
    save(&RgbaImage::new(3, 1), &pb);
    let out = dir.path().join("out.png");
    let o = halfray(&[&"composite", &pa, &pb, &"-o", &out]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("b.png") && err.contains("3×1") && err.contains("4×1"),
        "{err}"
    );
    assert!(!out.exists());
    let o = halfray(&[&"composite", &pa, &pb, &"-o", &pa]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = halfray(&[&"composite", &"--op", &"plus", &pa, &pb, &"-o", &out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("dst-atop"), "lists the operators");
}

/// Two images each within the memory limit whose composite is not are refused from their
/// headers, before any decode: exit 1 (bad input) naming both files, the size and the limit.
/// The headers hold no pixels, so a decode would have failed otherwise. Images of different
/// sizes are refused from their headers too.
#[test]
fn a_composite_beyond_the_memory_limit_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let (pa, pb) = (dir.path().join("big-a.png"), dir.path().join("big-b.png"));
    let out = dir.path().join("out.png");
    // Each image's width, height and bits a channel; what the message must hold.
    type Case = ([(u32, u32, u8); 2], &'static [&'static str]);
    let cases: [Case; 3] = [
        // 8-bit 20 000²: 1.5 GiB each, 4.5 GiB with the result.
        (
            [(20_000, 20_000, 8); 2],
            &[
                "big-a.png",
                "big-b.png",
                "both 20000×20000, needs about 4.5 GiB at once",
            ],
        ),
        // 16-bit 16 500²: each decodes within the limit (2.0 GiB buffer, 1.0 GiB copy) and
        // the three 8-bit copies fit (3.0 GiB), but the destination's decode beside the
        // source's copy does not (4.1 GiB).
        (
            [(16_500, 16_500, 16); 2],
            &[
                "big-a.png",
                "big-b.png",
                "both 16500×16500, needs about 4.1 GiB at once",
            ],
        ),
        (
            [(20_000, 20_000, 8), (20_000, 19_999, 8)],
            &["big-b.png", "20000×19999"],
        ),
    ];
    for ([a, b], want) in cases {
        std::fs::write(&pa, header_only_png(a.0, a.1, a.2)).unwrap();
        std::fs::write(&pb, header_only_png(b.0, b.1, b.2)).unwrap();
        let o = halfray(&[&"composite", &pa, &pb, &"-o", &out]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(want.iter().all(|w| err.contains(w)), "{want:?}: {err}");
        assert!(!out.exists());
    }
}

fn render(dir: &Path, name: &str, extra: &[&str]) -> RgbaImage {
    let out: PathBuf = dir.join(name);
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/bunny.toml");
    let mut args: Vec<&dyn AsRef<OsStr>> = vec![
        &"render",
        &scene,
        &"--width",
        &"40",
        &"--height",
        &"30",
        &"--quiet",
        &"-o",
        &out,
    ];
    args.extend(extra.iter().map(|a| a as &dyn AsRef<OsStr>));
    let o = halfray(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    image::open(&out).unwrap().into_rgba8()
}

#[test]
fn render_composites_with_the_chosen_operator() {
    let dir = tempfile::tempdir().unwrap();
    let bg = dir.path().join("bg.png");
    save(
        &RgbaImage::from_fn(40, 30, |x, y| Rgba([(x * 6) as u8, (y * 8) as u8, 90, 200])),
        &bg,
    );
    let bg_img = image::open(&bg).unwrap().into_rgba8();
    let bg_s = bg.to_str().unwrap();
    let alone = render(dir.path(), "alone.png", &["--transparent-background"]);
    // `dst` shows the background alone, `src` the render alone.
    let dst = render(
        dir.path(),
        "dst.png",
        &["--background", bg_s, "--op", "dst"],
    );
    let same = |x: &RgbaImage, y: &RgbaImage, what: &str| {
        for (i, (p, q)) in x.pixels().zip(y.pixels()).enumerate() {
            // Colour means nothing where alpha is 0.
            let equal = p == q || (p.0[3] == 0 && q.0[3] == 0);
            assert!(equal, "{what}: pixel {i}: {:?} vs {:?}", p.0, q.0);
        }
    };
    same(&dst, &bg_img, "dst = the background");
    let src = render(
        dir.path(),
        "src.png",
        &["--background", bg_s, "--op", "src"],
    );
    same(&src, &alone, "src = the render alone");
    // `over` (the default): the background where the render is transparent, the render where
    // it is opaque; `dst-out` keeps the background only where the render has nothing.
    let over = render(dir.path(), "over.png", &["--background", bg_s]);
    let dst_out = render(
        dir.path(),
        "dst-out.png",
        &["--background", bg_s, "--op", "dst-out"],
    );
    let (mut opaque, mut clear) = (0, 0);
    for (i, ((p, o), d)) in alone
        .pixels()
        .zip(over.pixels())
        .zip(dst_out.pixels())
        .enumerate()
    {
        match p.0[3] {
            255 => {
                opaque += 1;
                assert_eq!(o.0, p.0, "pixel {i}");
                assert_eq!(d.0[3], 0, "pixel {i}");
            }
            0 => {
                clear += 1;
                let b = bg_img.get_pixel(i as u32 % 40, i as u32 / 40);
                assert_eq!(o.0, b.0, "pixel {i}");
                assert_eq!(d.0, b.0, "pixel {i}");
            }
            _ => {}
        }
    }
    assert!(
        opaque > 0 && clear > 0,
        "{opaque} opaque, {clear} clear pixels"
    );
    // --op without --background is a usage error.
    let shadows = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/shadows.toml");
    let o = halfray(&[
        &"render",
        &shadows,
        &"--op",
        &"xor",
        &"-o",
        &dir.path().join("x.png"),
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// The scene of the tests below: a 16×16 orthographic view of a sphere lit by ambient light
/// alone (an orange one, `(0.5, 0.25, 0.1)` linear).
const SPHERE: &str = r#"ambient = [1, 1, 1]
background = [0.2, 0.9, 0.3]
[camera]
type = "orthographic"
eye = [0, 0, 5]
look_at = [0, 0, 0]
view_size = 4
width = 16
height = 16
[material.m]
diffuse = [0, 0, 0]
ambient = [0.5, 0.25, 0.1]
[[object]]
type = "sphere"
center = [0, 0, 0]
radius = 1.2
material = "m"
"#;

/// `render --background IMG --op dst` is the image, byte for byte, in every mode: the debug
/// modes composite on the image's stored values (written without encoding, as the debug
/// values are), colour mode in linear radiance (decoded, then encoded back). The image holds
/// every 8-bit grey once, with alpha from 1 to 255.
#[test]
fn dst_gives_the_background_back_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sphere.toml");
    std::fs::write(&scene, SPHERE).unwrap();
    let bg = dir.path().join("ramp.png");
    let ramp = RgbaImage::from_fn(16, 16, |x, y| {
        let g = (16 * y + x) as u8;
        Rgba([g, 255 - g, g / 2, g.max(1)])
    });
    save(&ramp, &bg);
    for mode in ["color", "depth", "normal", "barycentric", "heatmap"] {
        let out = dir.path().join(format!("{mode}.png"));
        let o = halfray(&[
            &"render",
            &scene,
            &"--mode",
            &mode,
            &"--background",
            &bg,
            &"--op",
            &"dst",
            &"--quiet",
            &"-o",
            &out,
        ]);
        assert!(o.status.success(), "{mode}: {}", stderr(&o));
        let got = image::open(&out).unwrap().into_rgba8();
        for (i, (g, want)) in got.pixels().zip(ramp.pixels()).enumerate() {
            assert_eq!(g.0, want.0, "--mode {mode}: pixel {i}");
        }
    }
}

/// `render --samples 8 --background IMG --op in` over an image of alpha 1/255: an edge pixel
/// the sphere covers less than half (coverage alpha below 128 when rendered alone) composites
/// to alpha `c / 255 < ½ / 255`, written 0, so it is `0, 0, 0, 0`, not the render's colour.
#[test]
fn a_composited_pixel_whose_alpha_rounds_to_zero_is_transparent_black() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sphere.toml");
    std::fs::write(&scene, SPHERE).unwrap();
    let bg = dir.path().join("faint.png");
    save(&RgbaImage::from_pixel(16, 16, Rgba([10, 20, 30, 1])), &bg);
    let run = |name: &str, extra: &[&dyn AsRef<OsStr>]| {
        let out = dir.path().join(name);
        let mut args: Vec<&dyn AsRef<OsStr>> = vec![
            &"render",
            &scene,
            &"--samples",
            &"8",
            &"--quiet",
            &"-o",
            &out,
        ];
        args.extend(extra);
        let o = halfray(&args);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        image::open(&out).unwrap().into_rgba8()
    };
    let alone = run("alone.png", &[&"--transparent-background"]);
    let inside = run("in.png", &[&"--background", &bg, &"--op", &"in"]);
    let mut faint = 0;
    for (i, (a, p)) in alone.pixels().zip(inside.pixels()).enumerate() {
        if (1..128).contains(&a.0[3]) {
            faint += 1;
            assert_eq!(p.0, [0, 0, 0, 0], "pixel {i} (coverage {})", a.0[3]);
        }
    }
    assert!(faint > 0, "no pixel is covered less than half");
}
