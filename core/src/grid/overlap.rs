//! The cell layout, the triangles' padding and the conservative triangle-to-cell assignment (box
//! or separating-axis).
//!
//! Cells are laid out in the grid's **frame**: coordinates relative to the centre `c` of its
//! box ([`Layout::centre`]), so that the cell planes, a ray's origin and every rounding
//! the padding covers are measured by the scene's size, not by how far it lies from the
//! coordinate origin. Cell `(i, j, k)` is the box `c + [min + i·size, min + (i+1)·size]` per
//! axis in **real** arithmetic on the stored `f32` `c`, `min` and `size`, except that the
//! first and last cell of each axis extend to `−∞` and `+∞`: the cells partition all of
//! space, so a point outside the grid's box maps to the nearest border cell on each axis (by
//! clamping) both when assigning and when traversing. Assignment is computed in `f64` on
//! `p − c` with a relative slack ([`SAT_SLACK_REL`]), so it never misses a cell the padded
//! triangle touches.

use super::{GRID_ABS_PAD, GRID_RAY_PAD, MAX_CELLS_PER_AXIS, ORIGIN_REACH, SAT_SLACK_REL};
use crate::aabb::Aabb;
use glam::{DVec3, Vec3};

/// How triangles are assigned to cells ([`super::GridOptions::assignment`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CellAssignment {
    /// Every cell the triangle's (padded) bounding box overlaps: cheap to build, more
    /// references (a long diagonal triangle fills its whole box).
    Bounds,
    /// Every cell the (padded) triangle itself overlaps, by the separating-axis test in `f64`
    /// (conservative: see [`super::SAT_SLACK_REL`]). The default.
    #[default]
    Exact,
}

/// Padding of every triangle at build time, world units (module docs of [`super`]):
/// [`GRID_RAY_PAD`]`·(reach + extent) + `[`GRID_ABS_PAD`], which covers every ray whose origin
/// has `max|o_i − c_i| ≤ reach` in the grid's frame.
#[inline]
pub(super) fn ray_pad(origin_mag: f32, extent: f32) -> f32 {
    GRID_RAY_PAD * (origin_mag + extent) + GRID_ABS_PAD
}

/// The origin magnitude in the grid's frame up to which rays need no more padding than the
/// build's: `extent + ORIGIN_REACH·(longest side)`.
#[inline]
pub(super) fn origin_reach(bounds: &Aabb, extent: f32) -> f32 {
    let side = bounds.extent().max_element();
    if side.is_finite() && side > 0.0 {
        extent + ORIGIN_REACH * side
    } else {
        extent
    }
}

/// Expands, inside the `impl` of a type with a `layout: Layout` field (the grid and the plan
/// it was built from, which describe the same cells), to the public `resolution`,
/// `cell_count` and `bounds`.
macro_rules! layout_accessors {
    () => {
        /// Cells along `x`, `y`, `z` (each in `1..=`[`MAX_CELLS_PER_AXIS`]).
        #[must_use]
        pub fn resolution(&self) -> [u32; 3] {
            self.layout.n
        }

        /// Number of cells.
        #[must_use]
        pub fn cell_count(&self) -> usize {
            self.layout.cell_count()
        }

        /// The grid's box: the union of the usable triangles' boxes of the mesh the plan
        /// was made for ([`Aabb::EMPTY`] for none). A grid built from a reused plan keeps
        /// it (it holds every usable triangle's box: [`Grid::build`](crate::grid::Grid::build)).
        #[must_use]
        pub fn bounds(&self) -> Aabb {
            self.layout.bounds
        }
    };
}

pub(super) use layout_accessors;

/// Geometry of the cells and the padding of the build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Layout {
    /// Union of the usable triangles' boxes ([`Aabb::EMPTY`] for none), world coordinates.
    pub(super) bounds: Aabb,
    /// Cells per axis.
    pub(super) n: [u32; 3],
    /// The frame's origin: the centre of `bounds` (zero for an empty grid). Every other
    /// field but `bounds` is relative to it.
    pub(super) centre: Vec3,
    /// `bounds` relative to `centre`, rounded outward ([`Aabb::relative_to`]; empty for an
    /// empty grid): it holds every exact `p − centre`. Its lower corner is that of cell
    /// `(0, 0, 0)` (read only on axes of more than one cell).
    pub(super) local: Aabb,
    /// Cell side per axis (0 on axes of one cell, where it is never used).
    pub(super) size: Vec3,
    /// Largest coordinate magnitude of `local` (0 when empty): about half the longest side.
    pub(super) extent: f32,
    /// Origin magnitude, relative to `centre`, up to which a ray needs no more padding than
    /// `pad`.
    pub(super) reach: f32,
    /// Padding of every triangle, world units ([`ray_pad`]`(reach, extent)`).
    pub(super) pad: f32,
}

