//! Area-weighted vertex normals.
//!
//! The normal of a vertex is the normalised **sum of the unnormalised face normals**
//! `(b − a) × (c − a)` ([`Mesh::face_normal_unnormalized`]) of the faces around it. Each face
//! normal has length twice the face's area, so the sum weights every face by its area: large
//! faces dominate, slivers barely count, and a vertex where faces meet at a crease gets a
//! normal that leans towards the side with more surface. This is what the clearance query
//! ([`crate::query::RayQuery::clearance`]) casts rays along.
//!
//! * Boundary vertices: the faces that exist are summed (the boundary gap contributes
//!   nothing), so a vertex on the rim of a flat sheet gets the sheet's normal.
//! * No normal (`None`, or a zero vector in [`Mesh::vertex_normals`]) for a dead or isolated
//!   vertex, and for a vertex whose face normals sum to zero or to a vector whose length is not
//!   a finite positive `f32` (all faces degenerate, cancelling faces such as a folded sheet, or
//!   coordinates so large that the squared length overflows).
//!
//! Allocation-free; O(valence) per vertex.

use glam::Vec3;

use super::handles::VertexId;
use super::mesh::Mesh;
use super::storage::MeshStorage;
use crate::error::{CapacityError, Storage};

impl<S: MeshStorage> Mesh<S> {
    /// The area-weighted unit normal of `v`: the normalised sum of the unnormalised normals
    /// (twice the area times the unit normal) of the faces around `v`; see the
    /// [module docs](self). Works at boundary vertices (only existing faces are summed).
    ///
    /// `None` for a dead or isolated vertex, or when the sum is zero or cannot be normalised.
    #[must_use]
    pub fn vertex_normal(&self, v: VertexId) -> Option<Vec3> {
        let mut sum = Vec3::ZERO;
        for f in self.vertex_faces(v) {
            sum += self.face_normal_unnormalized(f).unwrap_or(Vec3::ZERO);
        }
        sum.try_normalize()
    }

    /// Every vertex's [`Mesh::vertex_normal`], written to `out[v.index()]` for each vertex slot
    /// (`slots().vertices` entries; further entries are left alone). Vertices without a normal
    /// (dead, isolated, zero sum) get `Vec3::ZERO`. Each entry is bit-for-bit what
    /// `vertex_normal` returns. Returns the number of **live** vertices that got no normal.
    ///
    /// # Errors
    /// [`CapacityError`] of [`Storage::VertexNormals`] (nothing written) when `out` is shorter
    /// than `slots().vertices`.
    pub fn vertex_normals(&self, out: &mut [Vec3]) -> Result<usize, CapacityError> {
        let needed = self.slots().vertices;
        CapacityError::check(Storage::VertexNormals, needed, out.len())?;
        let mut missing = 0;
        for (i, o) in out.iter_mut().enumerate().take(needed) {
            let v = VertexId(i as u32);
            *o = match self.vertex_normal(v) {
                Some(n) => n,
                None => {
                    if self.contains_vertex(v) {
                        missing += 1;
                    }
                    Vec3::ZERO
                }
            };
        }
        Ok(missing)
    }
}

#[cfg(test)]
mod tests {
    use std::vec;
    use std::vec::Vec;

    use glam::{Vec3, vec3};

    use crate::error::{CapacityError, Storage};
    use crate::halfedge::{CollapseAt, HalfedgeMesh, VertexId, build_scratch_len};
    use crate::solids::{CUBE_TRIANGLES, CUBE_VERTICES};

    /// Absolute tolerance per component for unit normals computed in f32 from exact small
    /// inputs: one normalisation (a square root and a division, each ≤ ½ ulp) plus the
    /// rounding of the expected value's `1/√n`: a few ulps of 1 (2⁻²³ ≈ 1.2e-7).
    const NORMAL_TOL: f32 = 1e-6;

    type M = HalfedgeMesh<64, 192, 128>;

    fn build(p: &[Vec3], t: &[[u32; 3]]) -> M {
        let mut m = M::new();
        let mut scratch = vec![0u32; build_scratch_len(t.len())];
        m.build(p, t, &mut scratch).unwrap();
        m
    }

    fn assert_close(got: Vec3, want: Vec3) {
        assert!(
            (got - want).abs().max_element() <= NORMAL_TOL,
            "got {got}, want {want}"
        );
    }

