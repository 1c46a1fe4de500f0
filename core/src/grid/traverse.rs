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
        let cells = self.cell_count() as u64;
        // A far ray's walk visits each cell at most once, but up to `visits` of them: when
        // that reaches the references a pass over all of them tests (or the cells), that
        // pass costs no more (module docs, "Cost bound").
        let visits = self.visits_bound(radius, local.direction);
        let costly = !near && visits >= cells.min(self.reference_count as u64);
        if block >= cells || costly {
            // Every reference once (a block over the whole grid, or the cost bound).
            s.test(self.references());
            s.stats.nodes_visited = cells;
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
    /// visits, until the rule of the module docs ends it. Each cell is tested once: the
    /// block around the entry cell, then at each step only the face that the step adds to
    /// the block (the DDA's cell moves one way along each axis, so a cell that leaves the
    /// block never re-enters it).
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
        let mut fresh = self.block(cell, radius);
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
            if self.visit_cells(fresh, s) {
                return;
            }
            // The hit lies in this cell (or an earlier one), or the ray has left the box.
            if axis == 3 || !(t_exit <= t_end) || cull_bound(s.cur.t_max) < t_exit {
                return;
            }
            let (n, r) = (l.n[axis], radius[axis]);
            // Only the layer that the step adds to the block: `r` cells ahead of the new
            // cell, when that is still in the grid.
            let ahead = if d[axis] > 0.0 {
                cell[axis] = cell[axis].saturating_add(1);
                cell[axis].checked_add(r).filter(|&x| x < n)
            } else {
                cell[axis] = cell[axis].saturating_sub(1);
                cell[axis].checked_sub(r)
            };
            fresh = self.block(cell, radius);
            let (lo, hi) = (&mut fresh.0, &mut fresh.1);
            (lo[axis], hi[axis]) = ahead.map_or((1, 0), |x| (x, x));
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

    /// The cells within `radius` of `cell` on every axis, clamped to the grid: the lowest and
    /// the highest index per axis.
    #[inline(always)]
    fn block(&self, cell: [u32; 3], radius: [u32; 3]) -> ([u32; 3], [u32; 3]) {
        let n = self.layout.n;
        let lo = [0, 1, 2].map(|a| cell[a].saturating_sub(radius[a]));
        let hi = [0, 1, 2].map(|a| cell[a].saturating_add(radius[a]).min(n[a] - 1));
        (lo, hi)
    }

    /// At most how many cells `walk` visits with blocks of `radius` along direction
    /// `d`: the block around the entry cell, then one face of the block for each step, and
    /// the ray steps at most `n − 1` times along each axis it moves on (saturating).
    fn visits_bound(&self, radius: [u32; 3], d: Vec3) -> u64 {
        let n = self.layout.n;
        let side = |a: usize| (2 * u64::from(radius[a]) + 1).min(u64::from(n[a]));
        let block = side(0).saturating_mul(side(1)).saturating_mul(side(2));
        (0..3).filter(|&a| d[a] != 0.0).fold(block, |sum, a| {
            let face = side((a + 1) % 3).saturating_mul(side((a + 2) % 3));
            sum.saturating_add(u64::from(n[a] - 1).saturating_mul(face))
        })
    }

    /// Tests every cell of the box `lo..=hi` (per axis; empty when `lo > hi` on an axis);
    /// `true` when the query is done.
    fn visit_cells<F: PrimTest<H>, H>(
        &self,
        (lo, hi): ([u32; 3], [u32; 3]),
        s: &mut Search<F, H>,
    ) -> bool {
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
