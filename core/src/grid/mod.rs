//! A uniform grid over a triangle mesh, built into caller storage and traversed with the
//! Amanatides–Woo 3-D DDA.
//!
//! * [`GridPlan::new`] reads a [`TriangleMesh`] (the same input as [`crate::bvh::Bvh`]) and
//!   decides the grid's box and resolution, and counts exactly the storage the build needs:
//!   [`GridPlan::required_offsets`] `u32` cell offsets (one per cell, plus one) and
//!   [`GridPlan::required_references`] `u32` triangle indices.
//! * [`Grid::build`] fills the caller's storage (`AsRef<[u32]> + AsMut<[u32]>`: `Vec<u32>`,
//!   `&mut [u32]`, `[u32; K]`); too-small storage is refused with a [`GridError`] before
//!   anything is written. Cell `c` holds `references[offsets[c]..offsets[c + 1]]`, in
//!   increasing triangle index. A plan may be reused after the vertices move, as long as
//!   every triangle stays inside the plan's box and the reference count is unchanged;
//!   anything else is a [`GridError`] ([`Grid::build`] lists the conditions).
//! * The queries of every structure ([`crate::query::RayQuery`]), with
//!   [`crate::query::Triangles`] (any [`TriangleIntersector`], prepared once per ray) or a
//!   closure, under the BVH's contract: `t` in `(t_min, t_max]`, of
//!   equal `t` the smaller triangle index. With the default [`crate::triangle::Watertight`]
//!   the closest hit **equals a brute-force loop** over all triangles (same triangle, same
//!   hit record) inside the watertight test's documented domain.
//!
//! # Resolution
//!
//! `λN` cells over the `N` usable triangles: with `V` the volume of the grid's box, the rule
//! `∛(λN/V)` cells per unit length gives `nᵢ = round(Lᵢ·∛(λN/V))` cells along an axis of
//! length `Lᵢ`, clamped to `1..=`[`GridOptions::max_cells_per_axis`] (at most
//! [`MAX_CELLS_PER_AXIS`]). Flat scenes: an axis of zero length (or too short for cells of
//! normal `f32` size, or infinite) gets one cell and the rule runs in the remaining
//! dimensions (`(λN/A)^(1/2)` per unit length on a plane, `λN/L` on a line); so does an axis
//! that would get less than one cell. `λ` is [`GridOptions::lambda`], default
//! [`DEFAULT_LAMBDA`].
//!
//! # Cell assignment
//!
//! Each triangle, **padded** by `pad` world units on every axis (below), is referenced in
//! every cell its box overlaps ([`CellAssignment::Bounds`]) or, by default, every cell the
//! padded triangle itself overlaps ([`CellAssignment::Exact`]: the separating-axis test in
//! `f64`, conservative). The first and last cell of each axis extend to infinity, so cells
//! partition space and a point just outside the grid's box belongs to a border cell. On the
//! bunny (69 451 triangles, default `λ = 3`, 65×64×50 cells) the exact test cuts the
//! references from 205 116 (2.95 per triangle) to 177 315 (2.55), printed by
//! `tests/tests/grid_vs_bruteforce.rs`; building exactly takes about 4× as long.
//!
//! # Box query
//!
//! [`RayQuery::query_box`](crate::query::RayQuery::query_box) reports every triangle whose
//! bounds overlap the query box, once, as the BVH does. A triangle whose box overlaps the
//! query shares a point with it, whose cell lies in the range of cells the triangle's
//! padded box touches and among the cells the query box touches (scanned with one more on
//! each side, for the rounding of the cell of a coordinate). Under
//! [`CellAssignment::Bounds`] that cell references the triangle, so the scan of the query's
//! cells finds it. Under [`CellAssignment::Exact`] the triangle may miss that cell (a query
//! in the empty corner of a large triangle's box), but every cell that references it lies
//! in its padded box's range, at most `sᵢ` cells from the shared point's cell on axis `i`,
//! where `sᵢ` is the most cells beyond the first that any triangle's padded box spans on
//! that axis (recorded at build time): the scan is widened by `sᵢ` on each side. A triangle
//! is reported in the first cell, in scan order, that references it. The cost: a grid
//! holding one triangle as wide as the scene scans every cell for every box query under
//! `Exact`; `Bounds` scans only the query's cells.
//!
//! # Traversal and the rule that ends it
//!
//! The walk runs in the grid's frame, relative to the centre `c` of its box: the ray's
//! origin `o − c` (one `f32` subtraction), the box, the cell planes and the padding, so that
//! every bound below is measured by the scene's size and the origin's distance from it,
//! wherever the scene lies (a mesh moved `10⁴` of its sizes from the coordinate origin gets
//! the cells and the padding it has at the origin). Below, `o` is `o − c` and `extent` the
//! largest coordinate magnitude of the box in that frame (about half its longest side).
//! The triangles are tested on the caller's ray.
//!
//! The ray is clipped to the grid's box (grown by the padding) with the conservative slab
//! test, and the DDA starts in the cell of the entry point (clamped). Each step computes the
//! distance to the next cell plane on every axis directly, `t = (min + m·size − o)/d`
//! (nothing accumulates), and moves along the axis of the nearest (ties: the lowest axis). A
//! `±0` direction component never steps; NaN/∞ rays ([`Ray::validate`]) return no hit.
//!
//! **Closest hit: "the hit must lie in the current cell".** All triangles of the visited
//! cells are tested against the running interval (the best hit shrinks `t_max`), keeping the
//! best by `t`, then by index; the walk ends after the first cell whose exit distance
//! `t_exit` satisfies `cull_bound(t_best) < t_exit` (the best hit lies in this or an earlier
//! cell, where [`crate::query::CULL_REL_SLACK`] pads `t_best` by 64 ulps), or once it leaves
//! the padded box. No mailbox: a triangle in several cells is tested again, which is harmless
//! (the same `t` never replaces itself). **Why this equals brute force:** a hit of the
//! watertight test at `t` means the exact ray point `o + t·d` lies within
//! `γ₁₆·(max|o| + extent)` of the triangle (the argument of
//! [`crate::tolerance::BVH_PROJECTION_PAD`]: the test's rounding is relative to the distance
//! `max|p − o|` from the origin to the triangle's points, at most `max|o| + extent` in any
//! frame), and the DDA's cell at parameter `t` lies within `γ₁₃·(max|o| + extent)` of that
//! point on each axis (the planes and the entry point carry a few roundings each, and `o − c`
//! one). Triangles are padded by [`GRID_RAY_PAD`] `·(reach + extent)` ≥
//! twice their sum, so a triangle hit at `t` is referenced in the cell the DDA visits at `t`:
//! a triangle not yet tested cannot hit before the current cell's exit.
//!
//! `reach` is `extent + `[`ORIGIN_REACH`]` × (longest side)`: rays starting farther out
//! need more padding than the build applied, and test the block of `r` neighbouring cells
//! around each DDA cell instead, with `r` covering the missing padding per axis. Each cell is
//! tested once: the block around the entry cell, then at each step only the layer of cells
//! the step adds to the block (the DDA moves one way along each axis, so a cell that leaves
//! the block never re-enters it).
//!
//! **Cost bound:** such a walk visits at most the first block plus one layer per step, with
//! at most `nᵢ − 1` steps along each axis the ray moves on. When that count reaches the
//! number of references (or of cells), the ray tests every reference once instead (brute
//! force in effect), as does a valid ray whose `o − c` overflows `f32`. A ray therefore
//! either makes that one pass or visits fewer cells than there are references and tests
//! each reference at most once: its work (cells visited plus triangles tested) is at most
//! twice a pass over every reference, however far its origin.
//!
//! **Step bound:** each step moves one axis one cell toward its end, so the DDA visits at
//! most `nx + ny + nz − 2` cells (a ray within `reach` visits only those); the loop is
//! bounded by that count. There is no stack.
//!
//! # Size
//!
//! `4·(cells + 1) + 4·references` bytes of caller storage
//! ([`RayQuery::bytes_used`](crate::query::RayQuery::bytes_used)); the vertices and triangles
//! are the caller's and are not counted. The bunny at the default `λ`
//! takes 22.2 bytes per triangle (the binary BVH 38.5).
//!
//! # Degenerate input
//!
//! An empty mesh (or one whose triangles were all excluded) gives a one-cell grid that hits
//! nothing. Zero-area triangles are assigned like any other (the intersectors never hit
//! them). Coordinates up to `f32::MAX` build (pads are capped at `f32::MAX`). A scene far from
//! the coordinate origin gets the cells and padding it would get at the origin (the grid's
//! frame).
//!
//! [`Ray::validate`]: crate::ray::Ray::validate
//! [`TriangleIntersector`]: crate::triangle::TriangleIntersector
//! [`TriangleMesh`]: crate::mesh::TriangleMesh

