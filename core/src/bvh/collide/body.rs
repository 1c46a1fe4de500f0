//! The two inputs of a query: a mesh with its BVH, and the placement of the second mesh in
//! the first one's frame.

use super::CollideError;
use crate::aabb::Aabb;
use crate::bvh::{Bvh, BvhNode};
use crate::float::gamma;
use crate::mesh::TriangleMesh;
use crate::transform::Transform;
use glam::{DVec3, Mat4, Vec3};

/// Outward padding of a node box of the second mesh after it is mapped into the first mesh's
/// frame, relative to `Σ_c |L_rc|·max(|lo_c|, |hi_c|) + |t_r|` on row `r` (`L` the linear
/// part, `t` the translation of the placement). Unitless.
///
/// Why: the triangles actually tested are the `f32` images
/// [`Transform::point_to_world`]`(v)`, each coordinate within `γ₃` of that sum of the exact
/// image (three roundings per term of the pairwise row sum). The exact image of the box is
/// contained in `centre ± |L|·half`, evaluated here in `f64` (error below `γ_f64(8)` of the
/// same sum). `γ₄` (of `f32`) covers `γ₃` plus the `f64` evaluation with room to spare.
pub const PLACED_BOX_PAD_REL: f64 = gamma(4) as f64;

/// Absolute outward padding of a placed node box, added to [`PLACED_BOX_PAD_REL`]'s, world
/// units: `4·2⁻¹⁴⁹`. Why: where a row's products fall below `f32`'s normal range (a placement
/// that scales by `2⁻¹⁰⁰`) each rounds by up to half the subnormal spacing `2⁻¹⁴⁹`
/// absolutely, not relatively: three products a row, `3·2⁻¹⁵⁰`, which the relative pad does
/// not cover; 4 spacings leave a margin.
pub const PLACED_BOX_PAD_ABS: f64 = 4.0 * 1.401_298_464_324_817e-45;

/// A triangle mesh and a BVH built over it ([`Bvh::build`] or [`Bvh::from_parts`] with that
/// mesh as the source): one side of a collision or distance query.
#[derive(Clone, Copy, Debug)]
pub struct Body<'a, N, I> {
    bvh: &'a Bvh<N, I>,
    mesh: TriangleMesh<'a>,
}

impl<'a, N: AsRef<[BvhNode]>, I: AsRef<[u32]>> Body<'a, N, I> {
    /// The body of `mesh` with its tree `bvh`.
    ///
    /// Checks, once for every query made with the body (both are borrowed for its lifetime),
    /// that `bvh` bounds `mesh`: every triangle of every leaf that `mesh` gives with finite
    /// vertices lies in that leaf's box, as in a tree built or refit over `mesh` (a leaf's box
    /// is then the exact minimum and maximum of its vertices). The broad phase's "never loses
    /// a pair" rests on it. One pass over the tree's triangles: `O(N)`, about what one
    /// [`Bvh::refit`] reads, where a query reads what its boxes overlap. A triangle the mesh
    /// cannot give (a vertex index out of range) or gives with a non-finite vertex is left out,
    /// as every query leaves it out (a refit with a non-finite vertex keeps the tree usable).
    ///
    /// # Errors
    ///
    /// [`CollideError::MeshMismatch`] when the tree was built over a different number of
    /// primitives than `mesh` has (a tree of another mesh);
    /// [`CollideError::TriangleOutsideTree`] for the first triangle (in node order) outside
    /// its leaf's box (a tree of another mesh with as many triangles, or of this one before
    /// its vertices moved without a refit).
    pub fn new(bvh: &'a Bvh<N, I>, mesh: TriangleMesh<'a>) -> Result<Self, CollideError> {
        if bvh.source_len() != mesh.len() {
            return Err(CollideError::MeshMismatch {
                bvh: bvh.source_len(),
                mesh: mesh.len(),
            });
        }
        let body = Self { bvh, mesh };
        for node in body.nodes() {
            if let Some((p, _)) = body
                .leaf_triangles(node)
                .find(|(_, v)| v.iter().all(|p| p.is_finite()) && !node.holds(v))
            {
                return Err(CollideError::TriangleOutsideTree {
                    triangle: p as usize,
                });
            }
        }
        Ok(body)
    }

