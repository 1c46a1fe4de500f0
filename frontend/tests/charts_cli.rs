//! `halfray chart` as a user runs it: each chart from a run's JSON file, written where `-o`
//! says, as a well-formed SVG or a decodable PNG that carries the run's figures; a bad
//! extension refused before any reading. With `--features embree` the corpus chart is also
//! drawn from a real `bench bvh` run.

use halfray::bench::bvh::{BvhReport, SetFigures};
use halfray::crosscheck::report::{Report, RunConfig, SetReport};
use halfray::crosscheck::shard::Shard;
use std::path::Path;

mod common;

fn chart(kind: &str, input: &Path, output: &Path) -> std::process::Output {
    common::halfray(&[&"chart", &kind, &input, &"-o", &output])
}

/// The trimmed text of every `<text>` element of an SVG file, after parsing it as XML.
fn svg_texts(path: &Path) -> Vec<String> {
    common::svg::svg_texts(&std::fs::read(path).unwrap(), None)
}

fn assert_png(path: &Path) {
    let img = image::open(path).expect("a PNG").to_rgb8();
    assert!(img.width() >= 900 && img.height() >= 600);
    assert!(
        img.pixels().any(|p| p.0 != [255, 255, 255]),
        "something drawn"
    );
}

fn bench_report(mesh: &str, primary: [f64; 3]) -> BvhReport {
    let json = serde_json::json!({
        "mesh": mesh, "intersector": "watertight", "structure": "bvh8", "simd": "avx2+fma",
        "triangles": 100, "build_ms": 2.0, "build_ms_threads": 1.0, "build_threads": 2,
        "nodes": 3, "leaves": 4, "bytes_per_triangle": 50.0, "max_depth": 5, "sah_cost": 1.0,
        "binary_build_ms": 1.0, "binary_bytes_per_triangle": 40.0, "embree_build_ms": 3.0,
        "embree_robust_build_ms": 3.0, "brute_force_rays": 16, "mrays_brute_force": 0.1,
        "brute_force_mismatches": 0,
        "sets": [SetFigures {
            name: "primary".into(), query: "closest".into(), rays: 10, rays_outside_embree: 0,
            hit_rate: 0.5, embree_hit_rate: Some(0.5), embree_robust_hit_rate: Some(0.5),
            mrays: primary[0], nodes_per_ray: 1.0, triangles_per_ray: 1.0,
            embree_mrays: Some(primary[1]), embree_robust_mrays: Some(primary[2]),
            embree_packet8_mrays: None, embree_packet16_mrays: None,
        }]
    });
    serde_json::from_value(json).unwrap()
}

#[test]
fn each_chart_is_written_from_its_runs_json_and_carries_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();

    // Corpus: two meshes; primary over robust 1.5 and 0.6 → geometric mean 0.95, worst 0.60.
    let bench = d.join("bench.json");
    let reports = [
        bench_report("corpus/sphere.obj", [3.0, 2.0, 2.0]),
        bench_report("corpus/room.obj", [3.0, 6.0, 5.0]),
    ];
    std::fs::write(&bench, serde_json::to_vec(&reports).unwrap()).unwrap();
    for ext in ["svg", "png"] {
        let out = d.join(format!("corpus.{ext}"));
        let o = chart("corpus", &bench, &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        if ext == "svg" {
            let texts = svg_texts(&out);
            for want in [
                "sphere.obj",
                "room.obj",
                "primary: geo. mean 0.95 ÷ robust, 0.87 ÷ default; worst 0.60 (room.obj)",
            ] {
                assert!(texts.iter().any(|t| t == want), "{want}: {texts:?}");
            }
        } else {
            assert_png(&out);
        }
    }

    // Cross-check: one mesh, ties and a leak of Embree default.
    let crosscheck = d.join("crosscheck.json");
    let row = SetReport {
        mesh: "bunny.obj".into(),
        path: "m/bunny.obj".into(),
        name: "edges".into(),
        rays: 500,
        agree: 480,
        ties: 12,
        leaks_embree_default: 8,
        ..SetReport::default()
    };
    let config = RunConfig {
        intersector: "watertight".into(),
        seed: 1,
        rays: 500,
        ray_sets: vec!["edges".into()],
        shard: Shard::WHOLE,
    };
    let report = Report::new(config, 1, 1.0, &[]);
    let mut json = serde_json::to_value(&report).unwrap();
    json["sets"] = serde_json::to_value([row]).unwrap();
    std::fs::write(&crosscheck, serde_json::to_vec(&json).unwrap()).unwrap();
    let out = d.join("disagreements.svg");
    let o = chart("disagreements", &crosscheck, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let texts = svg_texts(&out);
    for want in [
        "bunny.obj",
        "tie: 12",
        "leak Embree default: 8",
        "genuine mismatch: 0",
    ] {
        assert!(texts.iter().any(|t| t == want), "{want}: {texts:?}");
    }

    // Accuracy: the variants' names and figures.
    let accuracy = d.join("accuracy.json");
    std::fs::write(
        &accuracy,
        r#"{"variants": [{"name": "watertight", "mrays_bvh_incoherent": 4.0,
            "leaks_per_million": 0.0, "false_hits_per_million": 0.0}]}"#,
    )
    .unwrap();
    let out = d.join("accuracy.png");
    let o = chart("accuracy", &accuracy, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_png(&out);
    let out = d.join("accuracy.svg");
    assert!(chart("accuracy", &accuracy, &out).status.success());
    assert!(svg_texts(&out).contains(&"watertight: 250.0 ns, 0.0 per million".to_string()));
}

