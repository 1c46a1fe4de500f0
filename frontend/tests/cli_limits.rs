//! Work that could run away: sizes from input are estimated before allocating and
//! refused with the option and the estimate; ray generation loops give up with an error.

use glam::Vec3;
use halfray::bench::accuracy::triangles::Workload;
use halfray::obj::ObjMesh;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

mod common;
use common::{BIN, shared_mesh, shared_mesh_str};

/// A refusal must come before the work: well under the time the work would take.
const REFUSAL_TIME: Duration = Duration::from_secs(20);

fn run(args: &[&str]) -> (Option<i32>, String) {
    let t0 = Instant::now();
    let o = Command::new(BIN).args(args).output().unwrap();
    assert!(
        t0.elapsed() < REFUSAL_TIME,
        "{args:?} took {:?}",
        t0.elapsed()
    );
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn image_and_subdivision_sizes_are_estimated_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/mirror.toml");
    let (code, e) = run(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--width",
        "16384",
        "--height",
        "16384",
    ]);
    assert_eq!(code, Some(2), "{e}");
    assert!(
        e.contains("16384×16384") && e.contains("--width/--height") && e.contains("GiB"),
        "{e}"
    );
    assert!(!png.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);

    // The same size from the scene file (each side within its range, the two together not):
    // an input error at the file's `camera.width`, exit 1.
    let text = std::fs::read_to_string(&scene).unwrap();
    let (mut w, mut h) = (false, false);
    let big: String = text
        .lines()
        .map(|l| match l.split('=').next().map(str::trim) {
            Some("width") if !w => {
                w = true;
                "width = 16384".to_string()
            }
            Some("height") if !h => {
                h = true;
                "height = 16384".to_string()
            }
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(w && h, "mirror.toml sets its size");
    let width_line = 1 + big.lines().position(|l| l == "width = 16384").unwrap();
    let big_scene = dir.path().join("big.toml");
    std::fs::write(&big_scene, big).unwrap();
    let (code, e) = run(&[
        "render",
        big_scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(1), "{e}");
    assert!(
        e.contains(&format!("big.toml:{width_line}:"))
            && e.contains("camera.width")
            && e.contains("16384×16384")
            && e.contains("GiB"),
        "{e}"
    );
    assert!(!png.exists());
    std::fs::remove_file(&big_scene).unwrap();

    let out = dir.path().join("b.obj");
    let bunny = shared_mesh("bunny.obj");
    let (code, e) = run(&[
        "mesh",
        "subdivide",
        bunny.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--levels",
        "6",
    ]);
    assert_eq!(code, Some(2), "{e}");
    assert!(
        e.contains("--levels 6 needs about") && e.contains("GiB"),
        "{e}"
    );
    assert!(!e.contains("Counts {"), "no Debug forms: {e}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// `--levels` beyond `MAX_LEVELS` is refused by the parser, at once, also on a mesh without
/// faces (which no level changes, so no size estimate refuses it, while each level would
/// recurse once more, up to a stack overflow). `MAX_LEVELS` itself is taken there, and on one
/// triangle it is already more than the half-edge core can hold, so the cap refuses no level
/// a mesh could reach.
#[test]
fn subdivision_levels_are_capped_where_one_face_outgrows_the_core() {
    use halfray::mesh_tools::MAX_LEVELS;
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.obj");
    std::fs::write(&empty, "v 0 0 0\nv 1 0 0\n").unwrap();
    let triangle = dir.path().join("triangle.obj");
    std::fs::write(&triangle, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let out = dir.path().join("out.obj");
    let subdivide = |input: &Path, levels: String| {
        run(&[
            "mesh",
            "subdivide",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--levels",
            &levels,
        ])
    };
    for levels in [u64::from(MAX_LEVELS) + 1, 100_000, u64::from(u32::MAX)] {
        let (code, e) = subdivide(&empty, levels.to_string());
        assert_eq!(code, Some(2), "--levels {levels}: {e}");
        assert!(
            e.contains("--levels") && e.contains(&format!("0..={MAX_LEVELS}")),
            "{e}"
        );
        assert!(!out.exists());
    }
    let (code, e) = subdivide(&empty, MAX_LEVELS.to_string());
    assert_eq!(code, Some(0), "{e}");
    assert!(out.exists());
    std::fs::remove_file(&out).unwrap();
    let (code, e) = subdivide(&triangle, MAX_LEVELS.to_string());
    assert_eq!(code, Some(2), "{e}");
    assert!(e.contains("more than the half-edge core's"), "{e}");
    let (code, e) = subdivide(&triangle, "2".into());
    assert_eq!(code, Some(0), "{e}");
    let faces = std::fs::read_to_string(&out)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("f "))
        .count();
    assert_eq!(faces, 16, "4² faces of one triangle");
}

/// A level past the core's limit names the counts that pass it and no other: on the
/// tetrahedron (V 4, E 6, F 4), level 14 has 6·4¹⁴ edges and 4·4¹⁴ = 2³⁰ faces, over
/// 2³⁰ − 1, and 4 + 2·(4¹⁴ − 1) vertices, under it.
#[test]
fn a_subdivision_past_the_core_names_the_counts_that_pass_it() {
    let dir = tempfile::tempdir().unwrap();
    let tetrahedron = dir.path().join("tetrahedron.obj");
    std::fs::write(
        &tetrahedron,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let out = dir.path().join("out.obj");
    let (code, e) = run(&[
        "mesh",
        "subdivide",
        tetrahedron.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--levels",
        "15",
    ]);
    assert_eq!(code, Some(2), "{e}");
    let level14 = 4u64.pow(14);
    assert!(
        e.contains(&format!(
            "--levels 15: level 14 would need {} edges and {} faces, more than the half-edge core's {} each",
            6 * level14,
            4 * level14,
            (1u64 << 30) - 1
        )),
        "{e}"
    );
    assert!(!e.contains(&format!("{}", 4 + 2 * (level14 - 1))), "{e}");
    assert!(!out.exists());
}

/// An OBJ whose parse and half-edge mesh would pass the memory limit is refused while it is
/// read, at the line where they do: 3 vertices and 40 `f` lines of 10⁶ fan triangles each
/// (2 bytes of file a triangle), which at 16 bytes a triangle parsed (indices and line) and
/// 3 edges, a face and 6 scratch indices of the half-edge mesh pass 4 GiB on line 34, long
/// before the end. Nothing is written.
#[test]
fn an_obj_too_large_for_the_half_edge_mesh_is_refused_at_its_line() {
    use halfray_core::halfedge::{EdgeRec, FaceRec};
    use std::mem::size_of;
    const PER_LINE: u64 = 1_000_000;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("big.obj");
    let line = format!("f{}\n", " 1 2".repeat(PER_LINE as usize / 2 + 1));
    let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{}", line.repeat(40));
    std::fs::write(&input, &text).unwrap();
    // The triangle that crosses 4 GiB with the file, the vertices' first room (1024 of 16
    // bytes) and each triangle's share; its line.
    let per_triangle = 16 + 3 * size_of::<EdgeRec>() + size_of::<FaceRec>() + 6 * 4;
    let budget = (4u64 << 30) - text.len() as u64 - 1024 * 16;
    let crossing = budget / per_triangle as u64 + 1;
    let want_line = 3 + crossing.div_ceil(PER_LINE);
    assert!(want_line < 43, "the file is large enough");
    let out = dir.path().join("out.obj");
    for args in [
        &["mesh", "check", input.to_str().unwrap()][..],
        &[
            "mesh",
            "subdivide",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
    ] {
        let (code, e) = run(args);
        assert_eq!(code, Some(1), "{e}");
        assert!(
            e.contains(&format!("big.obj:{want_line}:"))
                && e.contains("triangles, reading the file into a half-edge mesh needs about 4.0 GiB, more than the 4 GiB limit"),
            "{args:?}: {e}"
        );
        assert!(!out.exists());
    }
}

#[test]
fn ray_generation_on_a_mesh_near_f32_max_gives_up_with_an_error() {
    let s = f32::MAX / 2.0;
    let mesh = ObjMesh {
        positions: vec![
            Vec3::new(s, s, s),
            Vec3::new(s, -s, -s),
            Vec3::new(-s, s, -s),
            Vec3::new(-s, -s, s),
        ],
        triangles: vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
    };
    let t0 = Instant::now();
    let r = Workload::new(
        std::slice::from_ref(&mesh),
        std::slice::from_ref(&mesh),
        200,
        1,
    );
    assert!(t0.elapsed() < REFUSAL_TIME);
    let e = r.err().expect("no usable rays near f32::MAX");
    assert!(
        e.contains("could not generate") && e.contains("of 200"),
        "{e}"
    );
}

#[test]
fn bench_ray_sets_are_estimated_before_generating() {
    let cube = shared_mesh_str("cube.obj");
    for (width, rays, what) in [
        ("100000", "10", "--width 100000 --rays 10 needs about"),
        (
            "4294967296",
            "10",
            "--width 4294967296 --rays 10 is too large",
        ),
        (
            "16",
            "1000000000000000",
            "--width 16 --rays 1000000000000000 needs about",
        ),
    ] {
        let (code, e) = run(&["bench", "bvh", &cube, "--width", width, "--rays", rays]);
        assert_eq!(code, Some(2), "{width} {rays}: {e}");
        assert!(e.contains(what), "{width} {rays}: {e}");
    }
}

/// A worker count beyond the limit in `RAYON_NUM_THREADS` is refused by every command before
/// any work, naming the variable (the pool is built from it, checked, in `main`).
#[test]
fn a_worker_count_beyond_the_limit_is_refused() {
    let cube = shared_mesh("cube.obj");
    let o = std::process::Command::new(BIN)
        .args(["mesh", "check"])
        .arg(&cube)
        .env("RAYON_NUM_THREADS", "99999999")
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(0), "{e}");
    assert!(e.contains("RAYON_NUM_THREADS=99999999"), "{e}");
}

/// `mesh smooth --iterations` is capped as a scene's `smooth.iterations` is (10⁹ passes ran
/// on for minutes), and `bench bvh --leaf-size` starts at 1 (0 was taken silently as 1): both
/// refused by the parser, at once, with nothing written.
#[test]
fn smoothing_passes_and_leaf_sizes_are_checked_by_the_parser() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.obj");
    let cube = shared_mesh("cube.obj");
    let cap = halfray::scene::MAX_SMOOTH_ITERATIONS;
    let smooth = |n: u32| {
        run(&[
            "mesh",
            "smooth",
            cube.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--iterations",
            &n.to_string(),
        ])
    };
    for n in [cap + 1, 1_000_000_000] {
        let (code, e) = smooth(n);
        assert_eq!(code, Some(2), "{e}");
        assert!(
            e.contains("--iterations") && e.contains(&cap.to_string()),
            "{e}"
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let (code, e) = smooth(cap);
    assert_eq!(code, Some(0), "{e}");
    let (code, e) = run(&["bench", "bvh", cube.to_str().unwrap(), "--leaf-size", "0"]);
    assert_eq!(code, Some(2), "{e}");
    assert!(e.contains("--leaf-size"), "{e}");
    // A negative number is the option's value, as with `=` (it was cut to "unexpected
    // argument '-0'"), and reaches the option's own parser.
    let (cube, out) = (cube.to_str().unwrap(), out.to_str().unwrap());
    for step in [["--step", "-0.5"], ["--step=-0.5", "--force"]] {
        let (code, e) = run(&[&["mesh", "smooth", cube, "-o", out][..], &step[..]].concat());
        assert_eq!(code, Some(0), "{step:?}: {e}");
    }
    let (code, e) = run(&[
        "mesh", "smooth", cube, "-o", out, "--force", "--step", "-1e39",
    ]);
    assert_eq!(code, Some(2), "{e}");
    assert!(
        e.contains("--step") && !e.contains("unexpected argument"),
        "{e}"
    );
    let (code, e) = run(&[
        "mesh",
        "collapse",
        cube,
        "-o",
        out,
        "--force",
        "--shorter-than",
        "-1",
    ]);
    assert!(!e.contains("unexpected argument"), "{code:?}: {e}");
}