mod build;
mod error;
mod overlap;
mod plan;
mod query;
mod traverse;

#[cfg(test)]
mod tests;

pub use error::GridError;
pub use overlap::CellAssignment;
pub use plan::{GridOptions, GridPlan};

use crate::aabb::Aabb;
use crate::float::{gamma, gamma_f64};
use overlap::Layout;

/// Default [`GridOptions::lambda`]: cells per triangle. Unitless. With a triangle test costing
/// about two cell steps, the work per ray (cells visited + triangles tested, counted on the
/// bunny for λ from 1 to 8) is flat from λ = 3 to 8, and 3 takes the least memory there
/// (`docs/performance.md`).
pub const DEFAULT_LAMBDA: f32 = 3.0;

/// Largest number of cells along one axis (so at most 2³⁰ cells, whose offsets fit `u32`
/// indices and whose coordinates `m·size` are exact in `f32`).
pub const MAX_CELLS_PER_AXIS: u32 = 1024;

/// Largest number of triangles a grid can reference (indices are `u32`).
pub const MAX_TRIANGLES: usize = u32::MAX as usize;

/// Padding of the triangles relative to `max|o − c| + extent` in the grid's frame (`c` the
/// centre of the grid's box, `extent` the largest coordinate magnitude of the box relative to
/// it, about half its longest side; module docs). Unit: relative; the padding is
/// `GRID_RAY_PAD·(|o − c| + extent)` world units. Why: the watertight test's hit point is
/// within `γ₁₆·(|o − c| + extent)` of the triangle ([`crate::tolerance::BVH_PROJECTION_PAD`]:
/// its rounding is relative to `max|p − o|`) and the DDA's cell planes (`min + m·size`, a
/// product and a sum, then the distance: a subtraction and a division) and its entry cell
/// (`o + t·d`, then a subtraction and a division) are each within `γ₁₂·(|o − c| + extent)` of
/// exact along each axis, and `o − c` within `u·|o − c|`; `γ₆₄` is more than twice their
/// sum, which also covers the rounding of the padding itself.
pub const GRID_RAY_PAD: f32 = gamma(64);

