//! `halfray bake` as a firmware author uses it: the written source holds the mesh exactly (bit
//! patterns read back by a parser of its own here, compared with the OBJ), its BVH loads
//! through `Bvh::from_parts` and answers like brute force; bad input and bad outputs are
//! refused with nothing written. (`scripts/test-mcu.sh` compiles such a file into the QEMU
//! images and checks their answers against the host's.)

use halfray::obj::read_obj;
use halfray_core::Vec3;
use halfray_core::bvh::{Bvh, BvhNode, load_scratch_len};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, Triangles};
use halfray_core::ray::Ray;
use halfray_core::triangle::{TriangleIntersector, Watertight};

mod common;
use common::{halfray, stderr};

const TORUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/meshes/torus.obj");

/// The text of `static NAME: … = [ … ];`.
fn array<'a>(src: &'a str, name: &str) -> &'a str {
    let start = src.find(&format!("pub static {name}:")).expect(name);
    let body = &src[start..];
    let open = body.find("= [\n").unwrap() + 4;
    let close = body.find("\n];").unwrap();
    &body[open..close]
}

/// Every `f32::from_bits(0x…)` in `text`, in order.
fn floats(text: &str) -> Vec<f32> {
    text.split("f32::from_bits(0x")
        .skip(1)
        .map(|s| f32::from_bits(u32::from_str_radix(&s[..8], 16).unwrap()))
        .collect()
}

/// Every unsigned integer in `text` outside `from_bits(…)` calls.
fn integers(text: &str) -> Vec<u32> {
    let cleaned: String = text
        .split("f32::from_bits(0x")
        .enumerate()
        .map(|(i, s)| if i == 0 { s } else { &s[9..] })
        .collect();
    cleaned
        .split(|c: char| !c.is_ascii_digit())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse().unwrap())
        .collect()
}

/// A baked mesh and BVH: positions, triangles, nodes, indices.
type Baked = (Vec<Vec3>, Vec<[u32; 3]>, Vec<BvhNode>, Vec<u32>);

/// The arrays of a baked Rust source, read back by this file's own parser; checks that its
/// `LOAD_SCRATCH_WORDS` is the loader's bitset length.
fn read_source(src: &str) -> Baked {
    let p = floats(array(src, "POSITIONS"));
    let positions: Vec<Vec3> = p.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    let t = integers(array(src, "TRIANGLES"));
    // Each line is `[a, b, c],`: the `3` of the type is not inside the array body.
    let triangles: Vec<[u32; 3]> = t.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();

    let nodes_text = array(src, "NODES");
    let boxes = floats(nodes_text);
    let fields = integers(nodes_text);
    let nodes: Vec<BvhNode> = boxes
        .chunks(6)
        .zip(fields.chunks(2))
        .map(|(b, f)| BvhNode::from_raw([[b[0], b[1], b[2]], [b[3], b[4], b[5]]], f[0], f[1]))
        .collect();
    assert_eq!(
        nodes.len(),
        nodes_text.matches("BvhNode::from_raw(").count()
    );
    let indices = integers(array(src, "INDICES"));
    let words: usize = src
        .split("pub const LOAD_SCRATCH_WORDS: usize = ")
        .nth(1)
        .and_then(|s| s.split(';').next())
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(words, load_scratch_len(triangles.len()));
    (positions, triangles, nodes, indices)
}

