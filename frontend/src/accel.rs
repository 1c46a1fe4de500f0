//! A triangle mesh with its acceleration structure, owned (std), for the frontend's tools:
//! closest-hit and any-hit queries with any triangle intersector variant.

use crate::obj::ObjMesh;
use halfray_core::Ray;
use halfray_core::triangle::{
    Cramer, F64Reference, MollerTrumbore, TriangleHit, TriangleIntersector, TriangleVariant,
    Watertight, WatertightF32,
};

/// A mesh ready for ray queries.
pub struct MeshAccel {
    /// The mesh.
    pub mesh: ObjMesh,
    tris: Vec<[glam::Vec3; 3]>,
}

impl MeshAccel {
    /// Builds the acceleration structure over `mesh`.
    pub fn new(mesh: ObjMesh) -> crate::Result<Self> {
        let tris = (0..mesh.triangles.len())
            .map(|i| mesh.triangle(i))
            .collect();
        Ok(Self { mesh, tris })
    }

    /// Closest hit with `isect`: `(triangle index, hit)`.
    pub fn closest<I: TriangleIntersector>(
        &self,
        isect: &I,
        ray: &Ray,
    ) -> Option<(u32, TriangleHit)> {
        let pre = isect.prepare(ray)?;
        let mut r = *ray;
        let mut best = None;
        for (i, t) in self.tris.iter().enumerate() {
            if let Some(h) = isect.intersect_prepared(&pre, &r, t) {
                r.t_max = h.t;
                best = Some((i as u32, h));
            }
        }
        best
    }

    /// Whether anything is hit in the ray's interval.
    pub fn any<I: TriangleIntersector>(&self, isect: &I, ray: &Ray) -> bool {
        let Some(pre) = isect.prepare(ray) else {
            return false;
        };
        self.tris
            .iter()
            .any(|t| isect.intersect_prepared(&pre, ray, t).is_some())
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
