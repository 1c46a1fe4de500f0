//! Random input through the command-line entry points, in process: random bytes as OBJ files
//! (`mesh check`, `mesh smooth`, `mesh subdivide`) and random mutations of a valid scene
//! (`render`). Every run must end with success or a clean error of exit code 1 or 2, never a
//! panic; a failed run leaves no output file and a prior output file unchanged.
//! Deterministic (fixed seed), a few seconds.

use clap::Parser;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

mod common;
use common::{camera, plane, sphere};

#[derive(Parser)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(clap::Subcommand)]
enum Cmd {
    Render(halfray::render::RenderArgs),
    #[command(subcommand)]
    Mesh(halfray::mesh_tools::MeshCommand),
}

/// Runs `args` in process: `Ok(())` or the error's exit code; panics are reported with the
/// input that caused them.
fn run(args: &[&str], input: &str) -> Result<(), u8> {
    let cli = Cli::try_parse_from(std::iter::once("halfray").chain(args.iter().copied()))
        .unwrap_or_else(|e| panic!("test arguments rejected: {e}"));
    let outcome = catch_unwind(AssertUnwindSafe(|| match &cli.command {
        Cmd::Render(a) => halfray::render::run(a),
        Cmd::Mesh(m) => halfray::mesh_tools::run(m),
    }));
    match outcome {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(e.exit_code()),
        Err(_) => panic!("panic on {args:?} with input:\n{input}"),
    }
}

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const PRIOR: &[u8] = b"prior output, must survive a failed run\n";

/// Runs one command that writes `out`, with a prior file there; checks the exit code and
/// that a failure left the prior file as it was.
#[track_caller]
fn check_writer(args: &[&str], out: &Path, input: &str) -> bool {
    std::fs::write(out, PRIOR).unwrap();
    match run(args, input) {
        Ok(()) => true,
        Err(code) => {
            assert!(
                code == 1 || code == 2,
                "exit {code} on {args:?} with:\n{input}"
            );
            let now = std::fs::read(out).unwrap();
            assert_eq!(
                now, PRIOR,
                "a failed {args:?} touched its output; input:\n{input}"
            );
            false
        }
    }
}

/// Random OBJ-ish text: valid statements, broken numbers, stray bytes, huge and non-finite
/// values, out-of-range and negative indices.
fn random_obj(r: &mut Lcg) -> String {
    const TOKENS: &[&str] = &[
        "v",
        "f",
        "vn",
        "vt",
        "o",
        "g",
        "s",
        "#",
        "usemtl",
        "0",
        "1",
        "-1",
        "2",
        "3",
        "4",
        "0.5",
        "1e39",
        "-1e-45",
        "nan",
        "inf",
        "1/2/3",
        "-2",
        "99999999999",
        "x",
        "\u{feff}",
        "\t",
    ];
    let mut s = String::new();
    for _ in 0..r.below(40) {
        match r.below(4) {
            0 => {
                let k = r.below(3);
                s.push_str(&format!("v {} {} {}\n", k, r.below(3), r.below(2)));
            }
            1 => s.push_str(&format!(
                "f {} {} {}\n",
                1 + r.below(6),
                1 + r.below(6),
                1 + r.below(6)
            )),
            2 => {
                for _ in 0..1 + r.below(5) {
                    s.push_str(TOKENS[r.below(TOKENS.len())]);
                    s.push(' ');
                }
                s.push(['\n', '\r'][r.below(2)]);
            }
            _ => {
                for _ in 0..r.below(12) {
                    s.push(char::from_u32(r.below(0x80) as u32).unwrap_or('?'));
                }
                s.push('\n');
            }
        }
    }
    s
}

#[test]
fn random_obj_files_through_the_mesh_tools() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.obj");
    let out = dir.path().join("out.obj");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let mut r = Lcg(0x0b1f_11e0);
    let mut ok = 0;
    for case in 0..300 {
        // A quarter of the cases: a closed tetrahedron with random statements appended (most
        // of them still valid meshes, so the success path is exercised too).
        let text = if case % 4 == 0 {
            let junk = random_obj(&mut r);
            let keep = junk.lines().take(r.below(3)).collect::<Vec<_>>().join("\n");
            format!(
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n{keep}\n"
            )
        } else {
            random_obj(&mut r)
        };
        std::fs::write(&input, &text).unwrap();
        if let Err(code) = run(&["mesh", "check", i], &text) {
            assert!(code == 1 || code == 2, "check exit {code} on:\n{text}");
        }
        ok += usize::from(check_writer(
            &["mesh", "smooth", i, "-o", o, "--iterations", "2"],
            &out,
            &text,
        ));
        check_writer(
            &["mesh", "subdivide", i, "-o", o, "--levels", "1"],
            &out,
            &text,
        );
    }
    assert!(
        ok >= 30,
        "too few valid meshes ({ok}) to exercise the success path"
    );
}

