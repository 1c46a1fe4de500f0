//! The binary's outputs: an output that is an input or another output is refused
//! by file identity, output locations are checked before the work, temporary files go away
//! on SIGTERM, and stdout or stderr that is a closed pipe or a full device ends the program
//! cleanly.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{
    BIN, file_names as files, result_line, scenes_dir, shared_mesh, shared_mesh_str,
    start_long_render, stderr,
};

/// How long the SIGTERM test waits for the killed render to exit.
const EXIT_WAIT: Duration = Duration::from_secs(30);

fn scene(name: &str) -> PathBuf {
    scenes_dir().join(name)
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

macro_rules! os {
    ($($a:expr),* $(,)?) => { &[$(std::ffi::OsStr::new($a)),*] };
}

#[test]
fn an_output_that_is_an_input_or_another_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let victim = dir.path().join("victim.toml");
    std::fs::copy(scene("mirror.toml"), &victim).unwrap();
    let original = std::fs::read(&victim).unwrap();
    // The scene itself, spelt three ways: same path, through `sub/..`, through a symlink.
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let link = dir.path().join("link.png");
    std::os::unix::fs::symlink(&victim, &link).unwrap();
    for out in [
        victim.clone(),
        dir.path().join("sub/../victim.toml"),
        link.clone(),
    ] {
        let o = run(os!["render", &victim, "-o", &out, "--quiet"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("refusing to overwrite an input"),
            "{}",
            stderr(&o)
        );
        assert_eq!(std::fs::read(&victim).unwrap(), original);
    }
    // Two outputs naming one file (one of them not existing yet).
    let x = dir.path().join("x.png");
    let o = run(os![
        "render",
        &victim,
        "-o",
        &x,
        "--stats-json",
        &dir.path().join("sub/../x.png"),
        "--quiet"
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("are the same file"), "{}", stderr(&o));
    // A mesh tool writing over its input, through a hard link.
    let cube = dir.path().join("cube.obj");
    std::fs::copy(shared_mesh("cube.obj"), &cube).unwrap();
    let hard = dir.path().join("hard.obj");
    std::fs::hard_link(&cube, &hard).unwrap();
    let before = std::fs::read(&cube).unwrap();
    for out in [&cube, &hard] {
        let o = run(os!["mesh", "smooth", &cube, "-o", out, "--force"]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert_eq!(std::fs::read(&cube).unwrap(), before);
    }
    // A render writing over one of the scene's mesh files.
    let bunny_scene = dir.path().join("b.toml");
    std::fs::write(
        &bunny_scene,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 8\n\
         [mesh.c]\nfile = \"cube.obj\"\n[material.m]\ndiffuse = [1, 1, 1]\n\
         [[object]]\ntype = \"mesh\"\nmesh = \"c\"\nmaterial = \"m\"\n",
    )
    .unwrap();
    let o = run(os![
        "render",
        &bunny_scene,
        "-o",
        &cube,
        "--quiet",
        "--force"
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("mesh file"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&cube).unwrap(), before);
    assert_eq!(
        files(dir.path()),
        [
            "b.toml",
            "cube.obj",
            "hard.obj",
            "link.png",
            "sub",
            "victim.toml"
        ]
    );
}

/// The same refusals when the outputs are bare file names in the working directory (the
/// usual command line): a name without a folder is identified in `.`, so two outputs naming
/// one new file, or an output naming the scene, are caught as with full paths.
#[test]
fn bare_names_in_the_working_directory_are_identified_too() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(scene("mirror.toml"), dir.path().join("s.toml")).unwrap();
    let in_dir = |args: &[&str]| {
        Command::new(BIN)
            .args(args)
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    let o = in_dir(&[
        "render",
        "s.toml",
        "-o",
        "x.png",
        "--stats-json",
        "x.png",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("are the same file"), "{}", stderr(&o));
    let o = in_dir(&["render", "s.toml", "-o", "s.toml", "--quiet", "--force"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("refusing to overwrite an input"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read(dir.path().join("s.toml")).unwrap(),
        std::fs::read(scene("mirror.toml")).unwrap()
    );
    assert_eq!(files(dir.path()), ["s.toml"], "nothing written");
}

#[test]
fn output_locations_are_checked_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("out.png");
    let started = Instant::now();
    // A big render that would take long: it must fail at once, before rendering.
    let big_render = |stats: &Path| {
        run(os![
            "render",
            &scene("glass.toml"),
            "-o",
            &png,
            "--stats-json",
            stats,
            "--width",
            "16000",
            "--height",
            "16000"
        ])
    };
    let o = big_render(&dir.path().join("nodir/stats.json"));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("nodir/stats.json") && e.contains("does not exist"),
        "{e}"
    );
    assert!(!e.contains("rendering"), "failed before rendering: {e}");
    assert!(started.elapsed() < Duration::from_secs(20));
    assert_eq!(files(dir.path()), Vec::<String>::new(), "no PNG, no temp");
    let o = run(os![
        "mesh",
        "subdivide",
        &shared_mesh("cube.obj"),
        "-o",
        &dir.path().join("nodir/x.obj")
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    let o = run(os![
        "mesh",
        "check",
        &shared_mesh("cube.obj"),
        "--json",
        dir.path()
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("is a directory"), "{}", stderr(&o));
    assert!(o.stdout.is_empty(), "nothing checked, nothing printed");
    // A second output whose name can only be a folder's (`stats.json/`): refused before the
    // render, and the first output, which exists, keeps its bytes.
    std::fs::write(&png, b"prior").unwrap();
    for stats in ["stats.json/", "out.png/"] {
        let o = big_render(&PathBuf::from(format!("{}/{stats}", dir.path().display())));
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(stats) && e.contains("names a folder"), "{e}");
        assert!(!e.contains("rendering"), "failed before rendering: {e}");
        assert_eq!(std::fs::read(&png).unwrap(), b"prior", "{stats}");
        assert_eq!(files(dir.path()), ["out.png"], "{stats}: no temporary file");
    }
}

/// `bench bvh` and `bench accel` reserve `--json` before they measure: a report never
/// replaces one of the meshes or the mesh list it ran on, and a report that cannot be written
/// fails the run before minutes of work.
#[test]
fn a_benchmark_report_is_reserved_first_and_is_never_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    std::fs::copy(shared_mesh("cube.obj"), &cube).unwrap();
    // Writable, as a user's own mesh (the shared copies are read-only).
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&cube, std::fs::Permissions::from_mode(0o644)).unwrap();
    let list = dir.path().join("list.txt");
    std::fs::write(&list, format!("{}\n", cube.display())).unwrap();
    let before = (std::fs::read(&cube).unwrap(), std::fs::read(&list).unwrap());
    let sizes = ["--width", "4", "--rays", "4"];
    let cases: [(&[&str], &Path, &Path); 3] = [
        (&["bench", "bvh", "--sets", "primary"], &cube, &cube),
        (
            &["bench", "bvh", "--sets", "primary", "--mesh-list"],
            &list,
            &list,
        ),
        (&["bench", "accel"], &cube, &cube),
    ];
    for (command, input, json) in cases {
        let mut a: Vec<&std::ffi::OsStr> = command.iter().map(std::ffi::OsStr::new).collect();
        a.push(input.as_os_str());
        a.extend(sizes.iter().map(std::ffi::OsStr::new));
        a.extend([std::ffi::OsStr::new("--json"), json.as_os_str()]);
        let o = run(&a);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("refusing to overwrite an input"),
            "{}",
            stderr(&o)
        );
        assert!(o.stdout.is_empty(), "nothing measured, nothing printed");
    }
    assert_eq!(
        (std::fs::read(&cube).unwrap(), std::fs::read(&list).unwrap()),
        before
    );
    // A report into a missing folder, of a run that would take minutes: refused at once.
    let started = Instant::now();
    let o = run(os![
        "bench",
        "bvh",
        &cube,
        "--width",
        "2048",
        "--json",
        &dir.path().join("nodir/report.json")
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("does not exist"), "{}", stderr(&o));
    assert!(o.stdout.is_empty(), "nothing measured, nothing printed");
    assert!(started.elapsed() < Duration::from_secs(20));
    assert_eq!(files(dir.path()), ["cube.obj", "list.txt"]);
}

/// `bench accuracy` without meshes reads its default ones from `HALFRAY_MESHES`: those are its
/// inputs too, and a report onto one of them is refused before anything is measured.
#[test]
fn a_default_mesh_of_bench_accuracy_is_an_input() {
    let dir = tempfile::tempdir().unwrap();
    use std::os::unix::fs::PermissionsExt;
    for name in halfray::bench::accuracy::DEFAULT_MESHES {
        let copy = dir.path().join(format!("{name}.obj"));
        std::fs::copy(shared_mesh(&format!("{name}.obj")), &copy).unwrap();
        // Writable, as a user's own mesh (the shared copies are read-only).
        std::fs::set_permissions(&copy, std::fs::Permissions::from_mode(0o644)).unwrap();
    }
    let bunny = dir.path().join("bunny.obj");
    let before = std::fs::read(&bunny).unwrap();
    let o = Command::new(BIN)
        .env("HALFRAY_MESHES", dir.path())
        .args(os!["bench", "accuracy", "--quick", "--json", &bunny])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("refusing to overwrite an input"),
        "{}",
        stderr(&o)
    );
    assert!(o.stdout.is_empty(), "nothing measured, nothing printed");
    assert_eq!(std::fs::read(&bunny).unwrap(), before);
}

#[test]
fn sigterm_during_a_render_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("out.png");
    std::fs::write(&png, b"previous").unwrap();
    // The output was checked (a temporary file made and removed) before `rendering …`.
    let mut child = start_long_render(&scene("glass.toml"), &png);
    assert!(child.try_wait().unwrap().is_none(), "still rendering");
    assert_eq!(
        files(dir.path()),
        ["out.png"],
        "no temporary file while working"
    );
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(t0.elapsed() < EXIT_WAIT, "did not exit after SIGTERM");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(128 + 15));
    assert_eq!(files(dir.path()), ["out.png"]);
    assert_eq!(std::fs::read(&png).unwrap(), b"previous");
}

/// Runs with stdout a pipe whose read end is closed before the child starts, so its very first
/// write fails (a read end closed after the spawn lets a fast command print everything into
/// the pipe's buffer first and exit 0).
fn run_into_closed_pipe(args: &[&std::ffi::OsStr]) -> Output {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    Command::new(BIN)
        .args(args)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

fn run_into_dev_full(args: &[&std::ffi::OsStr]) -> Output {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    Command::new(BIN)
        .args(args)
        .stdout(full)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

#[test]
fn closed_pipe_exits_quietly_and_full_device_is_a_clean_error() {
    let dir = tempfile::tempdir().unwrap();
    let cube = shared_mesh("cube.obj");
    let json = dir.path().join("check.json");
    let png = dir.path().join("r.png");
    let mirror = scene("mirror.toml");
    let cases: [&[&std::ffi::OsStr]; 6] = [
        os!["mesh", "check", &cube, "--json", &json],
        // Help and version text too (clap's own printing ignored the error: exit 0).
        os!["--help"],
        os!["--version"],
        os!["bench", "bvh", "--help"],
        os![
            "render",
            &mirror,
            "--explain",
            "-o",
            &png,
            "--width",
            "16",
            "--height",
            "12",
            "--quiet"
        ],
        // `bench bvh` prints with `say!` (`print!`): the panic guard covers it.
        os!["bench", "bvh", &cube, "--width", "16", "--rays", "100"],
    ];
    for args in cases {
        let o = run_into_closed_pipe(args);
        assert_eq!(o.status.code(), Some(141), "{args:?}: {}", stderr(&o));
        assert!(o.stderr.is_empty(), "{args:?}: quiet, got {}", stderr(&o));
        let o = run_into_dev_full(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.starts_with("error: <stdout>: No space left on device") && !e.contains("panicked"),
            "{args:?}: {e}"
        );
    }
    // A PNG or a JSON written to stdout (`-`): the write error keeps its kind and names
    // `<stdout>`, as a failed summary does.
    let images = tempfile::tempdir().unwrap();
    let a = images.path().join("a.png");
    let o = Command::new(BIN)
        .args(["gamma", "--chart"])
        .arg(&a)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let to_stdout: [&[&std::ffi::OsStr]; 4] = [
        os!["gamma", "--chart", "-"],
        os!["mesh", "check", &cube, "--json", "-"],
        os!["composite", &a, &a, "-o", "-"],
        os![
            "render", &mirror, "-o", "-", "--width", "16", "--height", "12", "--quiet"
        ],
    ];
    for args in to_stdout {
        let o = run_into_closed_pipe(args);
        assert_eq!(o.status.code(), Some(141), "{args:?}: {}", stderr(&o));
        assert!(o.stderr.is_empty(), "{args:?}: quiet, got {}", stderr(&o));
        let o = run_into_dev_full(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).starts_with("error: <stdout>: No space left on device"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
    // `--json` is written before the report is printed: it survives the closed stdout.
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["faces"], 12);
    assert_eq!(files(dir.path()), ["check.json"], "no temporary files");
}

/// Runs with stderr `sink` (stdout to a file in `dir`, `stdout.bin`).
fn run_with_stderr(args: &[&std::ffi::OsStr], dir: &Path, sink: Stdio) -> Output {
    let out = std::fs::File::create(dir.join("stdout.bin")).unwrap();
    Command::new(BIN)
        .args(args)
        .stdout(out)
        .stderr(sink)
        .output()
        .unwrap()
}

/// A failed write to stderr (a full device, a closed pipe) is never a panic (status 101): a
/// failed command keeps its own status (1 bad input, 2 usage, 3 cross-check mismatches, which
/// must not read as anything else), and a summary that goes to stderr (the output is stdout)
/// ends the program as a failed stdout does: 141 on a closed pipe, 1 otherwise; no temporary
/// file stays.
#[test]
fn a_failed_stderr_keeps_the_commands_status_and_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("nan.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n").unwrap();
    let part = dir.path().join("part.jsonl");
    std::fs::write(&part, result_line("a.obj", 0, 1, 4) + "\n").unwrap();
    let (missing, out_png) = (dir.path().join("missing.toml"), dir.path().join("x.png"));
    let out_obj = dir.path().join("x.obj");
    let cube = shared_mesh("cube.obj");
    let mirror = scene("mirror.toml");
    // (arguments, status with stderr full, status with stderr a closed pipe)
    let cases: [(&[&std::ffi::OsStr], i32, i32); 5] = [
        (os!["mesh", "subdivide", &bad, "-o", &out_obj], 1, 1),
        (os!["render", &missing, "-o", &out_png], 1, 1),
        (os!["render", &mirror, "--width", "0", "-o", &out_png], 2, 2),
        (
            os!["crosscheck", "merge", &part, "--max-mismatch", "0"],
            3,
            3,
        ),
        // The summary goes to stderr: the output is stdout.
        (os!["mesh", "subdivide", &cube, "-o", "-"], 1, 141),
    ];
    for (args, on_full, on_closed) in cases {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = run_with_stderr(args, dir.path(), full.into());
        assert_eq!(o.status.code(), Some(on_full), "{args:?} 2>/dev/full");
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let o = run_with_stderr(args, dir.path(), writer.into());
        assert_eq!(o.status.code(), Some(on_closed), "{args:?} 2>closed pipe");
        assert_eq!(
            files(dir.path()),
            ["nan.obj", "part.jsonl", "stdout.bin"],
            "{args:?}: no output, no temporary file"
        );
    }
}

/// A diagnostic on stderr that cannot be written (a full device, a closed pipe) is lost, not
/// fatal: a render's `rendering …` and `wrote …` lines, a mesh tool's `note:` on what the
/// output OBJ does not carry (a comment line). The command succeeds and writes its file.
#[test]
fn a_failed_stderr_does_not_stop_a_command_writing_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let commented = dir.path().join("commented.obj");
    let cube = std::fs::read_to_string(shared_mesh("cube.obj")).unwrap();
    std::fs::write(&commented, format!("# by hand\n{cube}")).unwrap();
    let (png, obj) = (dir.path().join("rr.png"), dir.path().join("sub.obj"));
    let mirror = scene("mirror.toml");
    let cases: [(&[&std::ffi::OsStr], &Path); 2] = [
        (os!["render", &mirror, "-o", &png], &png),
        (os!["mesh", "subdivide", &commented, "-o", &obj], &obj),
    ];
    for (args, out) in cases {
        for closed in [false, true] {
            let sink: Stdio = if closed {
                let (reader, writer) = std::io::pipe().unwrap();
                drop(reader);
                writer.into()
            } else {
                let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
                full.unwrap().into()
            };
            let o = run_with_stderr(args, dir.path(), sink);
            let how = if closed { "a closed pipe" } else { "/dev/full" };
            assert_eq!(o.status.code(), Some(0), "{args:?} 2> {how}");
            assert!(out.is_file(), "{args:?} 2> {how}: no output");
            std::fs::remove_file(out).unwrap();
        }
    }
    assert_eq!(files(dir.path()), ["commented.obj", "stdout.bin"]);
}

/// An output named `-` is all that stdout carries: the command's summary ("baked …", the
/// mesh tools' counts, a render's ray totals, the benchmark's tables) goes to stderr then, so
/// `halfray bake m.obj -o - > m.rs` is the same file as `-o m.rs`.
#[test]
fn an_output_on_stdout_is_all_that_stdout_carries() {
    let dir = tempfile::tempdir().unwrap();
    let cube = shared_mesh_str("cube.obj");
    let file = dir.path().join("out");
    let mirror = scene("mirror.toml");
    let commands: [&[&str]; 3] = [
        &["bake", &cube],
        &["mesh", "subdivide", &cube, "--levels", "1"],
        &[
            "render",
            mirror.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "6",
        ],
    ];
    for args in commands {
        let to_file = Command::new(BIN)
            .args(args)
            .arg("-o")
            .arg(&file)
            .output()
            .unwrap();
        assert!(to_file.status.success(), "{args:?}: {}", stderr(&to_file));
        assert!(!to_file.stdout.is_empty(), "{args:?}: a summary on stdout");
        let to_stdout = Command::new(BIN)
            .args(args)
            .args(["-o", "-"])
            .output()
            .unwrap();
        assert!(
            to_stdout.status.success(),
            "{args:?}: {}",
            stderr(&to_stdout)
        );
        assert!(
            to_stdout.stdout == std::fs::read(&file).unwrap(),
            "{args:?}: stdout is not the output's bytes alone"
        );
        // The summary's first line, up to its timings, on stderr instead.
        let summary = String::from_utf8_lossy(&to_file.stdout)
            .lines()
            .next()
            .and_then(|l| l.split(" in ").next())
            .unwrap()
            .replace(&file.display().to_string(), "-");
        assert!(
            stderr(&to_stdout).contains(&summary),
            "{args:?}: `{summary}` not on stderr: {}",
            stderr(&to_stdout)
        );
    }
    let o = Command::new(BIN)
        .args([
            "bench", "bvh", &cube, "--width", "4", "--rays", "4", "--sets", "primary",
        ])
        .args(["--json", "/dev/stdout"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("stdout is the JSON alone");
    assert_eq!(report["triangles"], 12);
    assert!(stderr(&o).contains("bench bvh: "), "{}", stderr(&o));
}

/// An output named `-` is written through the process's own stdout, whatever stdout is: a
/// socket (a supervisor's log socket, one end of a `socketpair`) cannot be opened again
/// through `/dev/fd/1`, so the bytes must not go that way. They arrive whole: the same as
/// the output written to a file.
#[test]
fn an_output_on_stdout_reaches_a_socket() {
    use std::io::Read;
    use std::os::fd::OwnedFd;
    use std::os::unix::net::UnixStream;
    let dir = tempfile::tempdir().unwrap();
    let cube = shared_mesh_str("cube.obj");
    let file = dir.path().join("cube.rs");
    let o = run(os!["bake", &cube, "-o", &file]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (mut ours, theirs) = UnixStream::pair().unwrap();
    let child = {
        let mut cmd = Command::new(BIN);
        cmd.args(["bake", &cube, "-o", "-"])
            .stdout(Stdio::from(OwnedFd::from(theirs)))
            .stderr(Stdio::piped());
        cmd.spawn().unwrap()
        // `cmd` and its copy of the socket's other end are dropped here: the child's end
        // is the last, so the read below ends when the child exits.
    };
    let mut got = Vec::new();
    ours.read_to_end(&mut got).unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(got, std::fs::read(&file).unwrap());
}

/// Every command that refuses a read-only output with "pass --force" takes `--force` (the
/// benchmarks, `gamma --chart` and `crosscheck` suggested a flag they did not have).
#[test]
fn every_command_that_suggests_force_takes_it() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let cube = shared_mesh_str("cube.obj");
    let out = dir.path().join("out");
    let commands: [&[&str]; 3] = [
        &["gamma", "--chart"],
        &[
            "bench", "bvh", &cube, "--width", "4", "--rays", "4", "--sets", "primary", "--json",
        ],
        &[
            "bench", "accel", &cube, "--width", "4", "--rays", "4", "--json",
        ],
    ];
    for args in commands {
        std::fs::write(&out, b"kept").unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o444)).unwrap();
        let o = Command::new(BIN).args(args).arg(&out).output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("pass --force"),
            "{args:?}: {}",
            stderr(&o)
        );
        assert_eq!(std::fs::read(&out).unwrap(), b"kept");
        let o = Command::new(BIN)
            .args(args)
            .arg(&out)
            .arg("--force")
            .output()
            .unwrap();
        assert!(o.status.success(), "{args:?} --force: {}", stderr(&o));
        assert_ne!(std::fs::read(&out).unwrap(), b"kept");
        let mode = std::fs::metadata(&out).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o444, "{args:?}: the mode is kept");
    }
}

/// A hard link to an input named as the output is that input (exit 2), with or without
/// `--force`: it was refused first for its two links (exit 1), which hid the reason.
#[test]
fn a_hard_link_to_an_input_is_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cube.obj");
    std::fs::copy(shared_mesh("cube.obj"), &input).unwrap();
    let link = dir.path().join("link.obj");
    std::fs::hard_link(&input, &link).unwrap();
    let before = std::fs::read(&input).unwrap();
    for force in [false, true] {
        let mut cmd = Command::new(BIN);
        cmd.args(["mesh", "subdivide"])
            .arg(&input)
            .arg("-o")
            .arg(&link);
        if force {
            cmd.arg("--force");
        }
        let o = cmd.output().unwrap();
        assert_eq!(o.status.code(), Some(2), "--force {force}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("refusing to overwrite an input"),
            "{}",
            stderr(&o)
        );
        assert_eq!(std::fs::read(&input).unwrap(), before);
    }
}

