//! `halfray mesh ...` on the shared meshes (`../shared/meshes`) and on hand-made files: the
//! library functions for the numbers, the binary for exit codes and messages.

use glam::{Vec3, vec3};
use halfray::mesh_tools::{
    self, CollapseArgs, MeshBuffers, SmoothArgs, SubdivideArgs, Weights, build_mesh,
};
use halfray::obj::{ObjMesh, read_obj, write_obj};
use halfray_core::halfedge::{EdgeId, LoopWeights, VertexId};
use std::path::Path;
use std::process::Command;

mod common;
use common::{BIN, shared_mesh as mesh};

fn run_bin(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(BIN).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

// ----- check -----

#[test]
fn check_reports_the_readme_numbers() {
    let spot = mesh_tools::check(&mesh("spot.obj")).unwrap();
    assert!(spot.accepted);
    assert_eq!((spot.vertices, spot.edges, spot.faces), (2930, 8784, 5856));
    assert_eq!(spot.euler_characteristic, 2);
    assert_eq!(spot.genus, Some(0));
    assert_eq!(spot.closed, Some(true));
    assert_eq!(spot.boundary_loops, Some(0));
    assert_eq!(spot.components, Some(1));

    let torus = mesh_tools::check(&mesh("torus.obj")).unwrap();
    assert_eq!(torus.euler_characteristic, 0);
    assert_eq!(torus.genus, Some(1));
    assert_eq!(torus.closed, Some(true));

    // χ counts referenced vertices only: 35947 − 1113 − 104288 + 69451 = −3; with 5 holes the
    // genus is (2 − (−3) − 5)/2 = 0.
    let bunny = mesh_tools::check(&mesh("bunny.obj")).unwrap();
    assert_eq!(bunny.vertices, 35947);
    assert_eq!(bunny.unreferenced_vertices, 1113);
    assert_eq!(bunny.referenced_vertices, 35947 - 1113);
    assert_eq!(bunny.boundary_edges, Some(223));
    assert_eq!(bunny.boundary_loops, Some(5));
    assert_eq!(bunny.euler_characteristic, -3);
    assert_eq!(bunny.genus, Some(0));
    assert_eq!(bunny.closed, Some(false));

    let demo = mesh_tools::check(&mesh("demosthenes.obj")).unwrap();
    assert_eq!(demo.boundary_loops, Some(1));
    assert_eq!(demo.boundary_edges, Some(67));
    assert_eq!(demo.euler_characteristic, 1);
    assert_eq!(demo.genus, Some(0));
}

/// Every shared mesh but the one large one (`dragon.obj`) against `stats.json` (computed
/// independently in Python).
#[test]
fn check_agrees_with_stats_json() {
    let text = std::fs::read_to_string(mesh("stats.json")).unwrap();
    let stats: serde_json::Value = serde_json::from_str(&text).unwrap();
    let names = stats.as_object().unwrap().keys();
    let small: Vec<&String> = names.filter(|n| *n != "dragon.obj").collect();
    assert_eq!(small.len(), 9, "{small:?}");
    for name in small {
        let s = &stats[name];
        let n = |k: &str| s[k].as_u64().unwrap() as usize;
        let r = mesh_tools::check(&mesh(name)).unwrap();
        assert_eq!(r.vertices, n("vertices"), "{name}");
        assert_eq!(r.faces, n("triangles"), "{name}");
        assert_eq!(r.edges, n("edges"), "{name}");
        assert_eq!(
            r.unreferenced_vertices,
            n("unreferenced_vertices"),
            "{name}"
        );
        assert_eq!(
            r.euler_characteristic,
            s["euler_characteristic"].as_i64().unwrap(),
            "{name}"
        );
        let manifold = s["manifold"].as_bool().unwrap() && s["oriented"].as_bool().unwrap();
        assert_eq!(r.accepted, manifold, "{name}");
        if r.accepted {
            assert_eq!(r.boundary_edges, Some(n("boundary_edges")), "{name}");
            assert_eq!(r.boundary_loops, Some(n("boundary_loops")), "{name}");
            assert_eq!(r.components, Some(n("components")), "{name}");
            assert_eq!(r.closed, s["closed"].as_bool(), "{name}");
            if let Some(g) = s["genus"].as_f64() {
                assert_eq!(r.genus, Some(g as i64), "{name}");
            }
        } else {
            assert_eq!(r.manifold, Some(false), "{name}");
            assert!(r.reason.is_some(), "{name}");
        }
    }
}

#[test]
fn check_binary_prints_report_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("torus.json");
    let torus = mesh("torus.obj");
    let (code, out, err) = run_bin(&[
        "mesh",
        "check",
        torus.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("genus           1"), "{out}");
    assert!(out.contains("Euler χ         0"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["genus"], 1);
    assert_eq!(v["euler_characteristic"], 0);
    assert_eq!(v["accepted"], true);
}

#[test]
fn teapot_is_rejected_with_a_non_manifold_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("teapot.json");
    let teapot = mesh("teapot.obj");
    let (code, out, err) = run_bin(&[
        "mesh",
        "check",
        teapot.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(err.contains("teapot.obj:"), "{err}");
    assert!(err.contains("non-manifold vertex"), "{err}");
    // The counts that need no half-edge structure are still reported (README: χ = −34).
    assert!(out.contains("Euler χ         -34"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["accepted"], false);
    assert_eq!(v["manifold"], false);
    assert!(
        v["reason"]
            .as_str()
            .unwrap()
            .contains("non-manifold vertex")
    );

    // The named vertex (1-based OBJ number, and the file line of its `v` statement) really
    // is a pinch: its triangles do not form a single fan.
    let r = mesh_tools::check(&teapot).unwrap();
    let reason = r.reason.unwrap();
    let v: usize = reason
        .strip_prefix("non-manifold vertex ")
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    let at = r.reason_at.unwrap();
    assert_eq!(at.line, Some(v), "the shared meshes list vertices first");
    let obj = read_obj(&teapot).unwrap();
    assert!(!single_fan(&obj, (v - 1) as u32), "vertex {v} is a pinch");
}

/// Whether the triangles around `v` form one edge-connected fan.
fn single_fan(obj: &ObjMesh, v: u32) -> bool {
    let fan: Vec<[u32; 3]> = obj
        .triangles
        .iter()
        .copied()
        .filter(|t| t.contains(&v))
        .collect();
    let mut reached = vec![false; fan.len()];
    reached[0] = true;
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..fan.len() {
            for j in 0..fan.len() {
                if reached[i] && !reached[j] {
                    let shared = fan[i]
                        .iter()
                        .filter(|&&x| x != v && fan[j].contains(&x))
                        .count();
                    if shared > 0 {
                        reached[j] = true;
                        changed = true;
                    }
                }
            }
        }
    }
    reached.iter().all(|&r| r)
}

#[test]
fn beetle_is_rejected_with_a_non_manifold_edge() {
    let beetle = mesh("beetle.obj");
    let (code, _, err) = run_bin(&["mesh", "check", beetle.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("beetle.obj:"), "{err}");
    assert!(err.contains("non-manifold edge between vertices"), "{err}");
    // The named edge (1-based OBJ numbers) is used by more than two triangles.
    let r = mesh_tools::check(&beetle).unwrap();
    let reason = r.reason.unwrap();
    let nums: Vec<u32> = reason
        .strip_prefix("non-manifold edge between vertices ")
        .unwrap()
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .take(2)
        .map(|s| s.parse().unwrap())
        .collect();
    let (a, b) = (nums[0] - 1, nums[1] - 1);
    let obj = read_obj(&beetle).unwrap();
    let users = obj
        .triangles
        .iter()
        .filter(|t| t.contains(&a) && t.contains(&b))
        .count();
    assert!(users > 2, "edge {}–{} has {users} triangles", a + 1, b + 1);
}

/// A tetrahedron missing one face plus a quad `f 3 1 4 2` (fan triangles 4 = (3 1 4) and
/// 5 = (3 4 2)). The edge checked first, 2–3, is used by triangles 1, 3 and 5: the error names
/// triangle 5 and the quad's line 8, not the valid triangle 1 on line 5.
#[test]
fn a_non_manifold_edge_names_its_third_triangle_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tetq.obj");
    std::fs::write(
        &path,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4 2\n",
    )
    .unwrap();
    let r = mesh_tools::check(&path).unwrap();
    assert_eq!(
        r.reason.as_deref(),
        Some(
            "non-manifold edge between vertices 2 and 3: used by more than two triangles; \
             the third is triangle 5"
        )
    );
    assert_eq!(r.reason_at.unwrap().line, Some(8));
}

#[test]
fn missing_file_exits_1_and_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-mesh.obj");
    let out = dir.path().join("out.obj");
    for args in [
        vec!["mesh", "check", missing.to_str().unwrap()],
        vec![
            "mesh",
            "subdivide",
            missing.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        vec![
            "mesh",
            "smooth",
            missing.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        vec![
            "mesh",
            "collapse",
            missing.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--shorter-than",
            "1",
        ],
    ] {
        let (code, _, err) = run_bin(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains("no-such-mesh.obj"), "{args:?}: {err}");
    }
    assert!(!out.exists());
}

#[test]
fn malformed_obj_and_bad_arguments_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    let (code, _, err) = run_bin(&["mesh", "check", bad.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(err.contains("bad.obj:4:"), "{err}");

    // A triangle repeating a vertex: named by triangle number, file line and vertex.
    let rep = dir.path().join("rep.obj");
    std::fs::write(&rep, "v 0 0 0\nv 1 0 0\nv 0 1 0\n# c\nf 1 2 3\nf 1 2 2\n").unwrap();
    let (code, _, err) = run_bin(&["mesh", "check", rep.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(
        err.contains("rep.obj:6:") && err.contains("triangle 2") && err.contains("vertex 2"),
        "{err}"
    );

    let out = dir.path().join("o.obj");
    let spot = mesh("spot.obj");
    let (code, _, err) = run_bin(&[
        "mesh",
        "collapse",
        spot.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--shorter-than=-1",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--shorter-than"), "{err}");
    let (code, _, err) = run_bin(&[
        "mesh",
        "smooth",
        spot.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--step",
        "NaN",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(!out.exists());
}

// ----- subdivide -----

/// Subdivides `input` one level and checks the core's numbering through the OBJ round trip:
/// output vertex `i < V` is input vertex `i` moved by the vertex rule, output vertex `V + e`
/// the new vertex of edge `e`, bit for bit (OBJ coordinates round-trip f32 exactly).
fn check_one_level(input: &Path, weights: Weights) -> ObjMesh {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sub.obj");
    let report = mesh_tools::subdivide(&SubdivideArgs {
        input: input.to_path_buf(),
        output: out.clone(),
        force: false,
        levels: 1,
        weights,
    })
    .unwrap();
    let obj = read_obj(input).unwrap();
    let mut buffers = MeshBuffers::for_obj(&obj, input).unwrap();
    let m = build_mesh(&obj, None, input, &mut buffers).unwrap();
    let (v, e, f) = (m.len().vertices, m.len().edges, m.len().faces);
    let sub = read_obj(&out).unwrap();
    assert_eq!(sub.positions.len(), v + e);
    assert_eq!(sub.triangles.len(), 4 * f);
    assert_eq!(report.after.vertices, v + e);
    assert_eq!(report.after.edges, 2 * e + 3 * f);
    let w: LoopWeights = weights.into();
    for i in 0..v {
        let want = m.loop_vertex_position(VertexId::new(i as u32), w).unwrap();
        assert_eq!(sub.positions[i], want, "original vertex {}", i + 1);
        if m.is_isolated(VertexId::new(i as u32)) {
            assert_eq!(
                sub.positions[i], obj.positions[i],
                "unreferenced vertex stays"
            );
        }
    }
    for k in 0..e {
        let want = m.loop_edge_position(EdgeId::new(k as u32)).unwrap();
        assert_eq!(sub.positions[v + k], want, "edge vertex {k}");
    }
    // Original vertices are never joined to each other: every child triangle has at most
    // one original corner (corner triangles one, middle triangles none).
    for t in &sub.triangles {
        let old = t.iter().filter(|&&x| (x as usize) < v).count();
        assert!(old <= 1, "triangle {t:?} has {old} original corners");
    }
    sub
}

#[test]
fn subdivide_keeps_original_vertex_order_and_appends_one_vertex_per_edge() {
    check_one_level(&mesh("spot.obj"), Weights::Warren);
    check_one_level(&mesh("demosthenes.obj"), Weights::Loop);
}

#[test]
fn subdivide_bunny_keeps_unreferenced_vertices_in_place() {
    check_one_level(&mesh("bunny.obj"), Weights::Warren);
}

#[test]
fn subdivide_hand_made_file_with_polygon_and_stray_vertex() {
    // Vertex order not sorted by anything, an unreferenced vertex (3) in the middle, and a
    // quad that the reader fan-triangulates.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.obj");
    std::fs::write(
        &input,
        "v 1 1 0\nv 0 0 0\nv 9 9 9\nv 1 0 0\nv 0 1 0\nv 0.5 0.5 1\n\
         f 2 4 1 5\nf 2 6 4\nf 4 6 1\nf 1 6 5\nf 5 6 2\n",
    )
    .unwrap();
    let sub = check_one_level(&input, Weights::Loop);
    // A closed square pyramid plus one stray vertex: V = 6, E = 4 base + 1 diagonal (from the
    // quad's fan triangulation) + 4 slanted = 9, F = 6.
    assert_eq!(sub.positions.len(), 6 + 9);
    assert_eq!(sub.positions[2], vec3(9.0, 9.0, 9.0));
}

#[test]
fn subdivide_levels_multiply_and_weights_differ() {
    let dir = tempfile::tempdir().unwrap();
    let (warren, lp) = (dir.path().join("w.obj"), dir.path().join("l.obj"));
    for (out, weights) in [(&warren, Weights::Warren), (&lp, Weights::Loop)] {
        let r = mesh_tools::subdivide(&SubdivideArgs {
            input: mesh("octahedron.obj"),
            output: out.clone(),
            force: false,
            levels: 2,
            weights,
        })
        .unwrap();
        // Octahedron V 6 E 12 F 8 → V 18 E 48 F 32 → V 66 E 192 F 128.
        assert_eq!(r.levels.len(), 2);
        // The report names the command and both files, and times the read.
        assert_eq!(
            (r.command, &r.input, &r.output),
            ("subdivide", &mesh("octahedron.obj"), out)
        );
        let text = r.to_string();
        let first = format!(
            "mesh subdivide: {} -> {}",
            mesh("octahedron.obj").display(),
            out.display()
        );
        assert_eq!(text.lines().next(), Some(first.as_str()), "{text}");
        assert!(r.read_ms > 0.0 && r.read_ms.is_finite(), "{}", r.read_ms);
        assert_eq!(
            (r.after.vertices, r.after.edges, r.after.faces),
            (66, 192, 128)
        );
        let c = mesh_tools::check(out).unwrap();
        assert_eq!(c.closed, Some(true));
        assert_eq!(c.euler_characteristic, 2);
        assert_eq!(c.genus, Some(0));
    }
    // Valence 4 at the original vertices: Warren β = 3/32, Loop β ≈ 0.0977: they differ.
    let (w, l) = (read_obj(&warren).unwrap(), read_obj(&lp).unwrap());
    assert!((w.positions[0] - l.positions[0]).length() > 1e-3);
}

// ----- smooth -----

/// An `n × n`-quad grid in z = 0 on [0, n]², interior vertices lifted by a deterministic
/// pseudo-random noise in [−amp, amp].
fn noisy_grid(n: u32, amp: f32) -> ObjMesh {
    let mut positions = Vec::new();
    let mut state = 0x2545_f491u32;
    for j in 0..=n {
        for i in 0..=n {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let r = (state as f32 / u32::MAX as f32) * 2.0 - 1.0;
            let interior = i > 0 && j > 0 && i < n && j < n;
            let z = if interior { amp * r } else { 0.0 };
            positions.push(vec3(i as f32, j as f32, z));
        }
    }
    let triangles = halfray_core::solids::grid_triangles(n, n).collect();
    ObjMesh {
        positions,
        triangles,
    }
}

fn rms_z(p: &[Vec3]) -> f32 {
    (p.iter().map(|v| v.z * v.z).sum::<f32>() / p.len() as f32).sqrt()
}

#[test]
fn smooth_reduces_roughness_of_a_noisy_grid() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("noisy.obj");
    let grid = noisy_grid(20, 0.2);
    write_obj(&input, &grid.positions, &grid.triangles).unwrap();
    let is_boundary = |p: Vec3| p.x == 0.0 || p.y == 0.0 || p.x == 20.0 || p.y == 20.0;

    let fixed = dir.path().join("fixed.obj");
    let r = mesh_tools::smooth(&SmoothArgs {
        input: input.clone(),
        output: fixed.clone(),
        force: false,
        step: 0.5,
        iterations: 10,
        fix_boundary: true,
    })
    .unwrap();
    let (before, after) = r.roughness.unwrap();
    // Mean |L| also counts the fixed rim, whose in-plane Laplacian (towards the inside) never
    // changes, so it falls less than the height noise does.
    assert!(after < 0.75 * before, "mean |L| {before} -> {after}");
    assert_eq!(r.before, r.after);
    let out = read_obj(&fixed).unwrap();
    assert_eq!(out.triangles, grid.triangles, "connectivity unchanged");
    assert!(
        rms_z(&out.positions) < 0.25 * rms_z(&grid.positions),
        "rms z {} -> {}",
        rms_z(&grid.positions),
        rms_z(&out.positions)
    );
    for (a, b) in grid.positions.iter().zip(&out.positions) {
        if is_boundary(*a) {
            assert_eq!(a, b, "--fix-boundary keeps the rim");
        }
    }

    // Free boundary: rim vertices move (towards their neighbours, inward), still flatter.
    let free = dir.path().join("free.obj");
    mesh_tools::smooth(&SmoothArgs {
        input,
        output: free.clone(),
        force: false,
        step: 0.5,
        iterations: 10,
        fix_boundary: false,
    })
    .unwrap();
    let out = read_obj(&free).unwrap();
    assert!(
        grid.positions
            .iter()
            .zip(&out.positions)
            .any(|(a, b)| is_boundary(*a) && a != b)
    );
    assert!(rms_z(&out.positions) < 0.5 * rms_z(&grid.positions));
}

/// A step that throws vertices beyond the coordinate domain (or to infinity) is refused with
/// nothing written: the file would not read back (`--step=1e38` wrote it, exit 0).
#[test]
fn smoothing_beyond_the_coordinate_domain_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.obj");
    let cube = mesh("cube.obj");
    let (cube, out_arg) = (cube.to_str().unwrap(), out.to_str().unwrap());
    let smooth = |step| run_bin(&["mesh", "smooth", cube, "-o", out_arg, step]);
    for step in ["--step=1e38", "--step=3e38", "--step=-1e38"] {
        let (code, _, err) = smooth(step);
        assert_eq!(code, 2, "{step}: {err}");
        assert!(
            err.contains("outside the coordinate domain") && err.contains("nothing written"),
            "{err}"
        );
        assert!(!out.exists(), "{step}");
    }
    // A step that overflows only on a later iteration is the same usage error (it was exit 1,
    // blaming the input file).
    let (code, _, err) = run_bin(&[
        "mesh",
        "smooth",
        cube,
        "-o",
        out_arg,
        "--step=1e30",
        "--iterations=2",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("smoothing step 2 with --step 1000000000000000000000000000000")
            && err.contains("nothing written"),
        "{err}"
    );
    assert!(!out.exists());
    // A large step that stays inside the domain is written and reads back.
    let (code, _, err) = smooth("--step=1e3");
    assert_eq!(code, 0, "{err}");
    read_obj(&out).unwrap();
}

// ----- collapse -----

/// Every edge's length, in `f64` from the `f32` positions.
fn edge_lengths(obj: &ObjMesh) -> Vec<f64> {
    let mut keys: Vec<(u32, u32)> = obj
        .triangles
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.iter()
        .map(|&(a, b)| {
            let d = obj.positions[a as usize].as_dvec3() - obj.positions[b as usize].as_dvec3();
            (d.x * d.x + d.y * d.y + d.z * d.z).sqrt()
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn collapse_removes_short_edges_and_keeps_the_topology() {
    for (name, genus) in [("spot.obj", 0), ("torus.obj", 1), ("bunny.obj", 0)] {
        let input = mesh(name);
        let obj = read_obj(&input).unwrap();
        // An `f32` limit, as the option reads it.
        let limit = median(edge_lengths(&obj)) as f32;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("c.obj");
        let r = mesh_tools::collapse(&CollapseArgs {
            input: input.clone(),
            output: out.clone(),
            force: false,
            shorter_than: limit,
        })
        .unwrap();
        assert!(r.collapsed > 0, "{name}");
        assert!(r.after.faces < r.before.faces, "{name}");
        assert_eq!(r.before.vertices - r.after.vertices, r.collapsed, "{name}");

        // The output builds, validates (check does both) and keeps χ and genus.
        let before = mesh_tools::check(&input).unwrap();
        let after = mesh_tools::check(&out).unwrap();
        assert!(after.accepted, "{name}: {:?}", after.reason);
        assert_eq!(
            after.euler_characteristic, before.euler_characteristic,
            "{name}"
        );
        assert_eq!(after.genus, Some(genus), "{name}");
        assert_eq!(after.boundary_loops, before.boundary_loops, "{name}");
        assert_eq!(
            (after.vertices, after.edges, after.faces),
            (r.after.vertices, r.after.edges, r.after.faces)
        );
        // Unreferenced vertices are kept (compaction renumbers, but keeps them).
        assert_eq!(after.unreferenced_vertices, before.unreferenced_vertices);

        // Every edge still shorter than the limit is one the core refused, as reported.
        let short = edge_lengths(&read_obj(&out).unwrap())
            .into_iter()
            .filter(|&l| l < f64::from(limit))
            .count();
        assert_eq!(short, r.remaining_short(), "{name}: {:?}", r.refusals);
        assert!(short * 20 < after.edges, "{name}: {short} short edges left");
    }
}

/// A fan of six triangles around vertex 1; vertex 2 is `spoke`, the others far out.
fn fan(spoke: &str) -> String {
    format!(
        "v 0 0 0\nv {spoke}\nv -6.612 10.014 0.0\nv -11.978 -0.719 0.0\nv -5.367 -10.733 0.0\n\
         v 6.612 -10.014 0.0\nv 11.978 0.719 0.0\n\
         f 1 2 3\nf 1 3 4\nf 1 4 5\nf 1 5 6\nf 1 6 7\nf 1 7 2\n"
    )
}

/// "Strictly shorter" decided on the lengths, not on their `f32` roundings (found by a
/// review; lengths by exact rational arithmetic on the `f32` inputs):
/// - the spoke `(1, 2, 0)` is `√5 = 2.2360679…` long, shorter than `2.236068` (its `f32`
///   `2.2360680103`): it collapses (the `f32` length was `2.2360680103` too, not shorter);
/// - the spoke `(1.9568901, 1.1568258, 1.757585)` is longer than the `f32` limit
///   `2.8734595775604248046875` (its square `3.4·10⁻⁸` above the limit's): it stays (the `f32`
///   length `2.8734593` was shorter).
#[test]
fn collapse_compares_the_lengths_not_their_f32_roundings() {
    let dir = tempfile::tempdir().unwrap();
    for (spoke, limit, collapsed) in [
        ("1.0 2.0 0.0", "2.236068", 1),
        (
            "1.9568901 1.1568258 1.757585",
            "2.8734595775604248046875",
            0,
        ),
    ] {
        let input = dir.path().join("fan.obj");
        std::fs::write(&input, fan(spoke)).unwrap();
        let r = mesh_tools::collapse(&CollapseArgs {
            input,
            output: dir.path().join("out.obj"),
            force: true,
            shorter_than: limit.parse().unwrap(),
        })
        .unwrap();
        assert_eq!(r.collapsed, collapsed, "{spoke}: {:?}", r.refusals);
        assert_eq!(r.remaining_short(), 0, "{spoke}: {:?}", r.refusals);
    }
}

#[test]
fn collapse_on_a_tetrahedron_refuses_everything_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.obj");
    let r = mesh_tools::collapse(&CollapseArgs {
        input: mesh("tetrahedron.obj"),
        output: out.clone(),
        force: false,
        shorter_than: 100.0,
    })
    .unwrap();
    assert_eq!(r.collapsed, 0);
    assert_eq!(r.refusals.get("wing valence 3"), Some(&6));
    assert_eq!(r.after, r.before);
    let (code, stdout, _) = run_bin(&[
        "mesh",
        "collapse",
        mesh("tetrahedron.obj").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--shorter-than",
        "100",
    ]);
    assert_eq!(code, 0);
    assert!(stdout.contains("refused (wing valence 3): 6"), "{stdout}");
}

// ----- rejections located in the bytes read -----

/// Two triangles sharing only vertex 1: the half-edge core rejects the pinch at vertex 1.
const BOWTIE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n";

/// A rejected mesh's line comes from the bytes read once: a byte-order mark does not shift
/// it, and a named pipe (readable once) gets it as well, where a second open for the line
/// would wait for another writer forever.
#[test]
fn a_rejected_mesh_is_located_from_the_bytes_read_once() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, line) in [
        ("plain.obj", BOWTIE.to_string(), 1),
        ("bom.obj", format!("\u{feff}{BOWTIE}"), 1),
        ("comment.obj", format!("# a comment\n{BOWTIE}"), 2),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let (code, _, err) = run_bin(&["mesh", "check", p.to_str().unwrap()]);
        assert_eq!(code, 1, "{err}");
        assert!(
            err.contains(&format!("{name}:{line}: non-manifold vertex 1 is a pinch")),
            "{err}"
        );
    }
    #[cfg(unix)]
    for command in ["check", "subdivide"] {
        use std::time::{Duration, Instant};
        let fifo = dir.path().join("pipe.obj");
        let _ = std::fs::remove_file(&fifo);
        assert!(
            Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        let writer = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::write(&fifo, BOWTIE).unwrap())
        };
        let out = dir.path().join("out.obj");
        let mut args = vec!["mesh", command, fifo.to_str().unwrap()];
        if command == "subdivide" {
            args.extend(["-o", out.to_str().unwrap()]);
        }
        let mut child = Command::new(BIN)
            .args(&args)
            .stderr(std::process::Stdio::piped())
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(60);
        while child.try_wait().unwrap().is_none() {
            if Instant::now() > deadline {
                child.kill().unwrap();
                panic!("`mesh {command}` of a named pipe did not finish: it reopened the pipe");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let output = child.wait_with_output().unwrap();
        writer.join().unwrap();
        let err = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{err}");
        assert!(err.contains("pipe.obj:1: non-manifold vertex 1"), "{err}");
        assert!(!out.exists());
    }
}

/// Two triangles on the same three vertices (a "pillow", vertices 5–7, beside a tetrahedron):
/// subdivision refuses them naming two of those vertices by their OBJ numbers and the two
/// faces by their `f` lines (12 and 13).
#[test]
fn coincident_faces_are_named_by_their_obj_vertices() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("pillow.obj");
    std::fs::write(
        &input,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n\
         v 3 3 3\nv 4 3 3\nv 3 4 3\nf 5 6 7\nf 5 7 6\n",
    )
    .unwrap();
    let out = dir.path().join("o.obj");
    let (code, _, err) = run_bin(&[
        "mesh",
        "subdivide",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    let named: Vec<u32> = err
        .split("the edge of vertices ")
        .nth(1)
        .and_then(|r| r.split(" have").next())
        .map(|r| r.split(" and ").map(|n| n.parse().unwrap()).collect())
        .unwrap_or_else(|| panic!("no vertices named: {err}"));
    assert_eq!(named.len(), 2, "{err}");
    assert!(
        named[0] != named[1] && named.iter().all(|v| (5..=7).contains(v)),
        "{err}"
    );
    assert!(
        err.contains("pillow.obj:12: Loop subdivision refused: the two faces (the `f` lines 12 and 13) on the edge"),
        "{err}"
    );
    assert!(!out.exists());
}
