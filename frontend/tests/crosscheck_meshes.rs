//! `halfray crosscheck` on meshes that users have and the shared ones lack: faces lying in a
//! coordinate plane through the origin (a spawned ray from such a face starts exactly on its
//! plane, `t = 0` there) and faces wound inconsistently (one reversed against its
//! neighbours). The watertight intersector must pass on them: zero genuine mismatches and zero
//! leaks, exit code 0. Needs the `embree` feature (the CI's embree stage runs it).
#![cfg(feature = "embree")]

use serde_json::Value;
use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_halfray");

/// A tetrahedron with three faces in the planes `x = 0`, `y = 0`, `z = 0`.
const TETRAHEDRON: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";

/// A floor in the plane `y = 0` and a tetrahedron floating above it: ambient-occlusion rays
/// from the floor start exactly on its plane and reach the tetrahedron.
const FLOOR: &str = "v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nv 0 0.2 0\nv 1 0.2 0\nv 0 1.2 0\nv 0 0.2 1\n\
f 1 3 2\nf 1 4 3\nf 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n";

/// A box from `(0, 0, 0)` to `(2, 1, 3)` in quads (its bottom, in `z = 0`, wound against the
/// other five), negative indices on one, texture and normal indices, CRLF line ends.
const BOX: &str = "o box\r\nv 0 0 0\r\nv 2 0 0\r\nv 2 1 0\r\nv 0 1 0\r\nv 0 0 3\r\nv 2 0 3\r\nv 2 1 3\r\nv 0 1 3\r\nvt 0 0\r\nvn 0 0 1\r\n\
f 1/1/1 2/1/1 3/1/1 4/1/1\r\nf -4 -3 -2 -1\r\nf 1//1 2//1 6//1 5//1\r\nf 2 3 7 6\r\nf 3 4 8 7\r\nf 4 1 5 8\r\n";

fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn faces_in_coordinate_planes_and_mixed_windings_pass() {
    let dir = tempfile::tempdir().unwrap();
    let meshes = [
        write(
            dir.path(),
            "consistent.obj",
            &format!("{TETRAHEDRON}f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"),
        ),
        write(
            dir.path(),
            "mixed.obj",
            &format!("{TETRAHEDRON}f 1 2 3\nf 1 2 4\nf 1 4 3\nf 2 4 3\n"),
        ),
        write(dir.path(), "box.obj", BOX),
        write(dir.path(), "floor.obj", FLOOR),
    ];
    let json = dir.path().join("report.json");
    let o = Command::new(BIN)
        .arg("crosscheck")
        .args(&meshes)
        .args(["--rays", "3000", "--timing-rays", "300", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{text}");
    let report: Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let rows = report["sets"].as_array().unwrap();
    assert_eq!(rows.len(), 40, "{text}");
    for row in rows {
        let at = format!("{} {}", row["mesh"], row["name"]);
        assert_eq!(row["genuine_mismatches"], 0, "{at}: {text}");
        assert_eq!(row["leaks_halfray"], 0, "{at}: {text}");
        assert!(row["rays"].as_u64().unwrap() > 0, "{at}");
    }
    // The aimed sets did count crossings on each mesh (leaks are looked for).
    for mesh in ["consistent.obj", "mixed.obj", "box.obj"] {
        let counted: u64 = rows
            .iter()
            .filter(|r| r["mesh"] == mesh && (r["name"] == "edges" || r["name"] == "vertices"))
            .map(|r| r["leak_rays"].as_u64().unwrap())
            .sum();
        assert!(
            counted > 500,
            "{mesh}: {counted} counted edge and vertex rays"
        );
    }
}