/// An output written as PNG whose name says another format is refused before any work, with
/// nothing written; a chart, which may be SVG, goes to stdout as SVG with `-o -`.
#[test]
fn an_output_is_named_for_the_format_written() {
    let dir = tempfile::tempdir().unwrap();
    let mirror = scene("mirror.toml");
    let render = |out: &Path| {
        run(os![
            "render", &mirror, "-o", out, "--width", "8", "--height", "6", "--quiet"
        ])
    };
    let svg = dir.path().join("x.svg");
    let jpg = dir.path().join("x.jpg");
    for (o, out) in [
        (render(&svg), &svg),
        (run(os!["gamma", "--chart", &jpg]), &jpg),
        (run(os!["composite", "a.png", "b.png", "-o", &svg]), &svg),
    ] {
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("is a PNG image"), "{}", stderr(&o));
        assert!(!out.exists(), "{}", out.display());
    }
    let png = dir.path().join("upper.PNG");
    let o = render(&png);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));

    let json = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/bench-accuracy-quick.json"
    );
    let o = run(os!["chart", "accuracy", json, "-o", &svg]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(os!["chart", "accuracy", json, "-o", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stdout.starts_with(b"<svg"));
    assert_eq!(
        o.stdout,
        std::fs::read(&svg).unwrap(),
        "stdout is the SVG alone"
    );
    // The input named as the output is refused as the input, not for its `.json` name.
    let input = dir.path().join("accuracy.json");
    std::fs::copy(json, &input).unwrap();
    let o = run(os!["chart", "accuracy", &input, "-o", &input]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("refusing to overwrite an input"),
        "{}",
        stderr(&o)
    );
}

/// Outputs another user owns, as that other user (`nobody`, through `setpriv`; the test runs
/// only as root, and records a skip elsewhere): a file the user may not write is refused
/// until `--force`; another user's file in a sticky folder (`/tmp`'s mode) is refused even
/// with `--force`, when the outputs are reserved, so a render that also writes a PNG writes
/// nothing (it used to replace the PNG, then fail to rename the statistics into place).
#[test]
fn another_users_files_are_refused_before_the_work() {
    use std::os::unix::fs::PermissionsExt;
    let as_nobody = |args: &[&std::ffi::OsStr]| {
        Command::new("setpriv")
            .args(["--reuid=65534", "--regid=65534", "--clear-groups", BIN])
            .args(args)
            .output()
    };
    let root = running_as_root();
    if !root || as_nobody(os!["--version"]).is_err() {
        halfray::skips::record_skip(
            "SKIPPED halfray another_users_files_are_refused_before_the_work: needs root and setpriv",
        );
        return;
    }
    let mode = |p: &Path, m: u32| std::fs::set_permissions(p, std::fs::Permissions::from_mode(m));
    let dir = tempfile::tempdir().unwrap();
    mode(dir.path(), 0o777).unwrap();
    let cube = shared_mesh("cube.obj");

    let theirs = dir.path().join("theirs.obj");
    std::fs::write(&theirs, b"kept").unwrap();
    mode(&theirs, 0o644).unwrap();
    let o = as_nobody(os!["mesh", "subdivide", &cube, "-o", &theirs]).unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("not writable by you; pass --force"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(&theirs).unwrap(), b"kept");
    let o = as_nobody(os!["mesh", "subdivide", &cube, "-o", &theirs, "--force"]).unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(std::fs::read(&theirs).unwrap(), b"kept");

    let sticky = dir.path().join("sticky");
    std::fs::create_dir(&sticky).unwrap();
    mode(&sticky, 0o1777).unwrap();
    let stats = sticky.join("stats.json");
    std::fs::write(&stats, b"kept").unwrap();
    mode(&stats, 0o666).unwrap();
    let png = dir.path().join("out.png");
    let o = as_nobody(os![
        "render",
        &scene("mirror.toml"),
        "-o",
        &png,
        "--stats-json",
        &stats,
        "--quiet",
        "--force"
    ])
    .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("sticky folder"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&stats).unwrap(), b"kept");
    assert_eq!(files(dir.path()), ["sticky", "theirs.obj"], "no PNG");
}