impl Layout {
    /// `true` when axis `a` of `bounds` can be cut into cells: its length is finite and at
    /// least [`MAX_CELLS_PER_AXIS`] smallest normal floats (so every cell side is a normal
    /// `f32`, and the plane computations keep relative error bounds).
    pub(super) fn can_split(bounds: &Aabb, a: usize) -> bool {
        let len = bounds.max[a] - bounds.min[a];
        len.is_finite() && len >= f32::MIN_POSITIVE * MAX_CELLS_PER_AXIS as f32
    }

    /// The layout of `n` cells over `bounds`, in the frame of its centre.
    pub(super) fn new(bounds: &Aabb, n: [u32; 3]) -> Self {
        let usable = bounds.is_finite() && bounds.is_valid();
        let centre = if usable { bounds.center() } else { Vec3::ZERO };
        // A finite box relative to its own centre: each bound at most its side in magnitude
        // (an overflowing side, beyond `f32::MAX`, gives an infinite bound: not splittable).
        let local = if usable {
            bounds.relative_to(centre)
        } else {
            Aabb::EMPTY
        };
        let extent = if usable {
            crate::query::walk::extent_of(&local)
        } else {
            0.0
        };
        let mut n = n;
        let mut size = Vec3::ZERO;
        for a in 0..3 {
            if !usable || !Self::can_split(&local, a) {
                n[a] = 1;
            }
            if n[a] > 1 {
                size[a] = (local.max[a] - local.min[a]) / n[a] as f32;
            }
        }
        // Both finite (`f32::MAX` at most), so that the `f64` assignment never meets `∞ − ∞`.
        let finite = |x: f32| if x.is_finite() { x } else { f32::MAX };
        let reach = finite(origin_reach(&local, extent));
        Self {
            bounds: *bounds,
            n,
            centre,
            local,
            size,
            extent,
            reach,
            pad: finite(ray_pad(reach, extent)),
        }
    }

    /// `p − centre` in `f32`: a point (a ray's origin) in the grid's frame, rounded once
    /// relative to its own magnitude.
    #[inline(always)]
    pub(super) fn local_point(&self, p: Vec3) -> Vec3 {
        p - self.centre
    }

    /// Number of cells (at most `MAX_CELLS_PER_AXIS³ = 2³⁰`).
    pub(super) fn cell_count(&self) -> usize {
        self.n.iter().map(|&k| k as usize).product()
    }

    /// Linear index of cell `(i, j, k)`: `i + nx·(j + ny·k)`.
    #[inline(always)]
    pub(super) fn cell_id(&self, c: [u32; 3]) -> usize {
        c[0] as usize + self.n[0] as usize * (c[1] as usize + self.n[1] as usize * c[2] as usize)
    }

    /// The cell of coordinate `x` on axis `a`, clamped into `0..n` (traversal, `f32`).
    #[inline(always)]
    pub(super) fn cell_of(&self, a: usize, x: f32) -> u32 {
        let last = self.n[a] - 1;
        if last == 0 {
            return 0;
        }
        let q = (x - self.local.min[a]) / self.size[a];
        // `!(q > 0)` catches NaN (not reachable for finite x); `as` floors non-negative values.
        if !(q > 0.0) {
            0
        } else if q >= last as f32 {
            last
        } else {
            q as u32
        }
    }

    /// The plane `min + m·size` on axis `a`, in `f32` (traversal).
    #[inline(always)]
    pub(super) fn plane(&self, a: usize, m: u32) -> f32 {
        self.local.min[a] + m as f32 * self.size[a]
    }

    /// The cells on axis `a` that the closed interval `[lo, hi]` (`f64`) touches, clamped:
    /// computed in `f64` and widened by [`SAT_SLACK_REL`] of the quotients, so a cell that
    /// the exact interval touches is never left out.
    fn range(&self, a: usize, lo: f64, hi: f64) -> (u32, u32) {
        let last = self.n[a] - 1;
        if last == 0 {
            return (0, 0);
        }
        let (m, s) = (f64::from(self.local.min[a]), f64::from(self.size[a]));
        let clamp = |q: f64| {
            if !(q > 0.0) {
                0
            } else if q >= f64::from(last) {
                last
            } else {
                q as u32
            }
        };
        let (q_lo, q_hi) = ((lo - m) / s, (hi - m) / s);
        (
            clamp(q_lo - (q_lo.abs() + 1.0) * SAT_SLACK_REL),
            clamp(q_hi + (q_hi.abs() + 1.0) * SAT_SLACK_REL),
        )
    }

