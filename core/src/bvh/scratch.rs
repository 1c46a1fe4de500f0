//! The primitives as the builder reads them ([`Refs`]): through the index array from the
//! source ([`Indexed`]), or from a scratch array of [`PrimRef`] records filled once and
//! reordered in place ([`Scratch`]); and the box-corner vector type both use.

use crate::aabb::Aabb;
use crate::mesh::PrimitiveSource;
use glam::Vec3;

/// The builder's box corners: 16-byte SIMD vectors on x86-64 (one `min`/`max` instruction per
/// bin update; the fourth lane is spare: a [`PrimRef`] keeps its index there, bins ignore it),
/// plain `Vec3` elsewhere (smaller records and a smaller stack frame on microcontrollers, where
/// there is no SIMD to use). Same values either way.
#[cfg(target_arch = "x86_64")]
pub(super) type Corner = glam::Vec4;
#[cfg(not(target_arch = "x86_64"))]
pub(super) type Corner = Vec3;

/// `v` as a corner (spare lane 0).
#[inline(always)]
pub(super) fn corner(v: Vec3) -> Corner {
    #[cfg(target_arch = "x86_64")]
    return v.extend(0.0);
    #[cfg(not(target_arch = "x86_64"))]
    return v;
}

/// The `x, y, z` of a corner.
#[inline(always)]
pub(super) fn point(c: Corner) -> Vec3 {
    #[cfg(target_arch = "x86_64")]
    return c.truncate();
    #[cfg(not(target_arch = "x86_64"))]
    return c;
}

/// The point a primitive is binned by: **twice** the centre of its box `lo, hi`, `lo + hi`,
/// lane by lane (one addition where the centre itself takes two products and a sum).
///
/// Only the builder's own comparisons see it: the centroid boxes it grows, the bins it maps
/// to ([`super::sah`]) and the partition, all of which are unchanged by a common factor of
/// two. Where neither `lo + hi` nor [`Aabb::center`]'s `lo/2 + hi/2` leaves the normal range,
/// the sum is exactly twice that centre (scaling by two is exact in binary floating point),
/// so every bin, split and tree is the one the centre gives. Elsewhere the tree may differ
/// and is still valid: a sum past `±f32::MAX` (coordinates beyond `2¹²⁷`) is infinite, and
/// a half of a subnormal coordinate rounds where the sum does not. Binning and partitioning
/// still agree there: both compute the same value from it ([`super::sah`]).
#[inline(always)]
pub(super) fn centre2(lo: Corner, hi: Corner) -> Corner {
    lo + hi
}

/// Growing `[lo, hi]` by `p` (finite corners: one vector `min` and `max`).
#[inline(always)]
pub(super) fn extend(lo: &mut Corner, hi: &mut Corner, p: Corner) {
    *lo = lo.min(p);
    *hi = hi.max(p);
}

/// A primitive as the scratch builder keeps it: its box and its index in the source (the
/// point it is binned by, twice its centre, is computed from the box when needed). On x86-64
/// the corners are 16-byte vectors, so binning is one `min` and one `max` per bin, and the
/// index lives in the lower corner's spare lane: 32 bytes. Elsewhere 28 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimRef {
    lo: Corner,
    hi: Corner,
    #[cfg(not(target_arch = "x86_64"))]
    index: u32,
}

impl PrimRef {
    /// A record for initialising scratch storage: `[PrimRef::EMPTY; K]`.
    pub const EMPTY: Self = Self {
        lo: Corner::INFINITY,
        hi: Corner::NEG_INFINITY,
        #[cfg(not(target_arch = "x86_64"))]
        index: 0,
    };

    /// The record of primitive `index` with box `b`.
    #[inline(always)]
    pub(super) fn new(b: &Aabb, index: u32) -> Self {
        #[cfg(target_arch = "x86_64")]
        return Self {
            // The bits of `index` are only stored and copied, never computed with, so any
            // bit pattern (a NaN's included) comes back unchanged.
            lo: b.min.extend(f32::from_bits(index)),
            hi: corner(b.max),
        };
        #[cfg(not(target_arch = "x86_64"))]
        return Self {
            lo: b.min,
            hi: b.max,
            index,
        };
    }

