//! The box query and the [`RayQuery`] implementation of the grid.

use super::Grid;
use crate::aabb::Aabb;
use crate::mesh::PrimitiveSource;
use crate::query::RayQuery;
use crate::query::forward::{ClosureWalk, ray_queries};

impl<O, R> RayQuery for Grid<O, R>
where
    O: AsRef<[u32]>,
    R: AsRef<[u32]>,
{
    ray_queries!(
        #[inline]
        leaf_query
    );

    /// Visits the cells the box touches (one more on each side, for the rounding of the cell
    /// of a coordinate), widened by the grid's box reach on each axis (module docs, "Box
    /// query"), and reports a triangle whose bounds overlap `query` in the first of them, in
    /// scan order, that references it.
    fn query_box<P: PrimitiveSource + ?Sized>(
        &self,
        source: &P,
        query: &Aabb,
        mut found: impl FnMut(u32) -> bool,
    ) -> usize {
        if !query.is_valid() || self.reference_count == 0 {
            return 0;
        }
        let (lo, hi) = self.cells_touching(&query.relative_to(self.layout.centre));
        let s = self.box_reach;
        let lo = [0, 1, 2].map(|a| lo[a].saturating_sub(s[a]));
        let hi = [0, 1, 2].map(|a| hi[a].saturating_add(s[a]).min(self.layout.n[a] - 1));
        let mut reported = 0;
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    for &p in self.cell_by_id(self.layout.cell_id([i, j, k])) {
                        let b = source.primitive_bounds(p as usize);
                        if !b.overlaps(query) || self.first_holder(p, &b, (lo, hi)) != [i, j, k] {
                            continue;
                        }
                        reported += 1;
                        if !found(p) {
                            return reported;
                        }
                    }
                }
            }
        }
        reported
    }

    fn primitive_count(&self) -> usize {
        self.triangle_count
    }

    /// `4·(cells + 1) + 4·references`.
    fn bytes_used(&self) -> usize {
        4 * (self.cell_count() + 1 + self.reference_count)
    }
}

impl<O, R> Grid<O, R>
where
    O: AsRef<[u32]>,
    R: AsRef<[u32]>,
{
    /// The cells (lowest and highest per axis, clamped) that the closed box `b` touches, one
    /// more on each side; `b` in the grid's frame (a world box taken there by
    /// [`Aabb::relative_to`], outward: it still holds every point of the box).
    fn cells_touching(&self, b: &Aabb) -> ([u32; 3], [u32; 3]) {
        let l = &self.layout;
        let lo = [0, 1, 2].map(|a| l.cell_of(a, b.min[a]).saturating_sub(1));
        let hi = [0, 1, 2].map(|a| l.cell_of(a, b.max[a]).saturating_add(1).min(l.n[a] - 1));
        (lo, hi)
    }

    /// The first cell, in the box query's scan order over the cells `(lo, hi)`, that
    /// references triangle `p` (bounds `b`, world coordinates): only the cells its padded box
    /// touches can.
    /// `[u32::MAX; 3]` for none.
    fn first_holder(&self, p: u32, b: &Aabb, (lo, hi): ([u32; 3], [u32; 3])) -> [u32; 3] {
        let pad = self.layout.pad;
        let b = b.relative_to(self.layout.centre);
        let (plo, phi) = self.cells_touching(&Aabb::new(b.min - pad, b.max + pad));
        let lo = [0, 1, 2].map(|a| lo[a].max(plo[a]));
        let hi = [0, 1, 2].map(|a| hi[a].min(phi[a]));
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    // Cells list their triangles in increasing index.
                    if self
                        .cell_by_id(self.layout.cell_id([i, j, k]))
                        .binary_search(&p)
                        .is_ok()
                    {
                        return [i, j, k];
                    }
                }
            }
        }
        [u32::MAX; 3]
    }
}
