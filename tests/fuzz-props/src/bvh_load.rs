//! The `bvh_load` target: a BVH built on a soup (the `bvh` target's layout), changed by a
//! few byte-level corruptions, then given to [`Bvh::from_parts`] as a baked BVH would be.
//!
//! Layout: `mutations: u8` (mod 9), then per mutation `kind: u8`, `at: u16`, `value: u32`,
//! then a `bvh` soup ([`super::bvh::decode`]). Kinds (mod 8): 0 a box coordinate
//! (`at mod 6` picks it) set to `f32::from_bits(value)`; 1 a node's `start`, 2 its `count`
//! set to `value`; 3 an index entry set to `value`; 4 a vertex coordinate set to
//! `f32::from_bits(value)`; 5 the last node dropped; 6 the last index dropped; 7 two nodes
//! swapped (`at`, `value`).

use super::Input;
use super::bvh::{Oracle, Soup, decode};
use super::*;
use halfray_core::bvh::{Bvh, BvhError, BvhNode, load_scratch_len};
use halfray_core::mesh::TriangleMesh;
use halfray_core::triangle::Watertight;

/// Fuzz target `bvh_load`: [`check`] on the decoded input.
pub fn bvh_load(data: &[u8]) {
    let mut i = Input::new(data);
    let count = usize::from(i.u8()) % 9;
    let mutations: Vec<(u8, u16, u32)> = (0..count).map(|_| (i.u8(), i.u16(), i.u32())).collect();
    let rest = data.get(1 + 7 * count..).unwrap_or(&[]);
    check(&decode(rest), &mutations);
}

/// Properties:
///
/// 1. Loading never panics; every refusal is a typed error.
/// 2. A tree the builder made over a mesh with only usable triangles loads unchanged (checked
///    on every input, before the corruptions); the builder refuses only a mesh with a
///    non-finite (or out-of-range) triangle.
/// 3. Whatever loads answers every ray like brute force over all triangles (closest hit
///    exactly within the watertight test's documented domain, any-hit agreeing), so a
///    corruption is either refused or harmless.
pub fn check(s: &Soup, mutations: &[(u8, u16, u32)]) {
    let mut positions = s.positions.clone();
    let mesh = TriangleMesh::new(&s.positions, &s.triangles);
    let n = s.triangles.len();
    let options = halfray_core::bvh::BuildOptions {
        exclude_non_finite: false,
        ..s.options
    };
    let built = match Bvh::build(
        &mesh,
        vec![BvhNode::EMPTY; halfray_core::bvh::node_capacity(n)],
        vec![0u32; n],
        &options,
    ) {
        Ok(built) => built,
        // The storage fits and a soup has at most 16 triangles, so of the refusals
        // `Bvh::build` documents only a non-finite (or out-of-range) triangle's is possible:
        // nothing to bake.
        Err(e) => {
            reached();
            assert!(
                matches!(e, BvhError::NonFinite(_)),
                "the build refused a soup of {n} triangles with {e:?}"
            );
            return;
        }
    };
    let mut nodes = built.nodes().to_vec();
    let mut indices = built.indices().to_vec();
    let mut scratch = vec![0u32; load_scratch_len(n)];
    let loaded = Bvh::from_parts(&nodes[..], &indices[..], &mesh, &mut scratch);
    assert!(loaded.is_ok(), "a built tree is refused: {loaded:?}");
    for &(kind, at, value) in mutations {
        let at = usize::from(at);
        match kind % 8 {
            0..=2 if !nodes.is_empty() => {
                let k = at % nodes.len();
                let (mut b, mut start, mut count) = nodes[k].to_raw();
                match kind % 8 {
                    0 => b[(at / nodes.len()) % 2][at % 3] = f32::from_bits(value),
                    1 => start = value,
                    _ => count = value,
                }
                nodes[k] = BvhNode::from_raw(b, start, count);
            }
            3 if !indices.is_empty() => {
                let k = at % indices.len();
                indices[k] = value;
            }
            4 if !positions.is_empty() => {
                let k = at % positions.len();
                positions[k][at % 3] = f32::from_bits(value);
            }
            5 => {
                nodes.pop();
            }
            6 => {
                indices.pop();
            }
            7 if !nodes.is_empty() => {
                let (a, b) = (at % nodes.len(), value as usize % nodes.len());
                nodes.swap(a, b);
            }
            _ => {}
        }
    }
    let mesh = TriangleMesh::new(&positions, &s.triangles);
    // A refusal is a typed error (property 1); the tree as built loaded above, so a refusal
    // here is a corruption's.
    let Ok(bvh) = Bvh::from_parts(&nodes[..], &indices[..], &mesh, &mut scratch) else {
        return;
    };
    let in_tree = vec![true; n];
    let ctx = || {
        format!(
            "mutations {mutations:?}\n  nodes {nodes:?}\n  indices {indices:?}\n  positions {positions:?}"
        )
    };
    let oracle = Oracle {
        mesh: &mesh,
        in_tree: &in_tree,
        ctx: &ctx,
    };
    for ray in &s.rays {
        oracle.check_queries(&bvh, "BVH", &Watertight, ray, true);
    }
}

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    let grid: Vec<Vec3> = (0..9)
        .map(|k| {
            Vec3::new(
                (k % 3) as f32 * 2.0,
                (k / 3) as f32 * 2.0,
                (k % 2) as f32 * 0.5,
            )
        })
        .collect();
    let tris: Vec<[u8; 3]> = (0..4u8)
        .flat_map(|q| {
            let (i, j) = (q % 2, q / 2);
            let v = |di: u8, dj: u8| (j + dj) * 3 + i + di;
            [[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]]
        })
        .collect();
    let o = Vec3::new(1.5, 1.25, 6.0);
    let soup = bvh::encode_quantized(
        &grid,
        &tris,
        &[(o, 0, 8, 4), (o, 4, 4, 0), (o, 1, 7, 4), (o, 2, 6, 2)],
    );
    let with = |name: &str, muts: &[(u8, u16, u32)]| {
        let mut e = Enc::new().u8(muts.len() as u8);
        for &(k, at, v) in muts {
            e = e.u8(k).u16(at).bytes(&v.to_le_bytes());
        }
        (
            "bvh_load",
            format!("seed-{name}"),
            [e.done(), soup.clone()].concat(),
        )
    };
    s.push(with("as-built", &[]));
    s.push(with("box-coordinate", &[(0, 0, 1.0f32.to_bits())]));
    s.push(with("leaf-start", &[(1, 5, 3)]));
    s.push(with("repeated-index", &[(3, 1, 0)]));
    s.push(with("vertex-moved", &[(4, 4, 9.0f32.to_bits())]));
    s.push(with("nodes-swapped", &[(7, 0, 2)]));
    s.push(with("truncated", &[(5, 0, 0), (6, 0, 0)]));
}
