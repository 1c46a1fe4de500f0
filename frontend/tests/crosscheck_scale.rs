//! `halfray crosscheck` at scale, as a user runs it: sharded runs merged equal the unsharded
//! run ray for ray; a mesh list with a bad mesh is reported and the run goes on; `--resume`
//! skips exactly the meshes already done. Needs the `embree` feature (the CI's embree stage
//! runs it); `crosscheck merge` alone needs no Embree and is tested in `crosscheck::merge`.
#![cfg(feature = "embree")]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_halfray");
const SCENE_MESHES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/meshes");

fn mesh(name: &str) -> String {
    format!("{SCENE_MESHES}/{name}")
}

fn run(args: &[&str], extra: &[&Path]) -> Output {
    Command::new(BIN)
        .arg("crosscheck")
        .args(args)
        .args(extra)
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn read(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// Every field of every row except the timing ones.
fn counts(report: &Value) -> Vec<Value> {
    report["sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            let mut row = row.clone();
            let obj = row.as_object_mut().unwrap();
            obj.retain(|k, _| !k.starts_with("secs_") && !k.starts_with("mrays_"));
            row
        })
        .collect()
}

/// Halfray leaks summed over a report's rows.
fn leaks(report: &Value) -> u64 {
    report["sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| row["leaks_halfray"].as_u64().unwrap())
        .sum()
}

/// The Möller–Trumbore test leaks on edge rays, so the runs have disagreements to keep.
const RUN: [&str; 6] = [
    "--rays",
    "1500",
    "--intersector",
    "moller-trumbore",
    "--sets",
    "primary,edges,vertices",
];

#[test]
fn merged_shards_equal_the_unsharded_run_ray_for_ray() {
    let dir = tempfile::tempdir().unwrap();
    let meshes = [mesh("octahedron.obj"), mesh("torus.obj")];
    let whole = dir.path().join("whole.json");
    let o = run(
        &[
            &[meshes[0].as_str(), meshes[1].as_str()][..],
            &RUN[..],
            &["--json"],
        ]
        .concat(),
        &[&whole],
    );
    // A halfray leak fails the run (exit 3) whatever the intersector; the report is written.
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let whole = read(&whole);
    assert!(leaks(&whole) > 0, "the Möller–Trumbore run should leak");
    let details: usize = whole["sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["disagreements"].as_array().unwrap().len())
        .sum();
    assert!(details > 0, "the Möller–Trumbore run should record leaks");
    for n in [1usize, 2, 3, 7] {
        let mut parts: Vec<PathBuf> = Vec::new();
        for k in 0..n {
            let part = dir.path().join(format!("part-{k}-of-{n}.json"));
            let shard = format!("{k}/{n}");
            let o = run(
                &[
                    &[meshes[0].as_str(), meshes[1].as_str()][..],
                    &RUN[..],
                    &["--threads", "2", "--shard", &shard, "--json"],
                ]
                .concat(),
                &[&part],
            );
            let leaked = leaks(&read(&part)) > 0;
            let want = if leaked { 3 } else { 0 };
            assert_eq!(o.status.code(), Some(want), "shard {shard}: {}", text(&o));
            // Each shard holds about 1/n of each set.
            let part_rays = read(&part)["sets"][0]["rays"].as_u64().unwrap();
            let all_rays = whole["sets"][0]["rays"].as_u64().unwrap();
            assert!(part_rays.abs_diff(all_rays / n as u64) <= 1, "{shard}");
            parts.push(part);
        }
        let merged = dir.path().join(format!("merged-{n}.json"));
        let part_refs: Vec<&Path> = parts.iter().map(PathBuf::as_path).rev().collect();
        let o = Command::new(BIN)
            .args(["crosscheck", "merge"])
            .args(&part_refs)
            .arg("--json")
            .arg(&merged)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(3), "merge of {n}: {}", text(&o));
        let merged = read(&merged);
        assert_eq!(merged["merged_shards"], n);
        assert_eq!(counts(&merged), counts(&whole), "N = {n}");
    }
    // A shard missing from the merge is an error, not a partial sum.
    let o = Command::new(BIN)
        .args(["crosscheck", "merge"])
        .arg(dir.path().join("part-0-of-3.json"))
        .arg(dir.path().join("part-2-of-3.json"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("shard 1/3 is missing"), "{}", text(&o));
}

#[test]
fn a_bad_mesh_in_a_list_is_reported_and_the_run_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let nan = dir.path().join("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n").unwrap();
    let missing = dir.path().join("missing.obj");
    let list = dir.path().join("list.txt");
    std::fs::write(
        &list,
        format!(
            "# a corpus\n{}\n{}\n{}\n\n{}\n",
            mesh("tetrahedron.obj"),
            nan.display(),
            missing.display(),
            mesh("cube.obj")
        ),
    )
    .unwrap();
    let (log, json) = (dir.path().join("out.jsonl"), dir.path().join("out.json"));
    let o = run(
        &["--rays", "300", "--mesh-list"],
        &[
            &list,
            Path::new("--jsonl"),
            &log,
            Path::new("--json"),
            &json,
        ],
    );
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    assert!(all.contains("2 of 4 meshes could not be checked"), "{all}");
    assert!(all.contains(&format!("{}:3", nan.display())), "{all}");
    assert!(all.contains(&missing.display().to_string()), "{all}");
    // The list's lines of the two failed meshes (its first line is a comment).
    for line in [3, 4] {
        let at = format!("(named at {}:{line})", list.display());
        assert!(all.contains(&at), "`{at}` in: {all}");
    }
    let lines: Vec<Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 4, "one line per mesh, failed ones included");
    assert!(lines[1]["error"].as_str().unwrap().contains("not finite"));
    assert!(
        lines[3]["error"].is_null(),
        "the run went on past the bad meshes"
    );
    let report = read(&json);
    assert_eq!(report["meshes"], 4);
    assert_eq!(report["failed"].as_array().unwrap().len(), 2);
    assert_eq!(
        report["sets"].as_array().unwrap().len(),
        2 * 10,
        "every set"
    );
}

#[test]
fn resume_skips_exactly_the_meshes_already_done() {
    let dir = tempfile::tempdir().unwrap();
    let later = dir.path().join("later.obj");
    let list = dir.path().join("list.txt");
    std::fs::write(
        &list,
        format!("{}\n{}\n", mesh("tetrahedron.obj"), later.display()),
    )
    .unwrap();
    let log = dir.path().join("out.jsonl");
    let args = ["--rays", "300", "--sets", "primary,edges"];
    let o = run(
        &args,
        &[Path::new("--mesh-list"), &list, Path::new("--jsonl"), &log],
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "later.obj is missing: {}",
        text(&o)
    );
    // Without --resume an existing log is not overwritten.
    let o = run(
        &args,
        &[Path::new("--mesh-list"), &list, Path::new("--jsonl"), &log],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("is not empty: pass --resume"),
        "{}",
        text(&o)
    );
    assert_eq!(std::fs::read_to_string(&log).unwrap().lines().count(), 2);
    // Nor is a file that holds no results, and it is not said to hold any.
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "my notes\n").unwrap();
    let o = run(
        &args,
        &[
            Path::new("--mesh-list"),
            &list,
            Path::new("--jsonl"),
            &notes,
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!text(&o).contains("holds results"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "my notes\n");
    // The missing mesh appears; a third is added to the list; the run is resumed.
    std::fs::copy(mesh("octahedron.obj"), &later).unwrap();
    std::fs::write(
        &list,
        format!(
            "{}\n{}\n{}\n",
            mesh("tetrahedron.obj"),
            later.display(),
            mesh("cube.obj")
        ),
    )
    .unwrap();
    let json = dir.path().join("out.json");
    let o = run(
        &args,
        &[
            Path::new("--mesh-list"),
            &list,
            Path::new("--jsonl"),
            &log,
            Path::new("--resume"),
            Path::new("--json"),
            &json,
        ],
    );
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    assert_eq!(all.matches("skipped (--resume)").count(), 1, "{all}");
    assert!(
        all.contains("tetrahedron.obj: already in the results log"),
        "{all}"
    );
    assert!(all.contains("crosscheck later.obj primary"), "{all}");
    assert!(all.contains("crosscheck cube.obj edges"), "{all}");
    assert_eq!(std::fs::read_to_string(&log).unwrap().lines().count(), 4);
    let report = read(&json);
    assert_eq!(report["meshes"], 3);
    assert!(report["failed"].as_array().unwrap().is_empty());
    assert_eq!(report["sets"].as_array().unwrap().len(), 3 * 2);
    // A resumed run's report equals a fresh run's, counts for counts.
    let fresh = dir.path().join("fresh.json");
    let o = run(
        &args,
        &[Path::new("--mesh-list"), &list, Path::new("--json"), &fresh],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(counts(&read(&fresh)), counts(&report));
    // Resumed once more with every mesh in the log: this process checks no ray, so its
    // throughput is 0 (the log's rays over this run's wall time made it millions of rays/s).
    let again = dir.path().join("again.json");
    let o = run(
        &args,
        &[
            Path::new("--mesh-list"),
            &list,
            Path::new("--jsonl"),
            &log,
            Path::new("--resume"),
            Path::new("--json"),
            &again,
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let again = read(&again);
    assert_eq!(counts(&again), counts(&report));
    assert_eq!(again["rays_per_second"], 0.0, "{again}");
}

/// Sizes a run cannot hold are usage errors before any work (they aborted on a failed
/// allocation, or panicked: `--rays 2^64−1` a capacity overflow, `--depth-size 0` a remainder
/// by zero); the sizes of the documented corpus runs pass.
#[test]
fn sizes_beyond_memory_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let depth = dir.path().join("depth.png");
    let tetrahedron = mesh("tetrahedron.obj");
    for (args, want) in [
        (&["--rays", "4294967296"][..], "GiB limit"),
        (
            &["--rays", "18446744073709551615"][..],
            "does not fit in 64 bits",
        ),
        (
            &["--depth-size", "0"][..],
            "--depth-size must be at least 1",
        ),
        // A check of no ray passed (exit 0) before.
        (&["--rays", "0"][..], "--rays must be at least 1"),
        (
            &["--timing-rays", "0"][..],
            "--timing-rays must be at least 1",
        ),
        (&["--depth-size", "65536"][..], "GiB limit"),
        (
            &["--depth-size", "4294967296"][..],
            "does not fit in 64 bits",
        ),
        // workers::MAX_WORKER_THREADS, as for RAYON_NUM_THREADS.
        (&["--threads", "1025"][..], "1..=1024"),
        // A set named twice would be checked and counted twice.
        (
            &["--sets", "edges,primary,edges"][..],
            "--sets names `edges` twice",
        ),
    ] {
        let o = run(
            args,
            &[Path::new(&tetrahedron), Path::new("--depth-image"), &depth],
        );
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains(want), "{args:?}: {}", text(&o));
        assert!(o.stdout.is_empty() && !depth.exists(), "{args:?}");
    }
    // 1 666 667 rays a set, the 10⁸-ray run of docs/accuracy.md, still passes the check.
    let o = run(
        &[
            "--rays",
            "1666667",
            "--timing-rays",
            "2",
            "--sets",
            "primary",
            "--depth-size",
            "1",
        ],
        &[Path::new(&tetrahedron), Path::new("--depth-image"), &depth],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(depth.exists());
}

/// `--json` and `--depth-image` are written together at the end, both or neither: a report
/// that cannot be written leaves an existing depth image as it was (it was replaced first),
/// and a depth image that cannot be written is the run's error, not a failed mesh.
#[test]
fn the_report_and_the_depth_image_are_written_both_or_neither() {
    let dir = tempfile::tempdir().unwrap();
    let depth = dir.path().join("depth.png");
    let json = dir.path().join("out.json");
    std::fs::write(&depth, b"an earlier image").unwrap();
    let tetrahedron = mesh("tetrahedron.obj");
    let args = ["--rays", "50", "--sets", "primary", "--depth-size", "8"];
    let check = |depth: &Path, json: &Path| {
        let flags = [Path::new("--depth-image"), depth, Path::new("--json"), json];
        run(&args, &[&[Path::new(&tetrahedron)][..], &flags].concat())
    };
    let o = check(&depth, Path::new("/dev/full"));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("/dev/full"), "{}", text(&o));
    assert_eq!(std::fs::read(&depth).unwrap(), b"an earlier image");
    let o = check(Path::new("/dev/full"), &json);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(!text(&o).contains("could not be checked"), "{}", text(&o));
    assert!(text(&o).contains("/dev/full: "), "{}", text(&o));
    assert!(!json.exists());
    let o = check(&depth, &json);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read(&depth).unwrap().starts_with(b"\x89PNG"));
    assert_eq!(read(&json)["meshes"], 1);
}

/// One mesh file named twice in a run (another spelling) is a usage error before any work:
/// its counts would be in the report twice.
#[test]
fn a_mesh_named_twice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    std::fs::copy(mesh("cube.obj"), &cube).unwrap();
    let again = dir.path().join(".").join("cube.obj");
    let o = run(&["--rays", "10"], &[&cube, &again]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("(the same file): each mesh is checked once"),
        "{}",
        text(&o)
    );
    assert!(o.stdout.is_empty());
}

/// Each set's row carries its timed passes: some of its rays timed (at most all of them),
/// every side's seconds positive, and the throughput those give (`timed_rays / secs`, in
/// Mrays/s), as the README's figures and the run's "throughput ratio" line are read from it.
#[test]
fn every_set_reports_its_timed_rays_and_seconds() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("r.json");
    let o = run(
        &[&mesh("octahedron.obj"), "--rays", "600", "--json"],
        &[&json],
    );
    assert!(o.status.success(), "{}", text(&o));
    let report = read(&json);
    let rows = report["sets"].as_array().unwrap();
    assert!(!rows.is_empty());
    for row in rows {
        let name = row["name"].as_str().unwrap();
        let (rays, timed) = (
            row["rays"].as_u64().unwrap(),
            row["timed_rays"].as_u64().unwrap(),
        );
        assert!(timed > 0 && timed <= rays, "{name}: {timed} of {rays}");
        for side in ["halfray", "embree", "embree_default"] {
            let secs = row[format!("secs_{side}")].as_f64().unwrap();
            let mrays = row[format!("mrays_{side}")].as_f64().unwrap();
            assert!(secs > 0.0, "{name} {side}: {secs}");
            let expected = timed as f64 / secs / 1e6;
            assert!(
                (mrays - expected).abs() <= 1e-9 * expected,
                "{name} {side}: {mrays} vs {expected}"
            );
        }
    }
}