/// Absolute floor added to every padding, world units: the smallest normal `f32`. Below the
/// normal range rounding is absolute (at most `2⁻¹⁵⁰` per operation), which relative bounds
/// miss; a few dozen operations stay far below this floor.
pub const GRID_ABS_PAD: f32 = f32::MIN_POSITIVE;

/// How far ray origins may be from the grid's centre, in multiples of the grid's longest side
/// beyond its extent, and still be covered by the padding applied at build time (unitless).
/// 16 covers cameras framing the scene from a few diameters; it costs a padding of
/// `GRID_RAY_PAD·(2·extent + 16·side) ≈ 7·10⁻⁵·side` on each triangle, a fraction of a cell
/// (at most `1/1024` of the side: [`MAX_CELLS_PER_AXIS`]).
pub const ORIGIN_REACH: f32 = 16.0;

/// Relative slack of the `f64` assignment (separating-axis projections and cell ranges):
/// unit relative to the magnitudes involved. Each projection rounds a handful of times in
/// `f64` (`u = 2⁻⁵³`); `γ₃₂` bounds them all, so the test never separates a triangle from a
/// cell it touches. Its cost, ~10⁻¹⁵ of the coordinates, is nothing next to the padding.
pub const SAT_SLACK_REL: f64 = gamma_f64(32);

/// A uniform grid over caller storage `O` (cell offsets) and `R` (triangle references).
///
/// Only the first [`Grid::cell_count`]` + 1` offsets and [`Grid::reference_count`]
/// references are used. Queries take the mesh the grid was built over; another mesh gives
/// answers about that mesh's triangles by index, which mean nothing.
#[derive(Clone, Debug)]
pub struct Grid<O, R> {
    offsets: O,
    references: R,
    layout: Layout,
    triangle_count: usize,
    source_len: usize,
    reference_count: usize,
    /// Cells a box query scans beyond the query's own on each side, per axis (module docs,
    /// "Box query"): 0 under [`CellAssignment::Bounds`], under [`CellAssignment::Exact`] the
    /// most cells beyond the first that a triangle's padded box spans on that axis.
    box_reach: [u32; 3],
}

impl<O, R> Grid<O, R>
where
    O: AsRef<[u32]>,
    R: AsRef<[u32]>,
{
    overlap::layout_accessors!();

    /// The padding applied to every triangle at build time, world units.
    #[must_use]
    pub fn padding(&self) -> f32 {
        self.layout.pad
    }

    /// Triangles in the grid (the mesh's minus excluded ones).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// Number of triangles the mesh had at build time.
    #[must_use]
    pub fn source_len(&self) -> usize {
        self.source_len
    }

    /// Cell references in use.
    #[must_use]
    pub fn reference_count(&self) -> usize {
        self.reference_count
    }

    /// The used offsets (`cell_count + 1`, non-decreasing, the last equal to the reference
    /// count).
    #[must_use]
    pub fn offsets(&self) -> &[u32] {
        crate::storage::used(self.offsets.as_ref(), self.cell_count() + 1)
    }

    /// The used references.
    #[must_use]
    pub fn references(&self) -> &[u32] {
        crate::storage::used(self.references.as_ref(), self.reference_count)
    }

    /// The triangles of cell `(i, j, k)`, in increasing index; empty when out of range.
    #[must_use]
    pub fn cell(&self, cell: [u32; 3]) -> &[u32] {
        if (0..3).any(|a| cell[a] >= self.layout.n[a]) {
            return &[];
        }
        self.cell_by_id(self.layout.cell_id(cell))
    }

    /// The triangles of the cell with linear index `id` (empty when out of range).
    #[inline(always)]
    fn cell_by_id(&self, id: usize) -> &[u32] {
        let offsets = self.offsets.as_ref();
        let (Some(&a), Some(&b)) = (offsets.get(id), offsets.get(id.wrapping_add(1))) else {
            return &[];
        };
        self.references
            .as_ref()
            .get(a as usize..b as usize)
            .unwrap_or(&[])
    }

    /// Gives the storage back.
    #[must_use]
    pub fn into_storage(self) -> (O, R) {
        (self.offsets, self.references)
    }
}