    /// The box's corners, spare lanes zero.
    #[inline(always)]
    pub(super) fn corners(&self) -> (Corner, Corner) {
        // The index's bits are a subnormal `f32` for most indices: arithmetic on them would
        // take the processor's slow path, so the lane is cleared by a bit select first.
        #[cfg(target_arch = "x86_64")]
        return (
            Corner::select(
                glam::BVec4A::new(true, true, true, false),
                self.lo,
                Corner::ZERO,
            ),
            self.hi,
        );
        #[cfg(not(target_arch = "x86_64"))]
        return (self.lo, self.hi);
    }

    /// The primitive's index in the source.
    #[inline(always)]
    pub(super) fn index(&self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        return self.lo.w.to_bits();
        #[cfg(not(target_arch = "x86_64"))]
        return self.index;
    }
}

impl Default for PrimRef {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Scratch entries [`super::Bvh::build_with_scratch`] needs for `prim_count` primitives: `N`.
#[must_use]
pub const fn scratch_capacity(prim_count: usize) -> usize {
    prim_count
}

/// What [`Refs::visit_run`] hands a run of elements to: the run as a slice of the view's own
/// elements with the function giving an element's box, whatever the element type.
pub(super) trait RunVisitor {
    type Out;
    fn visit<E>(self, run: &mut [E], bounds: impl Fn(&E) -> Box2) -> Self::Out;
}

/// The primitives being partitioned: the box of element `k` of the current order (its spare
/// lanes mean nothing), and the elements of a range as a slice to reorder.
pub(super) trait Refs {
    fn get(&self, k: usize) -> (Corner, Corner);

    /// `v` on the elements of `range` (an empty run when `range` lies outside the view).
    fn visit_run<V: RunVisitor>(&mut self, range: core::ops::Range<usize>, v: V) -> V::Out;

    /// `f(lo, hi)` on the box of every element of `range`, in order.
    #[inline(always)]
    fn for_each(&self, range: core::ops::Range<usize>, mut f: impl FnMut(Corner, Corner)) {
        for k in range {
            let (lo, hi) = self.get(k);
            f(lo, hi);
        }
    }

    /// `f(a, Some(b))` on the boxes of elements `2k, 2k + 1` of `range` (counted from its
    /// start), in order, then `f(last, None)` when `range` has an odd length.
    #[inline(always)]
    fn for_each_pair(&self, range: core::ops::Range<usize>, f: impl FnMut(Box2, Option<Box2>)) {
        pairs_by_get(self, range, f);
    }
}

/// A box as [`Refs`] hands it out: its lower and upper corner.
pub(super) type Box2 = (Corner, Corner);

/// [`Refs::for_each_pair`] element by element through [`Refs::get`].
#[inline(always)]
fn pairs_by_get<R: Refs + ?Sized>(
    refs: &R,
    range: core::ops::Range<usize>,
    mut f: impl FnMut(Box2, Option<Box2>),
) {
    let mut k = range.start;
    while k < range.end {
        let b = (k + 1 < range.end).then(|| refs.get(k + 1));
        f(refs.get(k), b);
        k += 2;
    }
}

/// A run of records, renumbered from 0 (element `k` outside it: `NaN` corners).
impl Refs for [PrimRef] {
    #[inline(always)]
    fn get(&self, k: usize) -> (Corner, Corner) {
        self.get(k)
            .map_or((Corner::NAN, Corner::NAN), PrimRef::corners)
    }

    #[inline(always)]
    fn visit_run<V: RunVisitor>(&mut self, range: core::ops::Range<usize>, v: V) -> V::Out {
        v.visit(self.get_mut(range).unwrap_or_default(), PrimRef::corners)
    }

    #[inline(always)]
    fn for_each(&self, range: core::ops::Range<usize>, mut f: impl FnMut(Corner, Corner)) {
        match self.get(range.clone()) {
            Some(run) => run.iter().for_each(|r| {
                let (lo, hi) = r.corners();
                f(lo, hi);
            }),
            None => range.for_each(|k| {
                let (lo, hi) = Refs::get(self, k);
                f(lo, hi);
            }),
        }
    }

