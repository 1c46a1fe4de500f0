//! Closest-hit and any-hit queries: the Amanatides–Woo DDA with the "hit must lie in the
//! current cell" rule (module docs of [`super`]).

use super::Grid;
use super::overlap::ray_pad;
use crate::aabb::{Aabb, SlabRay};
use crate::query::forward::{ClosureWalk, PrimTest, Search};
use crate::query::walk::cull_bound;
use crate::ray::Ray;
use glam::Vec3;

impl<O, R> ClosureWalk for Grid<O, R>
where
    O: AsRef<[u32]>,
    R: AsRef<[u32]>,
{
    fn traverse<F: PrimTest<H>, H>(&self, ray: &Ray, s: &mut Search<F, H>) {
        if self.reference_count == 0 || !ray.is_valid() {
            return;
        }
        let l = &self.layout;
        // The walk runs in the grid's frame (module docs of `overlap`); the triangles are
        // tested on the caller's ray. An `o − c` that overflows gives `o_mag = ∞`: beyond
        // every reach, every reference once (below).
        let local = Ray {
            origin: l.local_point(ray.origin),
            ..*ray
        };
        let o_mag = local.origin.abs().max_element();
        let near = o_mag <= l.reach;
        let pad = if near {
            l.pad
        } else {
            ray_pad(o_mag, l.extent)
        };
        // Cells around each DDA cell that cover the padding the build did not apply: a
        // point within `pad` of a triangle lies in a cell at most ⌊pad/size⌋ + 1 away from
        // one of the triangle's own cells (clamped border cells only shorten that).
        let radius = [0, 1, 2].map(|a| {
            if near || l.n[a] <= 1 {
                0
            } else {
                // `as` saturates (∞ → u32::MAX).
                ((pad / l.size[a]) as u32).saturating_add(2)
            }
        });
        let block = radius
            .iter()
            .fold(1u64, |b, &r| b.saturating_mul(2 * u64::from(r) + 1));
        if block >= self.cell_count() as u64 {
            // The block would hold every cell: test every reference once.
            s.test(self.references());
            s.stats.nodes_visited = self.cell_count() as u64;
        } else if let Some(slab) = SlabRay::new(&local) {
            self.walk(&slab, &local, pad.max(l.pad), radius, s);
        }
    }
}

impl<O, R> Grid<O, R>
where
    O: AsRef<[u32]>,
    R: AsRef<[u32]>,
{
    /// The DDA of `ray` (in the grid's frame; `slab` its slab form) from the entry into the
    /// grid's box grown by `clip`, testing the block of `radius` cells around each cell it
    /// visits, until the rule of the module docs ends it.
    fn walk<F: PrimTest<H>, H>(
        &self,
        slab: &SlabRay,
        ray: &Ray,
        clip: f32,
        radius: [u32; 3],
        s: &mut Search<F, H>,
    ) {
        let l = &self.layout;
        let grown = Aabb::new(l.local.min - clip, l.local.max + clip);
        let Some((t0, t_end)) = grown.intersect_slab(slab, ray.t_min, ray.t_max) else {
            return;
        };
        let (o, d) = (ray.origin, ray.direction);
        let mut cell = [0, 1, 2].map(|a| {
            let x = if d[a] == 0.0 { o[a] } else { o[a] + t0 * d[a] };
            l.cell_of(a, x)
        });
        // Each step moves one axis one cell toward its end: fewer steps than this.
        let steps = l.n.iter().map(|&k| k as usize).sum::<usize>();
        for _ in 0..steps {
            let mut t_exit = f32::INFINITY;
            let mut axis = 3;
            for (a, &i) in cell.iter().enumerate() {
                let t = self.crossing(a, i, o, d);
                if t < t_exit {
                    t_exit = t;
                    axis = a;
                }
            }
            if self.visit_block(cell, radius, s) {
                return;
            }
            // The hit lies in this cell (or an earlier one), or the ray has left the box.
            if axis == 3 || !(t_exit <= t_end) || cull_bound(s.cur.t_max) < t_exit {
                return;
            }
            if let Some(c) = cell.get_mut(axis) {
                *c = if d[axis] > 0.0 {
                    c.saturating_add(1)
                } else {
                    c.saturating_sub(1)
                };
            }
        }
    }

    /// Distance along the ray to the plane that leaves cell index `i` on axis `a`; `+∞` when
    /// the ray does not move along `a` (`±0`) or the cell is the last one that way.
    #[inline(always)]
    fn crossing(&self, a: usize, i: u32, o: Vec3, d: Vec3) -> f32 {
        let l = &self.layout;
        let da = d[a];
        let plane = if da > 0.0 && i + 1 < l.n[a] {
            l.plane(a, i + 1)
        } else if da < 0.0 && i > 0 {
            l.plane(a, i)
        } else {
            return f32::INFINITY;
        };
        (plane - o[a]) / da
    }

    /// Tests every cell within `radius` of `cell` (clamped); `true` when the query is done.
    fn visit_block<F: PrimTest<H>, H>(
        &self,
        cell: [u32; 3],
        radius: [u32; 3],
        s: &mut Search<F, H>,
    ) -> bool {
        let n = self.layout.n;
        let lo = [0, 1, 2].map(|a| cell[a].saturating_sub(radius[a]));
        let hi = [0, 1, 2].map(|a| cell[a].saturating_add(radius[a]).min(n[a] - 1));
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    s.stats.nodes_visited += 1;
                    if s.test(self.cell_by_id(self.layout.cell_id([i, j, k]))) {
                        return true;
                    }
                }
            }
        }
        false
    }
}