/// The valid scene the mutations start from: a sphere, a plane and a glass mesh.
fn valid_scene() -> String {
    let camera = camera("[0, 1, 5]", "[0, 0, 0]", "40", [16, 12]);
    let sphere = sphere("[0, 0, 0]", "1", "red");
    let plane = plane("[0, -1, 0]", "[0, 1, 0]", "red");
    format!(
        r#"ambient = [0.1, 0.1, 0.1]
max_depth = 4

{camera}
[[light]]
type = "point"
position = [2, 4, 3]
color = [1, 1, 1]

[material.red]
diffuse = [0.8, 0.1, 0.1]
specular = [0.2, 0.2, 0.2]
shininess = 20
mirror = 0.2

[material.glass]
transparency = 0.9
ior = 1.5

[mesh.tet]
file = "tet.obj"

{sphere}
{plane}
[[object]]
type = "mesh"
mesh = "tet"
material = "glass"
transform = [{{ translate = [1.5, 0, 0] }}, {{ scale = 0.5 }}]
"#
    )
}

/// Mutations of a valid scene: a character deleted, inserted or replaced, a number replaced by
/// an extreme or non-numeric token, a line duplicated or dropped.
fn mutate(r: &mut Lcg, s: &str) -> String {
    const REPLACEMENTS: &[&str] = &[
        "nan",
        "inf",
        "-inf",
        "1e39",
        "-1e39",
        "0",
        "-0",
        "1e-45",
        "\"x\"",
        "[]",
        "[1, 2]",
        "[1, 2, 3, 4]",
        "{}",
        "true",
        "4294967296",
        "-1",
        "65",
        "1e30",
    ];
    let mut s = s.to_string();
    for _ in 0..1 + r.below(3) {
        let bytes = s.as_bytes();
        let at = r.below(bytes.len());
        let at = (0..=at).rev().find(|&k| s.is_char_boundary(k)).unwrap_or(0);
        match r.below(5) {
            0 => {
                let end = (at + 1..=s.len())
                    .find(|&k| s.is_char_boundary(k))
                    .unwrap_or(s.len());
                s.replace_range(at..end, "");
            }
            1 => s.insert(at, ['[', ']', '"', '=', '\n', '.', '-', '{'][r.below(8)]),
            2 => {
                // Replace the number (or word) starting at or after `at`.
                let rest = &s[at..];
                if let Some(p) = rest.find(|c: char| c.is_ascii_digit()) {
                    let start = at + p;
                    let len = s[start..]
                        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
                        .unwrap_or(s.len() - start);
                    s.replace_range(
                        start..start + len,
                        REPLACEMENTS[r.below(REPLACEMENTS.len())],
                    );
                }
            }
            3 => {
                let lines: Vec<&str> = s.lines().collect();
                let k = r.below(lines.len());
                let mut v: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
                v.insert(k, lines[k].to_string());
                s = v.join("\n");
            }
            _ => {
                let mut v: Vec<&str> = s.lines().collect();
                let k = r.below(v.len());
                v.remove(k);
                s = v.join("\n");
            }
        }
    }
    s
}

#[test]
fn mutated_scenes_through_render() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("tet.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    let scene = dir.path().join("scene.toml");
    let out = dir.path().join("out.png");
    let (sc, o) = (scene.to_str().unwrap(), out.to_str().unwrap());
    // Control: the unmutated scene renders.
    let valid = valid_scene();
    std::fs::write(&scene, &valid).unwrap();
    assert!(check_writer(&["render", sc, "-o", o, "-q"], &out, &valid));
    let mut r = Lcg(0x0005_ce7e);
    let (mut ok, mut refused) = (0, 0);
    for _ in 0..400 {
        let text = mutate(&mut r, &valid);
        std::fs::write(&scene, &text).unwrap();
        if check_writer(&["render", sc, "-o", o, "-q"], &out, &text) {
            ok += 1;
        } else {
            refused += 1;
        }
    }
    // Both paths exercised (most mutations break the file; some keep it valid).
    assert!(
        ok >= 20 && refused >= 100,
        "ok {ok}, refused {refused}: mutations too mild or too harsh"
    );
}
