//! Random input through the command-line entry points, in process: random bytes as OBJ files
//! (`mesh check`, `mesh smooth`, `mesh subdivide`), random mutations of a valid scene
//! (`render`), and hostile command lines: device paths as inputs and outputs,
//! `/dev/std*` outputs, `repeat` counts whose product overflows, file names with terminal
//! escapes and line breaks, and `crosscheck merge` parts with extreme numbers. Every run must end with success or a clean error of exit code 1 or 2, never a
//! panic; a failed run leaves no output file and a prior output file unchanged.
//! Deterministic (fixed seed), a few seconds.

use clap::Parser;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

mod common;
use common::{camera, material, plane, sphere};

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
    Crosscheck(halfray::crosscheck::CrosscheckArgs),
    Bake(halfray::bake::BakeArgs),
}

/// Runs `args` in process: `Ok(())` or the error's exit code; panics are reported with the
/// input that caused them.
fn run(args: &[&str], input: &str) -> Result<(), u8> {
    run_told(args, input).map_err(|(code, _)| code)
}

/// [`run`], with the error's message as the binary would print it.
fn run_told(args: &[&str], input: &str) -> Result<(), (u8, String)> {
    let cli = Cli::try_parse_from(std::iter::once("halfray").chain(args.iter().copied()))
        .unwrap_or_else(|e| panic!("test arguments rejected: {e}"));
    let outcome = catch_unwind(AssertUnwindSafe(|| match &cli.command {
        Cmd::Render(a) => halfray::render::run(a),
        Cmd::Mesh(m) => halfray::mesh_tools::run(m),
        Cmd::Crosscheck(c) => halfray::crosscheck::run(c),
        Cmd::Bake(b) => halfray::bake::run(b),
    }));
    match outcome {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err((e.exit_code(), e.to_string())),
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
    let red = material(
        "red",
        &[
            ("diffuse", "[0.8, 0.1, 0.1]"),
            ("specular", "[0.2, 0.2, 0.2]"),
            ("shininess", "20"),
            ("mirror", "0.2"),
        ],
    );
    let glass = material("glass", &[("transparency", "0.9"), ("ior", "1.5")]);
    format!(
        r#"ambient = [0.1, 0.1, 0.1]
max_depth = 4

{camera}
[[light]]
type = "point"
position = [2, 4, 3]
color = [1, 1, 1]

{red}
{glass}
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

/// A temporary directory holding `tet.obj` (the scene's mesh), with the paths of the scene
/// and of the image to write there.
fn scene_dir() -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("tet.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    let (scene, out) = (dir.path().join("scene.toml"), dir.path().join("out.png"));
    (dir, scene, out)
}

#[test]
fn mutated_scenes_through_render() {
    let (_dir, scene, out) = scene_dir();
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

/// A string that must never reach the terminal raw: ESC, BEL, a line break that could start a
/// forged `error:` line.
fn assert_escaped(message: &str, case: &str) {
    assert!(
        !message.contains('\u{1b}') && !message.contains('\u{7}') && !message.contains('\r'),
        "raw control characters in the message of {case}: {message:?}"
    );
}

/// Hostile names: terminal escapes, line breaks, a bidirectional override, a `|`.
const HOSTILE: &[&str] = &[
    "\u{1b}]0;title\u{7}",
    "\u{1b}[2J",
    "\nerror: forged",
    "\r",
    "\u{202e}",
    "a|b",
];

#[test]
fn hostile_command_lines() {
    let (dir, scene, out) = scene_dir();
    let (sc, o) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let mut r = Lcg(0x0037_0037);
    let small = valid_scene().replace("max_depth = 4", "max_depth = 1");
    // Device paths as inputs: refused before reading (a read of /dev/zero would not end).
    const DEVICES_IN: &[&str] = &["/dev/zero", "/dev/urandom", "/dev/null", "/"];
    // Device and descriptor paths as outputs: written in place or refused, never replaced.
    const DEVICES_OUT: &[&str] = &["/dev/null", "/dev/full", "/dev/stderr", "/proc/self/fd/2"];
    for case in 0..200 {
        std::fs::write(&scene, &small).unwrap();
        let input = DEVICES_IN[r.below(DEVICES_IN.len())];
        let device = DEVICES_OUT[r.below(DEVICES_OUT.len())];
        let hostile = HOSTILE[r.below(HOSTILE.len())];
        let named = dir.path().join(format!("m{hostile}.obj"));
        let named = named.to_str().unwrap();
        let big = |r: &mut Lcg| {
            [
                0u64,
                1,
                2,
                65_536,
                2_147_549_185,
                4_294_836_226,
                4_294_967_295,
            ][r.below(7)]
        };
        let repeat = format!(
            "{small}repeat = {{ count = [{}, {}, {}], step = [0, 0, 0] }}\n",
            big(&mut r),
            big(&mut r),
            big(&mut r)
        );
        let (args, text): (Vec<&str>, String) = match case % 6 {
            0 => (vec!["mesh", "check", input], input.into()),
            1 => (vec!["render", input, "-o", o, "-q"], input.into()),
            2 => {
                // The PNG to a device, the statistics to a regular file (or the reverse).
                if r.below(2) == 0 {
                    // The image only to a sink (not as bytes into the test's log).
                    let sink = ["/dev/null", "/dev/full"][r.below(2)];
                    (vec!["render", sc, "-o", sink, "-q"], sink.into())
                } else {
                    (
                        vec!["render", sc, "-o", o, "--stats-json", device, "-q"],
                        device.into(),
                    )
                }
            }
            3 => {
                std::fs::write(&scene, &repeat).unwrap();
                (vec!["render", sc, "-o", o, "-q"], repeat.clone())
            }
            4 => {
                // A hostile file name: missing, or a valid mesh baked.
                if r.below(2) == 0 {
                    std::fs::copy(dir.path().join("tet.obj"), named).unwrap();
                }
                (vec!["bake", named, "-o", o], named.into())
            }
            _ => {
                std::fs::write(
                    &scene,
                    format!(
                        "{small}\n[mesh.h]\nfile = \"m{}.obj\"\n",
                        hostile
                            .chars()
                            .map(|c| format!("\\u{:04X}", u32::from(c)))
                            .collect::<String>()
                    ),
                )
                .unwrap();
                (vec!["render", sc, "-o", o, "-q"], hostile.into())
            }
        };
        std::fs::write(&out, PRIOR).unwrap();
        match run_told(&args, &text) {
            Ok(()) => {}
            Err((code, message)) => {
                assert!(code == 1 || code == 2, "exit {code} on {args:?}: {message}");
                assert_escaped(&message, &format!("{args:?}"));
                assert_eq!(std::fs::read(&out).unwrap(), PRIOR, "{args:?} touched -o");
            }
        }
        let _ = std::fs::remove_file(named);
    }
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

/// `crosscheck merge` parts with extreme numbers: counts at and beyond the `u64` range,
/// negative and fractional counts, impossible shards, a BOM, concatenated lines. Every run
/// ends in a verdict or a clean error of exit code 1, 2 or 3, never a panic or a wrapped sum;
/// a merge that succeeds reports totals equal to the exact (`u128`) sums.
#[test]
fn merge_parts_with_extreme_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let mut r = Lcg(0x0e47_0e47);
    const NUMBERS: &[&str] = &[
        "0",
        "1",
        "9223372036854775807",
        "9223372036854775808",
        "18446744073709551615",
        "18446744073709551616",
        "-1",
        "1e300",
        "0.5",
    ];
    for case in 0..200 {
        let parts = 1 + r.below(3);
        let count = r.below(4);
        let mut paths = Vec::new();
        let mut exact: u128 = 0;
        let mut all_valid = true;
        for p in 0..parts {
            let genuine = NUMBERS[r.below(NUMBERS.len())];
            let index = r.below(4);
            match genuine.parse::<u64>() {
                Ok(g) => exact += u128::from(g),
                Err(_) => all_valid = false,
            }
            all_valid &= index < count;
            let line = format!(
                "{{\"path\":\"a.obj\",\"intersector\":\"watertight\",\"seed\":1,\"rays\":10,\"ray_sets\":[\"primary\"],\"shard\":{{\"index\":{index},\"count\":{count}}},\"sets\":[{{\"mesh\":\"a.obj\",\"path\":\"a.obj\",\"name\":\"primary\",\"rays\":1,\"agree\":0,\"genuine_mismatches\":{genuine},\"ties\":0,\"within_tolerance\":0,\"embree_wrong\":0,\"leaks_halfray\":0,\"leaks_embree\":0,\"leaks_embree_default\":0,\"leak_rays\":0,\"any_hit_disagreements\":0,\"any_vs_closest_inconsistent\":0,\"timed_rays\":0,\"secs_halfray\":0.0,\"secs_embree\":0.0,\"secs_embree_default\":0.0,\"mrays_halfray\":0.0,\"mrays_embree\":0.0,\"mrays_embree_default\":0.0,\"disagreements\":[]}}]}}\n"
            );
            let bom = if r.below(4) == 0 { "\u{feff}" } else { "" };
            let path = dir.path().join(format!("p{case}-{p}.jsonl"));
            std::fs::write(&path, format!("{bom}{line}")).unwrap();
            paths.push(path.to_str().unwrap().to_string());
        }
        let mut args = vec!["crosscheck", "merge"];
        args.extend(paths.iter().map(String::as_str));
        args.extend(["--max-mismatch", "0"]);
        match run_told(&args, &format!("case {case}")) {
            Ok(()) => assert!(
                all_valid && exact == 0,
                "case {case}: passed with {exact} genuine"
            ),
            Err((code, message)) => {
                assert!(
                    (1..=3).contains(&code),
                    "case {case}: exit {code}: {message}"
                );
                assert_escaped(&message, &format!("case {case}"));
                if code == 3 {
                    // A verdict: the total it reports is the exact sum.
                    assert!(
                        message.starts_with(&format!("{exact} genuine mismatches")),
                        "case {case}: {message} (exact {exact})"
                    );
                }
            }
        }
    }
}
