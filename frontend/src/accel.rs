//! A triangle mesh with its BVH, owned (std), for the frontend's tools: closest-hit and any-hit
//! queries with any triangle intersector variant.

use crate::error::{Error, Result};
use crate::obj::ObjMesh;
use halfray_core::Ray;
use halfray_core::bvh::{
    BuildOptions, Bvh, BvhNode, TraversalStats, TriangleMesh, index_capacity, node_capacity,
};
use halfray_core::triangle::{
    Cramer, F64Reference, MollerTrumbore, TriangleHit, TriangleIntersector, TriangleVariant,
    Watertight, WatertightF32,
};

/// A mesh ready for ray queries.
pub struct MeshAccel {
    /// The mesh.
    pub mesh: ObjMesh,
    bvh: Bvh<Vec<BvhNode>, Vec<u32>>,
}

impl MeshAccel {
    /// Builds the BVH over `mesh` (binned SAH, default options).
    pub fn new(mesh: ObjMesh) -> Result<Self> {
        let n = mesh.triangles.len();
        let bvh = Bvh::build(
            &TriangleMesh::new(&mesh.positions, &mesh.triangles),
            vec![BvhNode::default(); node_capacity(n)],
            vec![0u32; index_capacity(n)],
            &BuildOptions::default(),
        )
        .map_err(|e| Error::Other(format!("building the BVH: {e}")))?;
        Ok(Self { mesh, bvh })
    }

    /// The BVH.
    pub fn bvh(&self) -> &Bvh<Vec<BvhNode>, Vec<u32>> {
        &self.bvh
    }

    fn tri_mesh(&self) -> TriangleMesh<'_> {
        TriangleMesh::new(&self.mesh.positions, &self.mesh.triangles)
    }

    /// Closest hit with `isect`: `(triangle index, hit)`.
    pub fn closest<I: TriangleIntersector>(
        &self,
        isect: &I,
        ray: &Ray,
    ) -> Option<(u32, TriangleHit)> {
        self.bvh
            .closest_hit_triangles(&self.tri_mesh(), isect, ray, None)
    }

    /// Closest hit with traversal statistics added to `stats`.
    pub fn closest_with_stats<I: TriangleIntersector>(
        &self,
        isect: &I,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<(u32, TriangleHit)> {
        self.bvh
            .closest_hit_triangles(&self.tri_mesh(), isect, ray, Some(stats))
    }

    /// Whether anything is hit in the ray's interval.
    pub fn any<I: TriangleIntersector>(&self, isect: &I, ray: &Ray) -> bool {
        self.bvh
            .any_hit_triangles(&self.tri_mesh(), isect, ray, None)
            .is_some()
    }

    /// Closest hit with a variant chosen at run time.
    pub fn closest_variant(&self, v: TriangleVariant, ray: &Ray) -> Option<(u32, TriangleHit)> {
        match v {
            TriangleVariant::Watertight => self.closest(&Watertight, ray),
            TriangleVariant::WatertightF32 => self.closest(&WatertightF32, ray),
            TriangleVariant::MollerTrumbore => self.closest(&MollerTrumbore::CLASSIC, ray),
            TriangleVariant::MollerTrumboreNoEps => self.closest(&MollerTrumbore::NO_EPSILON, ray),
            TriangleVariant::Cramer => self.closest(&Cramer, ray),
            TriangleVariant::F64Reference => self.closest(&F64Reference, ray),
        }
    }

    /// Any hit with a variant chosen at run time.
    pub fn any_variant(&self, v: TriangleVariant, ray: &Ray) -> bool {
        match v {
            TriangleVariant::Watertight => self.any(&Watertight, ray),
            TriangleVariant::WatertightF32 => self.any(&WatertightF32, ray),
            TriangleVariant::MollerTrumbore => self.any(&MollerTrumbore::CLASSIC, ray),
            TriangleVariant::MollerTrumboreNoEps => self.any(&MollerTrumbore::NO_EPSILON, ray),
            TriangleVariant::Cramer => self.any(&Cramer, ray),
            TriangleVariant::F64Reference => self.any(&F64Reference, ray),
        }
    }
}
