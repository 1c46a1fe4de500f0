//! Planning a grid: bounds, resolution (`∛(λN/V)`), padding and the exact storage it needs.

use super::overlap::{CellAssignment, Layout, for_each_cell};
use super::{DEFAULT_LAMBDA, GridError, MAX_CELLS_PER_AXIS, MAX_TRIANGLES};
use crate::aabb::Aabb;
use crate::error::{InputElement, NonFiniteError};
use crate::mesh::{Primitive, TriangleMesh};
use glam::Vec3;

/// Options of [`GridPlan::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridOptions {
    /// Cells per triangle, `λ` of the resolution rule `∛(λN/V)` cells per unit length
    /// (module docs). Unitless. A value that is not positive and finite counts as
    /// [`DEFAULT_LAMBDA`].
    pub lambda: f32,
    /// Largest number of cells along one axis, clamped to `1..=`[`MAX_CELLS_PER_AXIS`].
    /// Default [`MAX_CELLS_PER_AXIS`].
    pub max_cells_per_axis: u32,
    /// Bounding-box or exact triangle–box cell assignment. Default [`CellAssignment::Exact`].
    pub assignment: CellAssignment,
    /// `false` (default): a triangle with a non-finite vertex or an out-of-range vertex index
    /// is an error ([`GridError::NonFinite`]). `true`: such triangles are left out of
    /// the grid (no query ever reports them).
    pub exclude_non_finite: bool,
}

impl Default for GridOptions {
    fn default() -> Self {
        Self {
            lambda: DEFAULT_LAMBDA,
            max_cells_per_axis: MAX_CELLS_PER_AXIS,
            assignment: CellAssignment::Exact,
            exclude_non_finite: false,
        }
    }
}

impl GridOptions {
    /// [`GridOptions::lambda`], the default in place of a value that is not positive and
    /// finite.
    fn cells_per_triangle(&self) -> f64 {
        let l = self.lambda;
        f64::from(if l > 0.0 && l.is_finite() {
            l
        } else {
            DEFAULT_LAMBDA
        })
    }
}

/// Everything a build needs to know before touching storage: the grid's box, resolution and
/// padding, and the exact number of offsets and references ([`GridPlan::required_offsets`],
/// [`GridPlan::required_references`]) for the caller to allocate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPlan {
    pub(super) layout: Layout,
    pub(super) assignment: CellAssignment,
    pub(super) source_len: usize,
    pub(super) triangle_count: usize,
    pub(super) reference_count: usize,
}

/// The vertices of triangle `i` and their box when they are usable (in range and finite).
#[inline]
pub(super) fn usable_triangle(mesh: &TriangleMesh<'_>, i: usize) -> Option<([Vec3; 3], Aabb)> {
    let v = mesh.triangle(i)?;
    let b = Primitive::bounds(&v);
    (b.is_finite() && b.is_valid()).then_some((v, b))
}

impl GridPlan {
    /// Plans a grid over `mesh`: one pass for the bounds (and the non-finite check), one pass
    /// assigning every triangle to its cells to count the references. Nothing is written.
    ///
    /// # Errors
    ///
    /// [`GridError::TooManyTriangles`] (more than [`MAX_TRIANGLES`]),
    /// [`GridError::NonFinite`] for the first unusable triangle unless
    /// [`GridOptions::exclude_non_finite`] is set, and [`GridError::TooManyReferences`] when
    /// the references or the cells overflow `u32`.
    pub fn new(mesh: &TriangleMesh<'_>, options: &GridOptions) -> Result<Self, GridError> {
        let n = mesh.len();
        if n > MAX_TRIANGLES {
            return Err(GridError::TooManyTriangles { count: n });
        }
        let mut bounds = Aabb::EMPTY;
        let mut usable = 0usize;
        for i in 0..n {
            match usable_triangle(mesh, i) {
                Some((_, b)) => {
                    bounds = bounds.union(b);
                    usable += 1;
                }
                None if options.exclude_non_finite => {}
                None => {
                    return Err(GridError::NonFinite(NonFiniteError::new(
                        InputElement::Triangle,
                        i,
                    )));
                }
            }
        }
        let resolution = resolution(&bounds, usable, options);
        let layout = Layout::new(&bounds, resolution);
        let cells = layout.cell_count();
        if cells >= u32::MAX as usize {
            return Err(GridError::TooManyReferences { count: cells });
        }
        // Counted in `u64`: on a 32-bit target a `usize` count would wrap before the check.
        let mut refs = 0u64;
        for i in 0..n {
            if let Some((v, _)) = usable_triangle(mesh, i) {
                for_each_cell(&layout, &v, options.assignment, |_| refs += 1);
            }
        }
        let refs = match u32::try_from(refs) {
            Ok(r) => r as usize,
            Err(_) => {
                let count = usize::try_from(refs).unwrap_or(usize::MAX);
                return Err(GridError::TooManyReferences { count });
            }
        };
        Ok(Self {
            layout,
            assignment: options.assignment,
            source_len: n,
            triangle_count: usable,
            reference_count: refs,
        })
    }

