//! The command line driven as a hostile user would (issue 37): one test per class of defect,
//! each on the binary. Data loss (a declared mesh overwritten, a file behind `/dev/stdout`
//! replaced), wrapping counters and impossible shards in `crosscheck merge`, meshes outside
//! the coordinate domain, overflowing `repeat` products, a huge `RAYON_NUM_THREADS`,
//! unbounded reads of devices, work estimates, stale temporary files, injection into `bake`'s
//! Rust, terminal escapes in messages, misleading errors and outputs that must be all or
//! nothing.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

mod common;
use common::{BIN, camera, sphere, stderr};

/// `v`/`f` text of a closed tetrahedron with its vertices at `±s` (the origin inside).
fn tetrahedron(s: &str) -> String {
    format!(
        "v {s} {s} {s}\nv {s} -{s} -{s}\nv -{s} {s} -{s}\nv -{s} -{s} {s}\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n"
    )
}

/// A small scene (8×6, one sphere), written to `dir/name`; `extra` is appended.
fn small_scene(dir: &Path, name: &str, extra: &str) -> PathBuf {
    let text = format!(
        "{}[[light]]\ntype = \"point\"\nposition = [2, 4, 3]\n[material.m]\ndiffuse = [1, 1, 1]\n{}{extra}",
        camera("[0, 0, 5]", "[0, 0, 0]", "40", [8, 6]),
        sphere("[0, 0, 0]", "1", "m"),
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn run(args: &[&dyn AsRef<OsStr>]) -> Output {
    common::halfray(args)
}

/// Runs with stdout appended to `log` (as `>> log` does).
fn run_appending(args: &[&dyn AsRef<OsStr>], log: &Path) -> Output {
    let out = std::fs::OpenOptions::new().append(true).open(log).unwrap();
    Command::new(BIN)
        .args(args.iter().map(|a| a.as_ref()))
        .stdout(out)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Item 1: every file a scene names is an input, used by an object or not.
#[test]
fn a_declared_but_unused_mesh_file_is_never_an_output() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    std::fs::write(&cube, tetrahedron("1")).unwrap();
    let scene = small_scene(dir.path(), "s.toml", "[mesh.unused]\nfile = \"cube.obj\"\n");
    let before = std::fs::read(&cube).unwrap();
    for out in [cube.clone(), dir.path().join("./cube.obj")] {
        let o = run(&[&"render", &scene, &"-o", &out, &"-q"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("refusing to overwrite an input"),
            "{}",
            stderr(&o)
        );
        assert_eq!(std::fs::read(&cube).unwrap(), before);
    }
    let o = run(&[
        &"render",
        &scene,
        &"-o",
        &dir.path().join("x.png"),
        &"--stats-json",
        &cube,
        &"-q",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(std::fs::read(&cube).unwrap(), before);
    assert_eq!(names(dir.path()), ["cube.obj", "s.toml"]);
}

/// Item 2: `/dev/stdout`, `/dev/fd/1`, `/proc/self/fd/1` and `-` are written through the
/// descriptor: a file stdout is appended to keeps its earlier lines.
#[test]
fn outputs_naming_stdout_append_to_it_and_never_replace_the_file_behind() {
    let dir = tempfile::tempdir().unwrap();
    let scene = small_scene(dir.path(), "s.toml", "");
    let png = dir.path().join("x.png");
    let log = dir.path().join("log.txt");
    for stdout in ["/dev/stdout", "/dev/fd/1", "/proc/self/fd/1", "-"] {
        std::fs::write(&log, b"earlier line\n").unwrap();
        let o = run_appending(
            &[
                &"render",
                &scene,
                &"-o",
                &png,
                &"--stats-json",
                &stdout,
                &"-q",
            ],
            &log,
        );
        assert_eq!(o.status.code(), Some(0), "{stdout}: {}", stderr(&o));
        let text = std::fs::read_to_string(&log).unwrap();
        let json = text.strip_prefix("earlier line\n").unwrap_or_else(|| {
            panic!("{stdout}: earlier line lost: {text:?}");
        });
        assert!(json.starts_with('{'), "{stdout}: {json}");
        assert!(json.contains("\"primary\": 48"), "{json}");
        assert!(
            json.contains("\nrays: primary 48 "),
            "summary after: {json}"
        );
        // The PNG to stdout, after the earlier line.
        std::fs::write(&log, b"earlier line\n").unwrap();
        let o = run_appending(&[&"render", &scene, &"-o", &stdout, &"-q"], &log);
        assert_eq!(o.status.code(), Some(0), "{stdout}: {}", stderr(&o));
        let bytes = std::fs::read(&log).unwrap();
        assert!(bytes.starts_with(b"earlier line\n\x89PNG"), "{stdout}");
    }
    // A symlink to /dev/stdout is the descriptor too.
    let link = dir.path().join("out.json");
    std::os::unix::fs::symlink("/dev/stdout", &link).unwrap();
    std::fs::write(&log, b"earlier line\n").unwrap();
    let o = run_appending(
        &[
            &"render",
            &scene,
            &"-o",
            &png,
            &"--stats-json",
            &link,
            &"-q",
        ],
        &log,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        std::fs::read_to_string(&log)
            .unwrap()
            .starts_with("earlier line\n{"),
    );
    // Two outputs to stdout are one file.
    let o = run_appending(
        &[
            &"render",
            &scene,
            &"-o",
            &"-",
            &"--stats-json",
            &"/dev/stdout",
        ],
        &log,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("are the same file"), "{}", stderr(&o));
    assert_eq!(
        names(dir.path()),
        ["log.txt", "out.json", "s.toml", "x.png"]
    );
}

/// Item 10: no temporary file exists while a command works (an abort or SIGKILL then leaves
/// nothing), and one left by a process that is gone is removed by the next write there.
#[test]
fn temporary_files_exist_only_while_writing_and_stale_ones_are_removed() {
    let dir = tempfile::tempdir().unwrap();
    let scene = small_scene(dir.path(), "s.toml", "");
    let png = dir.path().join("out.png");
    let mut child = Command::new(BIN)
        .args([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            png.as_os_str(),
            "--width".as_ref(),
            "4000".as_ref(),
            "--height".as_ref(),
            "3000".as_ref(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    std::io::BufRead::read_line(&mut err, &mut line).unwrap();
    assert!(line.starts_with("rendering"), "{line}");
    child.kill().unwrap(); // SIGKILL: no handler runs.
    child.wait().unwrap();
    assert_eq!(
        names(dir.path()),
        ["s.toml"],
        "nothing left by a killed run"
    );
    // A stale temporary file of a process that is gone, an hour old.
    let mut gone = Command::new("true").spawn().unwrap();
    let pid = gone.id();
    gone.wait().unwrap();
    let stale = dir.path().join(format!(".halfray-{pid}-0.tmp"));
    let f = std::fs::File::create(&stale).unwrap();
    f.set_modified(std::time::SystemTime::now() - std::time::Duration::from_secs(7200))
        .unwrap();
    drop(f);
    let o = run(&[&"render", &scene, &"-o", &png, &"-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(names(dir.path()), ["out.png", "s.toml"]);
}