#[test]
fn a_bad_extension_or_a_bad_file_is_refused_and_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("run.json");
    std::fs::write(&json, "{\"variants\": [1]}").unwrap();
    let jpg = dir.path().join("c.jpg");
    let o = chart("accuracy", &json, &jpg);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains(".svg or .png"));
    let svg = dir.path().join("c.svg");
    let o = chart("accuracy", &json, &svg);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("run.json:1:") && e.contains("bench accuracy --json"),
        "{e}"
    );
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["run.json"], "nothing written");
    // A device is refused before a byte is read (`/dev/zero` was read until memory ran out),
    // and JSON of another run's shape is said so plainly (no serde type names).
    let o = chart("corpus", std::path::Path::new("/dev/zero"), &svg);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("/dev/zero: is a character device"), "{e}");
    std::fs::write(&json, "{\"rays\": 3}").unwrap();
    let o = chart("corpus", &json, &svg);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("run.json:1:11: not the JSON of `bench bvh --json`: missing field `mesh`"),
        "{e}"
    );
    assert!(!e.contains("untagged"), "{e}");
    assert!(!svg.exists());
    // A value of the wrong type deep in a corpus run is named by its line and column (the
    // chart said only "not the JSON of" for an array of reports), in JSON's words.
    std::fs::write(&json, "[{\"mesh\": \"a.obj\"},\n 7]").unwrap();
    let o = chart("corpus", &json, &svg);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("run.json:1:"), "{e}");
    std::fs::write(&json, "[\"x\"]").unwrap();
    let e = String::from_utf8_lossy(&chart("corpus", &json, &svg).stderr).into_owned();
    assert!(
        e.contains("run.json:1:") && e.contains("expected a JSON object") && !e.contains("struct"),
        "{e}"
    );
    // An empty run is said to have no mesh, not to lack Embree.
    std::fs::write(&json, "[]").unwrap();
    let e = String::from_utf8_lossy(&chart("corpus", &json, &svg).stderr).into_owned();
    assert!(e.contains("run.json: the run has no mesh"), "{e}");
    assert!(!svg.exists());
}

/// A real corpus run (two small meshes, few rays) charted: every mesh on the axis.
#[cfg(feature = "embree")]
#[test]
fn a_real_bench_bvh_run_is_charted() {
    let meshes = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/meshes");
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let (torus, tetrahedron) = (
        format!("{meshes}/torus.obj"),
        format!("{meshes}/tetrahedron.obj"),
    );
    let o = common::halfray(&[
        &"bench",
        &"bvh",
        &torus,
        &tetrahedron,
        &"--width",
        &"16",
        &"--rays",
        &"200",
        &"--json",
        &json,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("corpus.svg");
    assert!(chart("corpus", &json, &out).status.success());
    let texts = svg_texts(&out);
    for want in ["torus.obj", "tetrahedron.obj"] {
        assert!(texts.iter().any(|t| t == want), "{want}: {texts:?}");
    }
    for set in halfray::raysets::named::RaySet::ALL.map(|s| s.name()) {
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with(&format!("{set}: geo. mean "))),
            "{set}: {texts:?}"
        );
    }
}