    /// Lower and upper bound of cell `i` on axis `a` in `f64`, infinite at the border.
    fn cell_bounds(&self, a: usize, i: u32) -> (f64, f64) {
        let (m, s) = (f64::from(self.local.min[a]), f64::from(self.size[a]));
        let lo = if i == 0 {
            f64::NEG_INFINITY
        } else {
            m + f64::from(i) * s
        };
        let hi = if i + 1 >= self.n[a] {
            f64::INFINITY
        } else {
            m + f64::from(i + 1) * s
        };
        (lo, hi)
    }
}

/// Calls `found(cell)` for every cell that triangle `v` (finite, world coordinates), padded
/// by the layout's `pad` on every axis, touches: by its box ([`CellAssignment::Bounds`]) or
/// by the triangle itself ([`CellAssignment::Exact`]). Cells are visited in increasing linear
/// index. The vertices are taken into the grid's frame in `f64` (`p − c`: one rounding
/// relative to the difference, within the assignment's slack). Returns the cells (lowest
/// and highest, per axis) that the padded box touches: every cell found lies in that range,
/// and under [`CellAssignment::Bounds`] every cell of it is found.
pub(super) fn for_each_cell(
    layout: &Layout,
    v: &[Vec3; 3],
    assignment: CellAssignment,
    mut found: impl FnMut(usize),
) -> [(u32, u32); 3] {
    let pad = f64::from(layout.pad);
    let c = layout.centre.as_dvec3();
    let w = v.map(|p| p.as_dvec3() - c);
    let lo = w[0].min(w[1]).min(w[2]) - DVec3::splat(pad);
    let hi = w[0].max(w[1]).max(w[2]) + DVec3::splat(pad);
    let r = [0, 1, 2].map(|a| layout.range(a, lo[a], hi[a]));
    for k in r[2].0..=r[2].1 {
        for j in r[1].0..=r[1].1 {
            for i in r[0].0..=r[0].1 {
                let c = [i, j, k];
                let keep = match assignment {
                    CellAssignment::Bounds => true,
                    CellAssignment::Exact => {
                        // The cell grown by `pad`, cut to the padded triangle's box (which
                        // holds the triangle, so nothing is lost); a cut emptied by rounding
                        // collapses to a point instead of rejecting the cell.
                        let mut bl = DVec3::ZERO;
                        let mut bh = DVec3::ZERO;
                        for a in 0..3 {
                            let (cl, ch) = layout.cell_bounds(a, c[a]);
                            let (l, h) = ((cl - pad).max(lo[a]), (ch + pad).min(hi[a]));
                            let (l, h) = if l <= h { (l, h) } else { (h, l) };
                            bl[a] = l;
                            bh[a] = h;
                        }
                        triangle_overlaps_box(&w, bl, bh)
                    }
                };
                if keep {
                    found(layout.cell_id(c));
                }
            }
        }
    }
    r
}

/// Separating-axis test of a triangle against the closed box `[lo, hi]` (Akenine-Möller
/// 2001: the box's three face normals, the triangle's normal and the nine cross products of
/// its edges with the axes), in `f64` on finite inputs. **Conservative:** an axis separates
/// only when the gap exceeds [`SAT_SLACK_REL`] of the magnitudes involved, which bounds the
/// `f64` rounding of every projection, so touching or overlapping inputs always return
/// `true`. Degenerate triangles (segments, points) have zero axes that separate nothing,
/// leaving the other axes to decide: still conservative.
pub(super) fn triangle_overlaps_box(v: &[DVec3; 3], lo: DVec3, hi: DVec3) -> bool {
    let c = (lo + hi) * 0.5;
    let h = (hi - lo) * 0.5;
    let p = v.map(|x| x - c);
    // Magnitude of everything a projection's rounding is relative to.
    let scale = v.iter().fold(c.abs().max(h).max_element(), |m, x| {
        m.max(x.abs().max_element())
    });
    let separates = |axis: DVec3| {
        let d = [axis.dot(p[0]), axis.dot(p[1]), axis.dot(p[2])];
        let a = axis.abs();
        let r = h.dot(a) + SAT_SLACK_REL * (a.x + a.y + a.z) * scale;
        d[0].min(d[1]).min(d[2]) > r || d[0].max(d[1]).max(d[2]) < -r
    };
    let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let units = [DVec3::X, DVec3::Y, DVec3::Z];
    !(units.iter().any(|&u| separates(u))
        || separates(e[0].cross(e[1]))
        || e.iter()
            .any(|&edge| units.iter().any(|&u| separates(edge.cross(u)))))
}
