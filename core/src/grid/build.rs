//! Filling the caller's storage: a counting pass into the offsets, a prefix sum, and a
//! scatter pass into the references (triangles in index order, so every cell's list is
//! sorted), without allocation or recursion.

use super::overlap::{CellAssignment, for_each_cell};
use super::plan::usable_triangle;
use super::{Grid, GridError, GridPlan};
use crate::error::{CapacityError, Storage};
use crate::mesh::TriangleMesh;

impl<O, R> Grid<O, R>
where
    O: AsRef<[u32]> + AsMut<[u32]>,
    R: AsRef<[u32]> + AsMut<[u32]>,
{
    /// Builds the grid `plan` describes over `mesh` into `offsets` (at least
    /// [`GridPlan::required_offsets`]) and `references` (at least
    /// [`GridPlan::required_references`]).
    ///
    /// `mesh` is the mesh the plan was made for, or one whose vertices have moved since
    /// (a plan reused across animation steps) provided that it has the same triangles, the
    /// same number of them usable, every usable triangle's box inside the plan's box
    /// ([`GridPlan::bounds`]), and the same reference count under the plan's cells. Such a
    /// mesh gets a grid with every guarantee of one planned for it (the plan's resolution
    /// and padding; triangles are assigned by their new vertices); any other is refused
    /// below.
    ///
    /// # Errors
    ///
    /// Before anything is written: [`GridError::Capacity`] (offsets or references), and
    /// [`GridError::PlanMismatch`] when `mesh` has a different triangle count than the
    /// plan's. After the counting pass has written the offsets (the references untouched):
    /// [`GridError::TriangleOutsidePlan`] for the first usable triangle whose box is not
    /// inside the plan's box, then [`GridError::PlanMismatch`] when `mesh` has a different
    /// number of usable triangles than the plan counted ([`GridPlan::triangle_count`]) or
    /// its vertices give a different reference count.
    pub fn build(
        mesh: &TriangleMesh<'_>,
        plan: &GridPlan,
        mut offsets: O,
        mut references: R,
    ) -> Result<Self, GridError> {
        let cells = plan.layout.cell_count();
        let refs = plan.reference_count;
        if mesh.len() != plan.source_len {
            return Err(GridError::PlanMismatch {
                expected: plan.source_len,
                found: mesh.len(),
            });
        }
        let off_len = offsets.as_ref().len();
        CapacityError::check(Storage::GridOffsets, cells + 1, off_len)?;
        let ref_len = references.as_ref().len();
        CapacityError::check(Storage::GridReferences, refs, ref_len)?;
        let off = offsets.as_mut().get_mut(..=cells).unwrap_or(&mut []);
        let dst = references.as_mut().get_mut(..refs).unwrap_or(&mut []);
        let box_reach = fill(mesh, plan, off, dst)?;
        Ok(Self {
            offsets,
            references,
            layout: plan.layout,
            triangle_count: plan.triangle_count,
            source_len: plan.source_len,
            reference_count: refs,
            box_reach,
        })
    }
}

/// The three passes into `off` (exactly `cells + 1` entries) and `dst` (exactly the plan's
/// reference count), after checking in the first that `mesh` fits the plan (see
/// [`Grid::build`]). Counts fit `u32`: the plan checked the total. Returns the grid's
/// `box_reach`: 0 per axis under [`CellAssignment::Bounds`], under
/// [`CellAssignment::Exact`] the most cells beyond the first that a triangle's padded box
/// spans on that axis.
fn fill(
    mesh: &TriangleMesh<'_>,
    plan: &GridPlan,
    off: &mut [u32],
    dst: &mut [u32],
) -> Result<[u32; 3], GridError> {
    let layout = &plan.layout;
    // 1. Count cell `c`'s references into `off[c + 1]`, checking each triangle against the
    //    plan's box: cells partition space, so a triangle outside it would still be counted
    //    (in border cells), but rays are clipped to the box and would never reach it.
    off.fill(0);
    let (mut total, mut usable) = (0usize, 0usize);
    let mut reach = [0u32; 3];
    for i in 0..mesh.len() {
        let Some((v, b)) = usable_triangle(mesh, i) else {
            continue;
        };
        if !(layout.bounds.contains_point(b.min) && layout.bounds.contains_point(b.max)) {
            return Err(GridError::TriangleOutsidePlan { triangle: i });
        }
        usable += 1;
        let span = for_each_cell(layout, &v, plan.assignment, |c| {
            if let Some(slot) = off.get_mut(c + 1) {
                *slot = slot.saturating_add(1);
                total += 1;
            }
        });
        if plan.assignment == CellAssignment::Exact {
            for (r, (lo, hi)) in reach.iter_mut().zip(span) {
                *r = (*r).max(hi.saturating_sub(lo));
            }
        }
    }
    for (expected, found) in [(plan.triangle_count, usable), (dst.len(), total)] {
        if found != expected {
            return Err(GridError::PlanMismatch { expected, found });
        }
    }
    // 2. Prefix sum: `off[c]` = start of cell `c`.
    let mut sum = 0u32;
    for o in off.iter_mut() {
        sum = sum.saturating_add(*o);
        *o = sum;
    }
    // 3. Scatter with `off[c]` as cell `c`'s cursor, which ends at the start of `c + 1`…
    for i in 0..mesh.len() {
        if let Some((v, _)) = usable_triangle(mesh, i) {
            for_each_cell(layout, &v, plan.assignment, |c| {
                if let Some(cursor) = off.get_mut(c) {
                    if let Some(slot) = dst.get_mut(*cursor as usize) {
                        *slot = i as u32;
                    }
                    *cursor = cursor.saturating_add(1);
                }
            });
        }
    }
    // …so shifting every entry up by one restores the starts.
    let n = off.len();
    off.copy_within(..n.saturating_sub(1), 1);
    if let Some(first) = off.first_mut() {
        *first = 0;
    }
    Ok(reach)
}