    #[inline(always)]
    fn for_each_pair(&self, range: core::ops::Range<usize>, mut f: impl FnMut(Box2, Option<Box2>)) {
        let Some(run) = self.get(range.clone()) else {
            return pairs_by_get(self, range, f);
        };
        let mut pairs = run.chunks_exact(2);
        for pair in &mut pairs {
            if let [a, b] = pair {
                f(a.corners(), Some(b.corners()));
            }
        }
        if let [last] = pairs.remainder() {
            f(last.corners(), None);
        }
    }
}

/// The source read through the index array (no scratch).
pub(super) struct Indexed<'a, S: ?Sized> {
    pub(super) source: &'a S,
    pub(super) indices: &'a mut [u32],
}

impl<S: PrimitiveSource + ?Sized> Refs for Indexed<'_, S> {
    #[inline(always)]
    fn get(&self, k: usize) -> (Corner, Corner) {
        let i = self.indices.get(k).map_or(usize::MAX, |&i| i as usize);
        let b = self.source.primitive_bounds(i);
        (corner(b.min), corner(b.max))
    }

    #[inline(always)]
    fn visit_run<V: RunVisitor>(&mut self, range: core::ops::Range<usize>, v: V) -> V::Out {
        let source = self.source;
        v.visit(self.indices.get_mut(range).unwrap_or_default(), |&i| {
            let b = source.primitive_bounds(i as usize);
            (corner(b.min), corner(b.max))
        })
    }
}

/// The scratch records `offset ..` (a job's run holds the records of its primitive range
/// only; positions stay global).
pub(super) struct Scratch<'a> {
    pub(super) refs: &'a mut [PrimRef],
    pub(super) offset: usize,
}

impl Scratch<'_> {
    /// `range` in the records' numbering. A bound before the records maps past them, so such a
    /// range visits no element (the builder never asks for one: a job's ranges lie in its run).
    #[inline(always)]
    fn local(&self, range: core::ops::Range<usize>) -> core::ops::Range<usize> {
        let past = self.refs.len().saturating_add(1);
        let shift = |k: usize| k.checked_sub(self.offset).unwrap_or(past);
        shift(range.start)..shift(range.end)
    }
}

impl Refs for Scratch<'_> {
    #[inline(always)]
    fn get(&self, k: usize) -> (Corner, Corner) {
        let k = k.checked_sub(self.offset).unwrap_or(usize::MAX);
        Refs::get(&*self.refs, k)
    }

    #[inline(always)]
    fn for_each(&self, range: core::ops::Range<usize>, f: impl FnMut(Corner, Corner)) {
        self.refs.for_each(self.local(range), f);
    }

    #[inline(always)]
    fn for_each_pair(&self, range: core::ops::Range<usize>, f: impl FnMut(Box2, Option<Box2>)) {
        self.refs.for_each_pair(self.local(range), f);
    }

    #[inline(always)]
    fn visit_run<V: RunVisitor>(&mut self, range: core::ops::Range<usize>, v: V) -> V::Out {
        let range = self.local(range);
        self.refs.visit_run(range, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::MAX_PRIMITIVES;

    #[test]
    fn prim_ref_keeps_every_index_and_box() {
        // Indices whose bits are a subnormal, a NaN, infinity and the largest allowed.
        let b = Aabb::new(Vec3::new(-1.5, 2.0, -0.0), Vec3::new(3.0, 2.0, 7.25));
        for index in [
            0,
            1,
            0x007F_FFFF,
            0x7F80_0000,
            0x7F80_0001,
            MAX_PRIMITIVES as u32,
        ] {
            let r = PrimRef::new(&b, index);
            let copy = [r, PrimRef::EMPTY];
            assert_eq!(copy[0].index(), index);
            let (lo, hi) = copy[0].corners();
            assert_eq!(Aabb::new(point(lo), point(hi)), b);
            // The spare lanes are zero: no subnormal or NaN reaches the arithmetic. Twice the
            // centre, exactly (coordinates well inside the normal range).
            assert_eq!(centre2(lo, hi), corner(b.center() * 2.0));
        }
    }
}
