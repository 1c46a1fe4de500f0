//! Helpers shared by the frontend's integration tests. Every test binary compiles its own copy
//! of this module and uses only part of it, hence the `dead_code` allowance.
#![allow(dead_code)]

pub mod svg;

use halfray::bench::accuracy::shared_meshes_dir;
use halfray::scene::{Scene, parse};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// The `halfray` binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_halfray");

/// Runs `halfray ARGS…` to completion (arguments as strings or paths alike).
pub fn halfray(args: &[&dyn AsRef<OsStr>]) -> Output {
    Command::new(BIN)
        .args(args.iter().map(|a| a.as_ref()))
        .output()
        .unwrap()
}

/// A 64-bit LCG (Knuth's MMIX constants) stepping `s`: an `f32` in `[0, 1)` with 24 random
/// bits, for reproducible test inputs.
pub fn lcg(s: &mut u64) -> f32 {
    *s = s
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*s >> 40) as f32) / (1u64 << 24) as f32
}

/// The standard error of a finished run, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The names of the entries of `dir`, sorted.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Starts `halfray render SCENE -o OUT` at 4000 × 3000 (long enough to interrupt) with
/// `--allow-long` (at that size the worst case of `glass.toml` is over the work budget: 16
/// segments per shadow ray through its glass) and returns
/// the running child once it has printed its `rendering …` line, i.e. once the outputs were
/// checked and the work began. Its stdout is discarded; the rest of its stderr stays piped.
pub fn start_long_render(scene: &Path, out: &Path) -> Child {
    let mut child = Command::new(BIN)
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--width", "4000", "--height", "3000", "--allow-long"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    std::io::BufRead::read_line(&mut err, &mut line).unwrap();
    assert!(line.starts_with("rendering"), "{line}");
    child.stderr = Some(err.into_inner());
    child
}

// Scene text: the tables the test scenes are made of, written once. Values are TOML text, so a
// scene reads as it is written (`"[0, 1.2, 0]"`, `"3e38"`), and each table ends in a newline:
// a test appends further keys of the same table (`cast_shadows = false`) right after it.

/// A `[camera]` table: `eye`, `look_at`, the vertical `fov` in degrees, `[width, height]`.
pub fn camera(eye: &str, look_at: &str, fov: &str, [width, height]: [u32; 2]) -> String {
    format!(
        "[camera]\neye = {eye}\nlook_at = {look_at}\nfov = {fov}\nwidth = {width}\nheight = {height}\n"
    )
}

/// A point `[[light]]` at `position` of `intensity`.
pub fn point_light(position: &str, intensity: &str) -> String {
    format!("[[light]]\ntype = \"point\"\nposition = {position}\nintensity = {intensity}\n")
}

/// A directional `[[light]]` shining along `direction`.
pub fn directional_light(direction: &str) -> String {
    format!("[[light]]\ntype = \"directional\"\ndirection = {direction}\n")
}

/// A sphere `[[object]]` of `material`.
pub fn sphere(center: &str, radius: &str, material: &str) -> String {
    format!(
        "[[object]]\ntype = \"sphere\"\ncenter = {center}\nradius = {radius}\nmaterial = \"{material}\"\n"
    )
}

/// A plane `[[object]]` through `point` with `normal`, of `material`.
pub fn plane(point: &str, normal: &str, material: &str) -> String {
    format!(
        "[[object]]\ntype = \"plane\"\npoint = {point}\nnormal = {normal}\nmaterial = \"{material}\"\n"
    )
}

/// A `[material.<name>]` table of `fields`, each `(key, value)`.
pub fn material(name: &str, fields: &[(&str, &str)]) -> String {
    let rows: String = fields.iter().map(|(k, v)| format!("{k} = {v}\n")).collect();
    format!("[material.{name}]\n{rows}")
}

/// The shipped example scenes, `<workspace>/scenes` (as `frontend/../scenes`).
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")
}

/// The example scenes' files, every `*.toml` of [`scenes_dir`], sorted.
pub fn example_scene_paths() -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    paths
}

/// The shared test mesh `name` (e.g. `"cube.obj"`) in halfray's [`shared_meshes_dir`]:
/// `$HALFRAY_MESHES` if set, else `../shared/meshes` beside the repository.
pub fn shared_mesh(name: &str) -> PathBuf {
    shared_meshes_dir().join(name)
}

/// [`shared_mesh`] as text, for argument lists of strings; panics if the path is not UTF-8.
pub fn shared_mesh_str(name: &str) -> String {
    let path = shared_mesh(name);
    path.to_str()
        .unwrap_or_else(|| panic!("{} is not UTF-8", path.display()))
        .to_owned()
}

/// Parses a test scene's `text` (as if read from `test.toml`); panics with the error.
pub fn parse_scene(text: &str) -> Scene {
    parse(text, Path::new("test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// One `--jsonl` line: mesh `mesh`, shard `index`/`count`, one set `primary` of `genuine`
/// rays (at least one), each a genuine mismatch (made-up counts, consistent as a run's are:
/// the merge refuses a set with more verdicts than rays before it sums).
pub fn result_line(mesh: &str, index: u64, count: u64, genuine: u64) -> String {
    let set = serde_json::json!({
        "mesh": mesh, "path": mesh, "name": "primary",
        "rays": genuine.max(1), "agree": 0, "genuine_mismatches": genuine, "ties": 0,
        "within_tolerance": 0, "embree_wrong": 0, "leaks_halfray": 0, "leaks_embree": 0,
        "leaks_embree_default": 0, "leak_rays": 0, "any_hit_disagreements": 0,
        "any_vs_closest_inconsistent": 0, "timed_rays": 0, "secs_halfray": 0.0,
        "secs_embree": 0.0, "secs_embree_default": 0.0, "mrays_halfray": 0.0,
        "mrays_embree": 0.0, "mrays_embree_default": 0.0, "disagreements": []
    });
    serde_json::json!({
        "path": mesh, "intersector": "watertight", "seed": 1, "rays": 10,
        "ray_sets": ["primary"], "shard": {"index": index, "count": count}, "sets": [set]
    })
    .to_string()
}

/// A PNG of `w`×`h` RGBA pixels, `depth` bits a channel (8 or 16), that holds only its header
/// (signature, `IHDR`, an `IDAT` of an empty zlib stream, `IEND`): its size can be read, its
/// pixels cannot be decoded. CRC-32 (IEEE, reflected) computed here.
pub fn header_only_png(w: u32, h: u32, depth: u8) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    let chunk = |kind: &[u8; 4], data: &[u8]| {
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
        out
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[depth, 6, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    png.extend(chunk(b"IEND", &[]));
    png
}
