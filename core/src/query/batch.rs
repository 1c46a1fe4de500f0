//! The default walk of ray batches ([`super::RayQuery::closest_hits`] and
//! [`super::RayQuery::any_hits`], for the structures without a packet walk): each chunk of
//! [`BATCH_CHUNK`] consecutive rays is walked in a coherent order — by direction octant, then the Morton code of the origin's cell within the chunk's origin
//! bounds, then the Morton code of the direction's cell — and each answer is written at its
//! ray's own index. Every ray is walked alone, by the structure's single-ray query with the
//! caller's context, so each answer **is** the single-ray answer: closest hits bit for bit,
//! any hits the same primitive and payload, for these structures (the order changes which ray is walked when, never
//! how). The reordering only changes which nodes and triangles are warm in the cache.
//!
//! Allocation-free: the order of a chunk is sorted in a fixed array of [`BATCH_CHUNK`] `u64`
//! keys (2 KiB) in the call's frame; nothing comes from the caller but the rays and the
//! output.
//!
//! ```
//! use halfray_core::prelude::*;
//! use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, index_capacity, node_capacity};
//! use halfray_core::mesh::TriangleMesh;
//! use halfray_core::query::{Query, QueryStack, Triangles};
//! use halfray_core::triangle::{TriangleHit, Watertight};
//! use halfray_core::{Ray, Vec3};
//!
//! let positions = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
//! let mesh = TriangleMesh::new(&positions, &[[0, 1, 2]]);
//! let (mut nodes, mut indices) = ([BvhNode::EMPTY; node_capacity(1)], [0u32; index_capacity(1)]);
//! let bvh = Bvh::build(&mesh, &mut nodes[..], &mut indices[..], &BuildOptions::default()).unwrap();
//! let rays = [Ray::new(Vec3::ZERO, Vec3::Z), Ray::new(Vec3::ZERO, -Vec3::Z)];
//! let mut out: [Option<(u32, TriangleHit)>; 2] = [None; 2];
//! let mut stack = QueryStack::new();
//! let mut tris = Triangles::new(&mesh, &Watertight);
//! bvh.closest_hits(&rays, &mut tris, &mut Query::new().stack(&mut stack), &mut out).unwrap();
//! assert_eq!(out[0].map(|(p, h)| (p, h.t)), Some((0, 2.0)));
//! assert!(out[1].is_none());
//! ```

use crate::query::QueryError;
use crate::ray::Ray;
use glam::Vec3;

/// Rays reordered together: a batch is cut into chunks of this many consecutive rays, each
/// sorted on its own (the sort keys live in a `[u64; BATCH_CHUNK]`, 2 KiB of stack).
pub const BATCH_CHUNK: usize = 256;

/// Cells per axis of the origin and direction grids of the sort key (4 bits per axis).
const CELLS: u32 = 16;

/// `Ok` when a batch of `rays` rays has `out` answers, else [`QueryError::LengthMismatch`].
#[inline(always)]
pub(crate) fn same_length(rays: usize, out: usize) -> Result<(), QueryError> {
    if out == rays {
        Ok(())
    } else {
        Err(QueryError::LengthMismatch {
            expected: rays,
            found: out,
        })
    }
}

/// Calls `answer` on every ray, chunk by chunk in [`chunk_order`], writing `out[i]` for
/// `rays[i]`. [`QueryError::LengthMismatch`] (nothing written) when the lengths differ.
#[inline(always)]
pub(super) fn in_coherent_order<O>(
    rays: &[Ray],
    out: &mut [O],
    mut answer: impl FnMut(&Ray) -> O,
) -> Result<(), QueryError> {
    same_length(rays.len(), out.len())?;
    let mut keys = [0u64; BATCH_CHUNK];
    for (chunk, out) in rays.chunks(BATCH_CHUNK).zip(out.chunks_mut(BATCH_CHUNK)) {
        for &key in chunk_order(chunk, &mut keys) {
            // The low 32 bits of a key are the ray's index in its chunk (< BATCH_CHUNK).
            let i = (key & 0xFFFF_FFFF) as usize;
            if let (Some(ray), Some(o)) = (chunk.get(i), out.get_mut(i)) {
                *o = answer(ray);
            }
        }
    }
    Ok(())
}

/// The walking order of `chunk` (at most [`BATCH_CHUNK`] rays): its keys sorted, each
/// `(octant << 24 | origin cell << 12 | direction cell) << 32 | index`, so equal cells keep
/// the caller's order. Any ray gets a key (NaN and infinite values fall into an edge cell);
/// the key decides only the order.
fn chunk_order<'k>(chunk: &[Ray], keys: &'k mut [u64; BATCH_CHUNK]) -> &'k [u64] {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for r in chunk {
        // `min`/`max` skip NaN; infinities widen the bounds and only coarsen the cells.
        (lo, hi) = (lo.min(r.origin), hi.max(r.origin));
    }
    // Empty extents (one origin for all rays, as a camera's) map every origin to cell 0.
    let scale = Vec3::splat(CELLS as f32) / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let n = chunk.len().min(BATCH_CHUNK);
    for (i, (r, key)) in chunk.iter().zip(keys.iter_mut()).enumerate() {
        let d = r.direction;
        let octant = u32::from(d.x < 0.0) | u32::from(d.y < 0.0) << 1 | u32::from(d.z < 0.0) << 2;
        let origin = morton3(cells((r.origin - lo) * scale));
        // The direction scaled to the unit cube by its largest component, shifted to [0, 2].
        let unit = d / d.abs().max_element() + Vec3::ONE;
        let direction = morton3(cells(unit * (CELLS as f32 / 2.0)));
        let cell = octant << 24 | origin << 12 | direction;
        *key = u64::from(cell) << 32 | i as u64;
    }
    let keys = &mut keys[..n];
    keys.sort_unstable();
    keys
}

/// Each coordinate as a cell index in `0..CELLS` (`as` maps NaN to 0 and saturates).
fn cells(v: Vec3) -> [u32; 3] {
    [v.x, v.y, v.z].map(|c| (c as u32).min(CELLS - 1))
}

/// The 3D Morton code of three 4-bit cell indices (12 bits, x in the lowest).
fn morton3(c: [u32; 3]) -> u32 {
    let mut code = 0;
    for bit in 0..4 {
        for (axis, &v) in c.iter().enumerate() {
            code |= ((v >> bit) & 1) << (3 * bit + axis);
        }
    }
    code
}

#[cfg(test)]
mod tests;