/// Whether this test process runs as root: the owner of a file it creates.
fn running_as_root() -> bool {
    use std::os::unix::fs::MetadataExt;
    let probe = tempfile::NamedTempFile::new().unwrap();
    probe.as_file().metadata().unwrap().uid() == 0
}

/// Outputs written together whose second target cannot be replaced, whoever runs the
/// program: an append-only statistics file (`chattr +a`), or one with a file bind-mounted on
/// it. The render is refused when its outputs are reserved, so no PNG is written beside a
/// statistics file that keeps its old bytes. Needs root (`chattr`, `mount`) and a file system
/// with the attribute; elsewhere the test records a skip.
#[test]
fn append_only_and_mounted_outputs_are_refused_before_the_work() {
    let command = |program: &str, args: &[&std::ffi::OsStr]| {
        Command::new(program)
            .args(args)
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let dir = tempfile::tempdir().unwrap();
    let (stats, source) = (dir.path().join("stats.json"), dir.path().join("source"));
    std::fs::write(&stats, b"kept").unwrap();
    std::fs::write(&source, b"over").unwrap();
    let png = dir.path().join("out.png");
    let render = || {
        run(os![
            "render",
            &scene("mirror.toml"),
            "-o",
            &png,
            "--stats-json",
            &stats,
            "--quiet",
            "--force"
        ])
    };
    let cases: [(&str, &[&std::ffi::OsStr], &str); 2] = [
        ("chattr", os!["+a", &stats], "append-only (chattr +a)"),
        (
            "mount",
            os!["--bind", &source, &stats],
            "mounted on it (mount --bind)",
        ),
    ];
    for (program, set, message) in cases {
        if !command(program, set) {
            halfray::skips::record_skip(&format!(
                "SKIPPED halfray append_only_and_mounted_outputs_are_refused_before_the_work: {program} refused here (not root?)"
            ));
            continue;
        }
        let o = render();
        let undone = if program == "chattr" {
            command("chattr", os!["-a", &stats])
        } else {
            command("umount", os![&stats])
        };
        assert!(undone, "{program} undone");
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(message), "{}", stderr(&o));
        assert_eq!(std::fs::read(&stats).unwrap(), b"kept");
        assert!(!png.exists(), "no PNG");
    }
}
