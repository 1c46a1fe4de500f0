//! Unit tests of the collapse's choice of children, on binary trees written by hand.

use super::*;
use std::vec::Vec;

/// A binary node over the cube `[0, side]³` (surface area `6·side²`): a leaf of `count`
/// primitives from `start`, or (`count = 0`) an inner node with children `start`, `start + 1`.
fn node(side: f32, start: u32, count: u32) -> BvhNode {
    BvhNode::from_raw([[0.0; 3], [side; 3]], start, count)
}

/// `child_list` expands every inner entry before any leaf run, the largest first, whatever
/// the order of the entries. The tree (52 primitives):
///
/// ```text
/// 0 root ── 1 A (side 1) ── 3 A1: leaf 0..6, 4 A2: leaf 6..12
///        └─ 2 B (side 4) ── 5 C (side 4) ── 7 C1: leaf 12..22, 8 C2: leaf 22..32
///                        └─ 6 D (side 2) ── 9 D1: leaf 32..42, 10 D2: leaf 42..52
/// ```
///
/// A is a run of 12 ≤ `LEAF_MERGE` primitives that opens (12 > `LEAF_OPEN_ABOVE`, an inner
/// node); B, C and D hold 20 or more, so they are inner entries. For `W = 4`, by hand:
/// `[A, B]` → B, the only inner entry, is replaced by its children: `[A, C, D]` → C, the inner
/// entry of larger area (96 against 24): `[A, C1, D, C2]`, full. A stays one leaf run of 12
/// although it comes first and could open. (Opening A first would give `[A1, C, A2, D]` or,
/// taking the later inner entry, D before C: `[A, D1, C, D2]`.)
#[test]
fn inner_entries_expand_before_leaf_runs_largest_first() {
    assert_eq!(
        (LEAF_MERGE, LEAF_OPEN_ABOVE),
        (16, 8),
        "the tree below assumes these"
    );
    let nodes = [
        node(4.0, 1, 0),
        node(1.0, 3, 0),
        node(4.0, 5, 0),
        node(1.0, 0, 6),
        node(1.0, 6, 6),
        node(4.0, 7, 0),
        node(2.0, 9, 0),
        node(4.0, 12, 10),
        node(4.0, 22, 10),
        node(2.0, 32, 10),
        node(2.0, 42, 10),
    ];
    let list = child_list::<4>(&nodes, 0);
    let got: Vec<_> = list.iter().collect();
    assert_eq!(
        got,
        [
            (1, Some(0..12)),
            (7, Some(12..22)),
            (6, None),
            (8, Some(22..32))
        ]
    );
}

/// `group_capacity` is the documented `⌈7N/16⌉`, worked by hand: 0 → 0, 1 → 1, 16 → 7,
/// 17 → ⌈119/16⌉ = 8, 1000 → ⌈7000/16⌉ = 438.
#[test]
fn group_capacity_is_seven_sixteenths_rounded_up() {
    for (n, want) in [(0, 0), (1, 1), (16, 7), (17, 8), (1000, 438)] {
        assert_eq!(crate::bvh::wide::group_capacity(n), want, "{n}");
    }
}

/// A run whose split spares a ray entering the root's box at least `LARGE_NODE_SAVING` tests
/// is an inner entry, expanded before smaller inner ones; in a tree of at most `LEAF_MERGE`
/// triangles it stays one run. The tree (24 primitives; boxes are cubes, area `6·side²`):
///
/// ```text
/// 0 root (side 10) ── 1 A (side 10) ── 3 A1: leaf 0..2 (side 1), 4 A2: leaf 2..4 (side 1)
///                  └─ 2 B (side 1)  ── 5 B1: leaf 4..14, 6 B2: leaf 14..24 (side 1)
/// ```
///
/// A is a run of 4 (≤ `LEAF_OPEN_ABOVE`, so [`opens`] says no), but splitting it spares
/// `4·600 − (2·6 + 2·6) = 2376 ≥ 0.5·600` (the root's area): `[A, B]` → A, the larger:
/// `[A1, B, A2]` → B: `[A1, B1, A2, B2]`. With B's leaves of 2 (8 primitives in all) the
/// whole tree is at most `LEAF_MERGE`: `[A, B]` stay runs.
#[test]
fn a_run_that_spares_enough_tests_is_an_inner_entry() {
    let mut nodes = [
        node(10.0, 1, 0),
        node(10.0, 3, 0),
        node(1.0, 5, 0),
        node(1.0, 0, 2),
        node(1.0, 2, 2),
        node(1.0, 4, 10),
        node(1.0, 14, 10),
    ];
    let got: Vec<_> = child_list::<4>(&nodes, 0).iter().collect();
    assert_eq!(
        got,
        [
            (3, Some(0..2)),
            (5, Some(4..14)),
            (4, Some(2..4)),
            (6, Some(14..24))
        ]
    );
    nodes[5] = node(1.0, 4, 2);
    nodes[6] = node(1.0, 6, 2);
    let got: Vec<_> = child_list::<4>(&nodes, 0).iter().collect();
    assert_eq!(got, [(1, Some(0..4)), (2, Some(4..8))]);
}
