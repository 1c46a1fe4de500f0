//! One query interface for every acceleration structure ([`crate::bvh::Bvh`],
//! [`crate::bvh::wide::Bvh8`] and [`crate::bvh::wide::Bvh4`], [`crate::grid::Grid`],
//! [`crate::kdtree::KdTree`]):
//!
//! * [`RayQuery`]: closest hit, any hit, box query, clearance and size, one contract for all;
//! * [`LeafTest`]: what a query does with one primitive — a closure, or [`Triangles`] (a
//!   mesh with any [`TriangleIntersector`](crate::triangle::TriangleIntersector));
//! * [`Query`]: what varies between calls — the traversal stack, the SIMD level, statistics
//!   ([`TraversalStats`]).
//!
//! ```
//! use halfray_core::prelude::*;
//! use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
//! use halfray_core::mesh::TriangleMesh;
//! use halfray_core::query::{Query, Triangles};
//! use halfray_core::triangle::Watertight;
//! use halfray_core::{Ray, Vec3};
//!
//! let positions = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
//! let mesh = TriangleMesh::new(&positions, &[[0, 1, 2]]);
//! let (mut nodes, mut indices) = ([BvhNode::EMPTY; node_capacity(1)], [0u32; index_capacity(1)]);
//! let bvh = Bvh::build(&mesh, &mut nodes[..], &mut indices[..], &BuildOptions::default()).unwrap();
//! let ray = Ray::new(Vec3::ZERO, Vec3::Z);
//! let mut tris = Triangles::new(&mesh, &Watertight);
//! let (prim, hit) = bvh.closest_hit(&ray, &mut tris, &mut Query::new()).unwrap();
//! assert_eq!((prim, hit.t), (0, 2.0));
//! ```
//!
//! # The contract
//!
//! **Closest hit**: of the primitives whose [`LeafTest`] reports a `t` in the ray's interval
//! `(t_min, t_max]`, the one with the smallest `t`; of equal `t`, the **smaller primitive
//! index** (the tie rule), so the answer does not depend on the structure and equals a
//! brute-force loop over all primitives with the same rule (with [`crate::triangle::Watertight`]
//! triangles, within its documented domain). **Any hit**: some primitive reporting a `t` in
//! the interval, found first by the structure's walk (which one depends on the structure;
//! hit/miss does not). An invalid ray ([`crate::ray::Ray::validate`]) hits nothing and tests
//! nothing. **Box query**: every primitive whose bounds overlap a box (closed boxes), each
//! reported once.

mod batch;
pub(crate) use batch::same_length;
mod context;
mod error;
pub(crate) mod forward;
mod leaf;
mod stats;
pub(crate) mod walk;

#[cfg(test)]
mod tests;

pub use batch::BATCH_CHUNK;
pub use context::{OwnStack, QUERY_STACK_SIZE, Query, QueryStack, Stack, StackEntry};
pub use error::QueryError;
pub use leaf::{LeafTest, Triangles};
pub use stats::TraversalStats;
pub use walk::CULL_REL_SLACK;

use crate::aabb::Aabb;
use crate::float::sqrt_f64;
use crate::mesh::PrimitiveSource;
use crate::ray::Ray;
use crate::sealed::Inside;
use crate::simd_level::SimdLevel;
use crate::triangle::TriangleLanes;
use glam::Vec3;