    /// `cube.obj` of the shared meshes: [-1, 1]³, each square split on a diagonal.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (CUBE_VERTICES.to_vec(), CUBE_TRIANGLES.to_vec())
    }

    #[test]
    fn cube_corners_are_area_weighted() {
        // Every triangle has area 2, so its unnormalised normal has length 4 along its face's
        // axis. A corner touches one or both triangles of each of its three squares,
        // depending on whether that square's diagonal runs through it. Corners 0 and 7 lie on
        // three diagonals: 4·(±2, ±2, ±2) → (±1, ±1, ±1)/√3. The others lie on one diagonal,
        // e.g. corner 1 = (−1, −1, 1): one triangle on −x, one on −y, both on +z →
        // 4·(−1, −1, 2) → (−1, −1, 2)/√6.
        let (p, t) = cube();
        let m = build(&p, &t);
        let s3 = 1.0 / 3.0f32.sqrt();
        let s6 = 1.0 / 6.0f32.sqrt();
        let want = [
            vec3(-1.0, -1.0, -1.0) * s3,
            vec3(-1.0, -1.0, 2.0) * s6,
            vec3(-1.0, 2.0, -1.0) * s6,
            vec3(-2.0, 1.0, 1.0) * s6,
            vec3(2.0, -1.0, -1.0) * s6,
            vec3(1.0, -2.0, 1.0) * s6,
            vec3(1.0, 1.0, -2.0) * s6,
            vec3(1.0, 1.0, 1.0) * s3,
        ];
        for (i, w) in want.iter().enumerate() {
            let n = m.vertex_normal(VertexId::new(i as u32)).unwrap();
            assert_close(n, *w);
            // Points out of the cube: same octant as the corner.
            assert!(n.dot(p[i]) > 0.0);
        }
        let mut out = [Vec3::NAN; 8];
        assert_eq!(m.vertex_normals(&mut out), Ok(0));
        for (i, o) in out.iter().enumerate() {
            assert_eq!(Some(*o), m.vertex_normal(VertexId::new(i as u32)));
        }
    }

    #[test]
    fn area_weighting_differs_from_angle_or_uniform() {
        // Two faces at vertex 0 across the edge 0–1: [0, 1, 2] in z = 0 with normal (0, 0, 2)
        // (area 1), and [1, 0, 3] in y = 0 with normal (0, 1, 0) (area ½). Area-weighted:
        // (0, 1, 2)/√5; an unweighted mean of unit normals would give (0, 1, 1)/√2.
        let p = [
            Vec3::ZERO,
            vec3(1.0, 0.0, 0.0),
            vec3(0.0, 2.0, 0.0),
            vec3(0.0, 0.0, 1.0),
        ];
        let m = build(&p, &[[0, 1, 2], [1, 0, 3]]);
        let n = m.vertex_normal(VertexId::new(0)).unwrap();
        assert_close(n, vec3(0.0, 1.0, 2.0) / 5.0f32.sqrt());
        // Vertex 2 touches only the first face, vertex 3 only the second.
        assert_close(m.vertex_normal(VertexId::new(2)).unwrap(), Vec3::Z);
        assert_close(m.vertex_normal(VertexId::new(3)).unwrap(), Vec3::Y);
    }

    /// A flat `n × n`-quad grid in z = `z0`, counter-clockwise seen from +z, with jittered
    /// in-plane positions (the plane normal must not depend on the triangle shapes).
    fn grid(n: u32, z0: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let jitter = ((i * 7 + j * 13) % 5) as f32 * 0.03;
                p.push(vec3(i as f32 + jitter, j as f32 - jitter, z0));
            }
        }
        (p, crate::solids::grid_triangles(n, n).collect())
    }

    #[test]
    fn flat_grid_interior_and_boundary_vertices_get_the_plane_normal() {
        let (p, t) = grid(4, 2.5);
        let m = build(&p, &t);
        let mut boundary = 0;
        for v in m.vertices() {
            boundary += usize::from(m.is_boundary_vertex(v));
            // In-plane components are exact zeros (every face normal is (0, 0, +c)); z is 1 up
            // to the rounding of the normalisation.
            let n = m.vertex_normal(v).unwrap();
            assert_eq!((n.x, n.y), (0.0, 0.0), "vertex {v:?}");
            assert_close(n, Vec3::Z);
        }
        assert_eq!(boundary, 16);
        // Flipped orientation flips the normal.
        let flipped: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let m = build(&p, &flipped);
        for v in m.vertices() {
            assert_close(m.vertex_normal(v).unwrap(), -Vec3::Z);
        }
    }

    #[test]
    fn isolated_dead_and_degenerate_vertices_have_no_normal() {
        // Vertex 3 is unreferenced; the face [0, 1, 2] is degenerate (collinear corners).
        let p = [
            Vec3::ZERO,
            vec3(1.0, 0.0, 0.0),
            vec3(2.0, 0.0, 0.0),
            vec3(5.0, 5.0, 5.0),
        ];
        let m = build(&p, &[[0, 1, 2]]);
        for v in 0..4 {
            assert_eq!(m.vertex_normal(VertexId::new(v)), None);
        }
        assert_eq!(m.vertex_normal(VertexId::new(99)), None);
        let mut out = [Vec3::ONE; 5];
        assert_eq!(m.vertex_normals(&mut out), Ok(4));
        assert_eq!(&out[..4], &[Vec3::ZERO; 4]);
        assert_eq!(out[4], Vec3::ONE, "entries past the slots are left alone");
    }

    #[test]
    fn buffer_too_small_is_a_typed_error_and_writes_nothing() {
        let (p, t) = cube();
        let m = build(&p, &t);
        let mut out = [Vec3::ONE; 7];
        assert_eq!(
            m.vertex_normals(&mut out),
            Err(CapacityError {
                storage: Storage::VertexNormals,
                needed: 8,
                available: 7
            })
        );
        assert_eq!(out, [Vec3::ONE; 7]);
    }

    #[test]
    fn tombstoned_slots_get_zero_and_live_ones_stay_consistent() {
        let (p, t) = grid(3, 0.0);
        let mut m = build(&p, &t);
        // Collapse an interior edge: its tail's slot becomes a tombstone.
        let a = VertexId::new(5);
        let b = VertexId::new(6);
        let h = m.find_halfedge(a, b).unwrap();
        m.collapse_edge(h, CollapseAt::Midpoint).unwrap();
        assert!(!m.contains_vertex(a));
        let mut out = vec![Vec3::ONE; m.slots().vertices];
        assert_eq!(m.vertex_normals(&mut out), Ok(0));
        assert_eq!(out[5], Vec3::ZERO);
        for v in m.vertices() {
            assert_close(out[v.index()], Vec3::Z);
        }
    }
}
