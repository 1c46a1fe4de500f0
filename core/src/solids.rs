//! Small closed solids and a flat grid as index lists, for examples and tests: the vertex
//! order is part of the contract, and every triangle is counter-clockwise seen from outside
//! (its normal `(b − a) × (c − a)` points out of the solid; for the grid, towards +z when its
//! `i` runs along +x and `j` along +y).

use glam::Vec3;

/// The octahedron's vertices, the unit points on the axes in the order +x, −x, +y, −y, +z, −z
/// (circumradius 1).
pub const OCTAHEDRON_VERTICES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// The octahedron's eight faces over [`OCTAHEDRON_VERTICES`]: the four around +z, then the
/// four around −z.
pub const OCTAHEDRON_TRIANGLES: [[u32; 3]; 8] = [
    [0, 2, 4],
    [2, 1, 4],
    [1, 3, 4],
    [3, 0, 4],
    [2, 0, 5],
    [1, 2, 5],
    [3, 1, 5],
    [0, 3, 5],
];

/// The cube `[-1, 1]³`: corner `i = 4·[x > 0] + 2·[y > 0] + [z > 0]`.
pub const CUBE_VERTICES: [Vec3; 8] = [
    Vec3::new(-1.0, -1.0, -1.0),
    Vec3::new(-1.0, -1.0, 1.0),
    Vec3::new(-1.0, 1.0, -1.0),
    Vec3::new(-1.0, 1.0, 1.0),
    Vec3::new(1.0, -1.0, -1.0),
    Vec3::new(1.0, -1.0, 1.0),
    Vec3::new(1.0, 1.0, -1.0),
    Vec3::new(1.0, 1.0, 1.0),
];

/// The cube's twelve triangles over [`CUBE_VERTICES`], two per face (−x, +x, −y, +y, −z, +z),
/// each square split on a diagonal through its lowest-numbered corner.
pub const CUBE_TRIANGLES: [[u32; 3]; 12] = [
    [0, 1, 3],
    [0, 3, 2],
    [4, 6, 7],
    [4, 7, 5],
    [0, 4, 5],
    [0, 5, 1],
    [2, 3, 7],
    [2, 7, 6],
    [0, 2, 6],
    [0, 6, 4],
    [1, 5, 7],
    [1, 7, 3],
];

/// The `2·nx·ny` triangles of a grid of `nx × ny` quads over `(nx + 1)·(ny + 1)` vertices
/// numbered row by row (vertex `(i, j)`, `0 ≤ i ≤ nx`, `0 ≤ j ≤ ny`, is `j·(nx + 1) + i`):
/// quad `(i, j)`, rows `j` in order and `i` in order within a row, is split on its diagonal
/// from `(i, j)` to `(i + 1, j + 1)` into `[(i, j), (i + 1, j), (i + 1, j + 1)]` and
/// `[(i, j), (i + 1, j + 1), (i, j + 1)]`. Indices are `u32`: the caller keeps
/// `(nx + 1)·(ny + 1) ≤ 2³²`; beyond it they wrap modulo `2³²` (never a panic).
pub fn grid_triangles(nx: u32, ny: u32) -> impl Iterator<Item = [u32; 3]> {
    let at = move |i: u32, j: u32| j.wrapping_mul(nx.wrapping_add(1)).wrapping_add(i);
    (0..ny).flat_map(move |j| {
        (0..nx).flat_map(move |i| {
            let (i1, j1) = (i.wrapping_add(1), j.wrapping_add(1));
            let (a, b, c, d) = (at(i, j), at(i1, j), at(i1, j1), at(i, j1));
            [[a, b, c], [a, c, d]]
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Beyond the documented `(nx + 1)·(ny + 1) ≤ 2³²` the indices wrap instead of
    /// overflowing: the first quad of a `u32::MAX`-wide grid is still two triangles.
    #[test]
    fn grid_triangles_beyond_u32_indices_wrap_without_panic() {
        let first: std::vec::Vec<_> = grid_triangles(u32::MAX, 1).take(2).collect();
        assert_eq!(first, [[0, 1, 1], [0, 1, 0]]);
    }

    /// Every quad's two triangles cover it once: over a 3 × 2 grid at integer positions, the
    /// signed areas (z of the cross product) are all `+1/2`, sum to the grid's area, and every
    /// interior edge is used once in each direction.
    #[test]
    fn grid_triangles_tile_the_grid_counter_clockwise() {
        let (nx, ny) = (3u32, 2u32);
        let pos = |v: u32| ((v % (nx + 1)) as i64, (v / (nx + 1)) as i64);
        let mut area2 = 0;
        let mut edges = [[0i32; 12]; 12];
        let mut count = 0;
        for t in grid_triangles(nx, ny) {
            let [a, b, c] = t.map(pos);
            let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
            assert_eq!(cross, 1, "{t:?}");
            area2 += cross;
            for k in 0..3 {
                edges[t[k] as usize][t[(k + 1) % 3] as usize] += 1;
            }
            count += 1;
        }
        assert_eq!((count, area2), (12, 12));
        for (u, row) in edges.iter().enumerate() {
            for (v, &used) in row.iter().enumerate() {
                assert!(used <= 1, "edge {u}->{v} used twice");
                let (pu, pv) = (pos(u as u32), pos(v as u32));
                let on_border = |p: (i64, i64), q: (i64, i64)| {
                    (p.0 == q.0 && (p.0 == 0 || p.0 == nx as i64))
                        || (p.1 == q.1 && (p.1 == 0 || p.1 == ny as i64))
                };
                if used == 1 && !on_border(pu, pv) {
                    assert_eq!(edges[v][u], 1, "interior edge {u}->{v} has no twin");
                }
            }
        }
    }
}