#[test]
fn the_baked_source_holds_the_mesh_and_a_bvh_that_loads_and_answers_like_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("torus_bvh.rs");
    let o = halfray(&[&"bake", &TORUS, &"-o", &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let src = std::fs::read_to_string(&out).unwrap();
    let obj = read_obj(std::path::Path::new(TORUS)).unwrap();

    let (positions, triangles, nodes, indices) = read_source(&src);
    assert_eq!(positions.len(), obj.positions.len());
    for (a, b) in positions.iter().zip(&obj.positions) {
        assert_eq!(
            a.to_array().map(f32::to_bits),
            b.to_array().map(f32::to_bits)
        );
    }
    assert_eq!(triangles, obj.triangles);
    let words = load_scratch_len(triangles.len());

    let mesh = TriangleMesh::new(&positions, &triangles);
    let bvh = Bvh::from_parts(&nodes[..], &indices[..], &mesh, &mut vec![0u32; words]).unwrap();
    let mut s = 7u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    for _ in 0..500 {
        let o = Vec3::new(next(), next(), next()) * 4.0;
        let d = Vec3::new(next(), next(), next()) * 0.5 - o * 0.2;
        let ray = Ray::new(o, d);
        let mut best: Option<(u32, u32)> = None;
        for (i, tri) in triangles.iter().enumerate() {
            let v = tri.map(|k| positions[k as usize]);
            if let Some(h) = Watertight.intersect(&ray, &v)
                && best.is_none_or(|(_, t)| h.t < f32::from_bits(t))
            {
                best = Some((i as u32, h.t.to_bits()));
            }
        }
        let got = bvh
            .closest_hit(
                &ray,
                &mut Triangles::new(&mesh, &Watertight),
                &mut Query::new(),
            )
            .map(|(i, h)| (i, h.t.to_bits()));
        assert_eq!(got, best);
    }
}

#[test]
fn bad_input_and_bad_outputs_are_refused_with_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n").unwrap();
    let out = dir.path().join("out.rs");
    let o = halfray(&[&"bake", &bad, &"-o", &out]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("bad.obj:3"), "{err}");
    assert!(!out.exists(), "nothing written on error");
    // The input itself as the output: refused, the input intact.
    let copy = dir.path().join("torus.obj");
    std::fs::copy(TORUS, &copy).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let o = halfray(&[&"bake", &copy, &"-o", &copy]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(std::fs::read(&copy).unwrap(), before);
    // A folder that does not exist.
    let o = halfray(&[&"bake", &TORUS, &"-o", &dir.path().join("missing/out.rs")]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("does not exist"));
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 2, "no temporary files left: {left:?}");
}

/// The little-endian `u32`s of `bytes`.
fn le_words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

#[test]
fn the_baked_buffer_holds_what_the_baked_source_holds_at_the_documented_offsets() {
    let dir = tempfile::tempdir().unwrap();
    let (rs, bin) = (dir.path().join("torus.rs"), dir.path().join("torus.bin"));
    let o = halfray(&[&"bake", &TORUS, &"-o", &rs]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = halfray(&[&"bake", &TORUS, &"-o", &bin, &"--format", &"bin"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (positions, triangles, nodes, indices) =
        read_source(&std::fs::read_to_string(&rs).unwrap());
    let b = std::fs::read(&bin).unwrap();
    // The table of `halfray_core::bvh::BakedLayout`, decoded here by hand.
    let (v, t, k) = (positions.len(), triangles.len(), nodes.len());
    assert_eq!(&b[..8], b"halfray\0");
    assert_eq!(le_words(&b[8..32]), [1, v as u32, t as u32, k as u32, 0, 0]);
    assert_eq!(b.len(), 32 + 32 * k + 12 * v + 16 * t);
    // The summary gives the file's size, the arrays' and the header's.
    let said = String::from_utf8(o.stdout).unwrap();
    let want = format!(
        "{} bytes ({} of arrays after a 32-byte header)",
        b.len(),
        b.len() - 32
    );
    assert!(said.contains(&want), "{said}");
    let node_words = le_words(&b[32..32 + 32 * k]);
    for (n, w) in nodes.iter().zip(node_words.chunks(8)) {
        let (bounds, start, count) = n.to_raw();
        let f: Vec<u32> = bounds.as_flattened().iter().map(|x| x.to_bits()).collect();
        assert_eq!(&w[..6], &f[..]);
        assert_eq!(&w[6..], &[start, count]);
    }
    let at = 32 + 32 * k;
    let p = le_words(&b[at..at + 12 * v]);
    let want: Vec<u32> = positions
        .iter()
        .flat_map(|q| q.to_array().map(f32::to_bits))
        .collect();
    assert_eq!(p, want);
    let at = at + 12 * v;
    assert_eq!(le_words(&b[at..at + 12 * t]), triangles.as_flattened());
    assert_eq!(le_words(&b[at + 12 * t..]), indices);
}
