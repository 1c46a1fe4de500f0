//! OBJ dialects through the binary: CR-only files are read line by line, and a
//! mesh tool says on stderr what the output will not carry.

use std::process::Command;

mod common;
use common::{BIN, shared_mesh};

#[test]
fn cr_only_files_are_read_as_lines_and_drops_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let lf = std::fs::read(shared_mesh("cube.obj")).unwrap();
    assert!(lf.contains(&b'\n') && !lf.contains(&b'\r'));
    let cr: Vec<u8> = lf
        .iter()
        .map(|&b| if b == b'\n' { b'\r' } else { b })
        .collect();
    let path = dir.path().join("mac.obj");
    std::fs::write(&path, &cr).unwrap();
    let o = Command::new(BIN)
        .args(["mesh", "check"])
        .arg(&path)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("vertices        8 "), "{out}");
    assert!(out.contains("faces           12"), "{out}");

    let quads = dir.path().join("quads.obj");
    std::fs::write(
        &quads,
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nusemtl red\nf 1 2 3 4\n",
    )
    .unwrap();
    let out = dir.path().join("out.obj");
    let o = Command::new(BIN)
        .args(["mesh", "smooth"])
        .arg(&quads)
        .arg("-o")
        .arg(&out)
        .args(["--iterations", "0"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("not carried over")
            && e.contains("1 `mtllib`, 1 `usemtl`, 1 `vt`, 1 polygon(s) split into triangles"),
        "{e}"
    );
}

/// The note is about what was dropped, nothing else: a polygon split into triangles is noted
/// even when it is the only loss, and a file of triangles and vertices only gets no note.
#[test]
fn a_split_polygon_alone_is_noted_and_a_clean_file_gets_no_note() {
    let dir = tempfile::tempdir().unwrap();
    let smooth = |name: &str, text: &str| {
        let input = dir.path().join(name);
        std::fs::write(&input, text).unwrap();
        let o = Command::new(BIN)
            .args(["mesh", "smooth"])
            .arg(&input)
            .arg("-o")
            .arg(dir.path().join(format!("out-{name}")))
            .args(["--iterations", "0"])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{name}: {e}");
        e
    };
    let quad = smooth(
        "quad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
    );
    assert!(
        quad.contains("not carried over") && quad.contains(": 1 polygon(s) split into triangles"),
        "{quad}"
    );
    let clean = smooth(
        "tris.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    );
    assert!(!clean.contains("not carried"), "{clean}");
}
