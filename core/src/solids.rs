//! Small closed solids as index lists, for examples and tests: the vertex order is part of
//! the contract, and every triangle is counter-clockwise seen from outside (its normal
//! `(b − a) × (c − a)` points out of the solid).

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