/// A mesh whose camera rays all lie outside Embree's range: the triangle `(0,0,0), (10³⁰,0,0),
/// (0,10³⁰,0)` (a camera framing it stands beyond `FLT_LARGE`).
fn huge_mesh(dir: &Path) -> PathBuf {
    let huge = dir.join("huge.obj");
    std::fs::write(&huge, "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n").unwrap();
    huge
}

/// A set whose every ray Embree cannot take is not silently a pass of 0 rays: its row counts
/// the rays dropped, stderr warns that no ray was left, and the summary names them; a mesh
/// with no compared ray at all was not checked, and the run exits 1 naming it (it exited 0),
/// its report written.
#[test]
fn rays_outside_embree_are_counted_and_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let huge = huge_mesh(dir.path());
    let json = dir.path().join("r.json");
    let o = run(
        &["--rays", "40", "--sets", "primary"],
        &[&huge, Path::new("--json"), &json],
    );
    let all = text(&o);
    assert_eq!(o.status.code(), Some(1), "{all}");
    assert!(all.contains("1 of 1 meshes could not be checked"), "{all}");
    assert!(
        all.contains("none of its 40 generated rays is within Embree's range"),
        "{all}"
    );
    let row = &read(&json)["sets"][0];
    assert_eq!(
        (row["rays"].as_u64(), row["rays_outside_embree"].as_u64()),
        (Some(0), Some(40)),
        "{all}"
    );
    let warning = "warning: crosscheck huge.obj primary: no ray left to check \
                   (40 generated, 40 of them outside Embree's range)";
    assert!(all.contains(warning), "{all}");
    assert!(
        all.contains("40 generated rays outside Embree's range"),
        "{all}"
    );
}

/// The depth image of that mesh traces none of its pixels on either side (it reported them
/// as "only halfray hits"): they are counted apart and magenta in all three panels.
#[test]
fn depth_pixels_outside_embree_are_not_traced() {
    let dir = tempfile::tempdir().unwrap();
    let huge = huge_mesh(dir.path());
    let depth = dir.path().join("d.png");
    let o = run(
        &["--rays", "1", "--sets", "primary", "--depth-size", "3"],
        &[&huge, Path::new("--depth-image"), &depth],
    );
    let all = text(&o);
    // No ray compared: the mesh was not checked (exit 1), the image written all the same.
    assert_eq!(o.status.code(), Some(1), "{all}");
    let counts = "only halfray hits: 0, only Embree hits: 0, depth differs: 0, \
                  not traced (outside Embree's range): 9";
    assert!(all.contains(counts), "{all}");
    let img = image::open(&depth).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (9, 3));
    assert!(img.pixels().all(|p| p.0 == [255, 0, 255]), "{all}");
}