/// The queries of an acceleration structure over primitives numbered `0..N` (module docs for
/// the contract).
///
/// Closest and any hit take the ray, the [`LeafTest`] and a [`Query`] context; what they
/// return depends on the context's [`Stack`]: `Option<(primitive index, hit payload)>` on a
/// stack that cannot be too small (the default), `Result` of it on a caller's stack of any
/// length.
pub trait RayQuery {
    /// The closest hit of `ray` as `(primitive index, leaf's payload)`: the leaf test sees
    /// the ray with `t_max` shrunk to the closest `t` so far. The context's statistics are
    /// added to.
    fn closest_hit<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut T,
        ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, T::Hit)>;

    /// Any hit of `ray` (occlusion, shadow rays): the walk stops at the first primitive the
    /// leaf test reports in `(t_min, t_max]`. The context's statistics are added to.
    fn any_hit<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        ray: &Ray,
        leaf: &mut T,
        ctx: &mut Query<'_, L, S>,
    ) -> S::Out<(u32, T::Hit)>;

    /// Writes [`RayQuery::closest_hit`] of `rays[i]` into `out[i]`, for every `i`, through
    /// `leaf` and the context `ctx` (its stack reused, its statistics added to): each answer
    /// is the single-ray answer, bit for bit. Pass a [`QueryStack`] in the context
    /// (`Query::new().stack(&mut stack)`) to avoid a fresh stack per ray. An empty batch is
    /// `Ok` and writes nothing. The wide trees walk coherent rays in packets (see
    /// [`crate::bvh::wide`]); the other structures walk each ray alone, in a coherent order
    /// chunk by chunk ([`BATCH_CHUNK`]).
    ///
    /// # Errors
    ///
    /// Nothing written, no ray walked: [`QueryError::LengthMismatch`] when `out` does not have
    /// `rays.len()` entries. (A caller stack too small for one ray is that ray's answer,
    /// `Err(StackTooSmall)`, in `out`, as for the single-ray query.)
    #[inline(always)]
    fn closest_hits<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        rays: &[Ray],
        leaf: &mut T,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, T::Hit)>],
    ) -> Result<(), QueryError> {
        batch::in_coherent_order(rays, out, |ray| self.closest_hit(ray, leaf, ctx))
    }

    /// Writes an any hit of `rays[i]` into `out[i]`, for every `i` (as
    /// [`RayQuery::closest_hits`]): hit or miss is [`RayQuery::any_hit`]'s, and a hit is a
    /// primitive the leaf test reports in the ray's interval, with that report's payload.
    /// Which primitive is the single-ray walk's, except where a structure tests rays together:
    /// the wide trees' any-hit packets (shadow rays towards one light) report the first one
    /// the packet reaches, and a wide tree of at most eight groups with nodes tests all its
    /// triangles without the nodes for every batch, even of one ray, so its primitive may be
    /// another than the single-ray walk's.
    ///
    /// # Errors
    ///
    /// As [`RayQuery::closest_hits`]: [`QueryError::LengthMismatch`], nothing written.
    #[inline(always)]
    fn any_hits<T: LeafTest, L: SimdLevel, S: Stack>(
        &self,
        rays: &[Ray],
        leaf: &mut T,
        ctx: &mut Query<'_, L, S>,
        out: &mut [S::Out<(u32, T::Hit)>],
    ) -> Result<(), QueryError> {
        batch::in_coherent_order(rays, out, |ray| self.any_hit(ray, leaf, ctx))
    }

    /// Calls `found(prim)` once for every primitive whose bounds in `source` (the source the
    /// structure was built over or last refitted to; the wide trees read their own copies)
    /// overlap `query` (closed boxes: touching counts, see [`Aabb::overlaps`]); `found`
    /// returns `true` to continue, `false` to stop. Returns the number reported. An empty or
    /// NaN query box reports nothing. The broad phase of a collision query: primitives come
    /// in the structure's order, not index order.
    fn query_box<P: PrimitiveSource + ?Sized>(
        &self,
        source: &P,
        query: &Aabb,
        found: impl FnMut(u32) -> bool,
    ) -> usize;

    /// Number of primitives in the structure (those excluded at build time not counted).
    fn primitive_count(&self) -> usize;

    /// Bytes of the structure's storage in use (nodes, references, copied triangles); the
    /// caller's vertices and triangles are not counted.
    fn bytes_used(&self) -> usize;

    /// [`RayQuery::bytes_used`] per primitive (0 for an empty structure): the one size figure
    /// comparable across structures.
    #[must_use]
    fn bytes_per_triangle(&self) -> f64 {
        match self.primitive_count() {
            0 => 0.0,
            n => self.bytes_used() as f64 / n as f64,
        }
    }

    /// For each point `points[i]` casts the ray `points[i] + t·normals[i]`, `t ∈ (0, ∞]`,
    /// and writes the distance to its closest hit by `leaf` — `t·|normals[i]|`, in world
    /// units, so normals need not be unit length — into `out[i]` (`+∞` when nothing is hit or
    /// the ray is invalid, e.g. a zero or NaN normal). Returns the minimum over all points
    /// (`+∞` for none). Typical use: how far a body (a drone's mesh, by its vertex normals)
    /// can move before it meets the scene (a hangar's walls in the structure).
    ///
    /// # Errors
    ///
    /// Nothing written: [`QueryError::LengthMismatch`] when `normals` or `out` do not have
    /// `points.len()` entries.
    fn clearance<T: LeafTest>(
        &self,
        leaf: &mut T,
        points: &[Vec3],
        normals: &[Vec3],
        out: &mut [f32],
    ) -> Result<f32, QueryError> {
        for len in [normals.len(), out.len()] {
            if len != points.len() {
                return Err(QueryError::LengthMismatch {
                    expected: points.len(),
                    found: len,
                });
            }
        }
        let mut leaf = HitDistance(leaf);
        let mut min = f32::INFINITY;
        for ((&p, &n), o) in points.iter().zip(normals).zip(out.iter_mut()) {
            let ray = Ray::new(p, n);
            let dist = match self.closest_hit(&ray, &mut leaf, &mut Query::new()) {
                // In `f64`: the square of an `f32` length neither overflows nor underflows
                // there, so a normal of length 1e-30 or 1e30 gives the distance, not 0 or ∞.
                Some((_, t)) => (f64::from(t) * sqrt_f64(n.as_dvec3().length_squared())) as f32,
                None => f32::INFINITY,
            };
            *o = dist;
            min = min.min(dist);
        }
        Ok(min)
    }
}

/// A leaf test whose payload is the hit's `t` (the clearance query's), otherwise `T`.
struct HitDistance<'l, T>(&'l mut T);

impl<T: LeafTest> LeafTest for HitDistance<'_, T> {
    type Hit = f32;
    type Prepared = T::Prepared;

    #[inline(always)]
    fn prepare(&self, ray: &Ray) -> Option<T::Prepared> {
        self.0.prepare(ray)
    }

    #[inline(always)]
    fn prepare_valid(&self, ray: &Ray) -> Option<T::Prepared> {
        self.0.prepare_valid(ray)
    }

    #[inline(always)]
    fn intersect(&mut self, pre: &T::Prepared, prim: u32, ray: &Ray) -> Option<(f32, f32)> {
        self.0.intersect(pre, prim, ray).map(|(t, _)| (t, t))
    }

    #[inline(always)]
    fn intersect_triangle<L: SimdLevel>(
        &mut self,
        inside: Inside,
        level: L,
        pre: &T::Prepared,
        prim: u32,
        v: &[Vec3; 3],
        ray: &Ray,
    ) -> Option<(f32, f32)> {
        self.0
            .intersect_triangle(inside, level, pre, prim, v, ray)
            .map(|(t, _)| (t, t))
    }

    #[inline(always)]
    fn certain_misses<L: SimdLevel>(
        &self,
        inside: Inside,
        level: L,
        pre: &T::Prepared,
        ray: &Ray,
        first: &TriangleLanes,
        second: Option<&TriangleLanes>,
    ) -> u32 {
        self.0
            .certain_misses(inside, level, pre, ray, first, second)
    }
}