    /// The tree.
    #[must_use]
    pub fn bvh(&self) -> &'a Bvh<N, I> {
        self.bvh
    }

    /// The mesh.
    #[must_use]
    pub fn mesh(&self) -> TriangleMesh<'a> {
        self.mesh
    }

    /// The used nodes.
    pub(super) fn nodes(&self) -> &'a [BvhNode] {
        self.bvh.nodes()
    }

    /// The triangles of a leaf with their indices, in the leaf's order, skipping any the mesh
    /// cannot give (a vertex index out of range). Empty for an inner node or a bad range.
    pub(super) fn leaf_triangles(
        &self,
        node: &BvhNode,
    ) -> impl Iterator<Item = (u32, [Vec3; 3])> + Clone + use<'a, N, I> {
        let (indices, mesh) = (self.bvh.indices(), self.mesh);
        let leaf = node
            .primitive_range()
            .and_then(|r| indices.get(r))
            .unwrap_or(&[]);
        leaf.iter()
            .filter_map(move |&i| mesh.triangle(i as usize).map(|t| (i, t)))
    }
}

/// An `f64` axis-aligned box (closed).
#[derive(Clone, Copy, Debug)]
pub(super) struct DBox {
    pub(super) min: DVec3,
    pub(super) max: DVec3,
}

impl DBox {
    pub(super) fn from_aabb(b: &Aabb) -> Self {
        Self {
            min: b.min.as_dvec3(),
            max: b.max.as_dvec3(),
        }
    }

    pub(super) fn overlaps(&self, o: &Self) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// Euclidean distance between the boxes (`0` when they overlap), rounded in `f64`.
    pub(super) fn distance(&self, o: &Self) -> f64 {
        let gap = (o.min - self.max).max(self.min - o.max).max(DVec3::ZERO);
        gap.length()
    }

    /// The largest coordinate magnitude.
    pub(super) fn magnitude(&self) -> f64 {
        self.min.abs().max(self.max.abs()).max_element()
    }
}

/// The placement of the second body in the first one's frame: its matrix in `f64` rows.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placement {
    tf: Transform,
    rows: [(DVec3, f64); 3],
}

impl Placement {
    pub(super) fn new(tf: &Transform) -> Self {
        let m: Mat4 = tf.matrix();
        let row = |r: usize| {
            let r4 = m.row(r);
            (r4.truncate().as_dvec3(), f64::from(r4.w))
        };
        Self {
            tf: *tf,
            rows: [row(0), row(1), row(2)],
        }
    }

    /// The triangle's vertices in the first body's frame, as every test sees them.
    #[inline]
    pub(super) fn triangle(&self, t: [Vec3; 3]) -> [Vec3; 3] {
        t.map(|v| self.tf.point_to_world(v))
    }

    /// A box containing the placed images of every point of `b` (padded by
    /// [`PLACED_BOX_PAD_REL`] and [`PLACED_BOX_PAD_ABS`]); `None` for an empty or non-finite
    /// box.
    pub(super) fn place_box(&self, b: &Aabb) -> Option<DBox> {
        if !(b.is_finite() && b.is_valid()) {
            return None;
        }
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let (c, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        let mag = lo.abs().max(hi.abs());
        let (mut min, mut max) = (DVec3::ZERO, DVec3::ZERO);
        for (r, &(l, t)) in self.rows.iter().enumerate() {
            let centre = l.dot(c) + t;
            let half = l.abs().dot(h);
            let pad = PLACED_BOX_PAD_REL * (l.abs().dot(mag) + t.abs()) + PLACED_BOX_PAD_ABS;
            min[r] = centre - half - pad;
            max[r] = centre + half + pad;
        }
        (min.is_finite() && max.is_finite()).then_some(DBox { min, max })
    }
}