    /// Offsets the build needs: one per cell plus one (`u32` each).
    #[must_use]
    pub fn required_offsets(&self) -> usize {
        self.layout.cell_count() + 1
    }

    /// Triangle references the build needs (`u32` each): the sum over cells of the triangles
    /// assigned to each.
    #[must_use]
    pub fn required_references(&self) -> usize {
        self.reference_count
    }

    /// Bytes of caller storage the build needs: `4·(offsets + references)`, or `usize::MAX`
    /// where that does not fit in a `usize` (on a 32-bit target: storage no caller can have).
    #[must_use]
    pub fn required_bytes(&self) -> usize {
        self.required_offsets()
            .saturating_add(self.reference_count)
            .saturating_mul(4)
    }

    super::overlap::layout_accessors!();

    /// Usable triangles (the mesh's minus excluded ones).
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// The cell assignment the plan counted with.
    #[must_use]
    pub fn assignment(&self) -> CellAssignment {
        self.assignment
    }
}

/// Cells per axis for `count` triangles in `bounds` (module docs, "Resolution"): `λN` cells
/// spread over the axes of non-zero extent in proportion to their lengths; an axis that
/// would get less than one cell is made flat (one cell) and the others are recomputed
/// without it. In `f64`, so no product of extents overflows or underflows.
fn resolution(bounds: &Aabb, count: usize, options: &GridOptions) -> [u32; 3] {
    let max = options.max_cells_per_axis.clamp(1, MAX_CELLS_PER_AXIS);
    let mut n = [1u32; 3];
    if count == 0 || !bounds.is_finite() || !bounds.is_valid() {
        return n;
    }
    let cells = options.cells_per_triangle() * count as f64;
    let len = |a: usize| f64::from(bounds.max[a]) - f64::from(bounds.min[a]);
    let mut active = [0usize, 1, 2].map(|a| Layout::can_split(bounds, a));
    // Each round either finishes or drops one axis: at most three rounds.
    for _ in 0..3 {
        let dims = active.iter().filter(|&&a| a).count();
        if dims == 0 {
            return [1; 3];
        }
        // Density of cells per unit length: (λN / Π lengths)^(1/dims).
        let prod: f64 = (0..3).filter(|&a| active[a]).map(len).product();
        let density = libm::pow(cells / prod, 1.0 / dims as f64);
        let per_axis = [0, 1, 2].map(|a| if active[a] { len(a) * density } else { 1.0 });
        // The shortest active axis below one cell becomes flat.
        let thin = (0..3)
            .filter(|&a| active[a] && !(per_axis[a] >= 1.0))
            .min_by(|&a, &b| per_axis[a].total_cmp(&per_axis[b]));
        match thin {
            Some(a) => active[a] = false,
            None => {
                for a in 0..3 {
                    // `as` saturates (and maps NaN to 0, clamped to 1).
                    n[a] = if active[a] {
                        (libm::round(per_axis[a]) as u32).clamp(1, max)
                    } else {
                        1
                    };
                }
                return n;
            }
        }
    }
    n
}
