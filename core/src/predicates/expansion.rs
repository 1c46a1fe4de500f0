//! Exact floating-point expansions (Shewchuk 1997, "Adaptive precision floating-point
//! arithmetic and fast robust geometric predicates"): a value is kept as an unevaluated sum of
//! `f64` components, non-overlapping and in increasing magnitude, so that sums and products of
//! `f64` values are represented **exactly** and the sign of the sum is the sign of its last
//! (largest) component.
//!
//! Only what the exact orientation predicates need: the exact difference of two `f64`
//! ([`two_diff`]), the exact product ([`two_product`], Dekker's split, no fused multiply-add),
//! and growing an expansion by one component ([`Expansion::grow`], zero components
//! eliminated). Exactness needs no overflow and no underflow: for differences and products of
//! up to three differences of finite `f32` values every magnitude lies between `2⁻⁴⁴⁷` and
//! `2³⁹⁰`, far inside the normal `f64` range.

/// `2²⁷ + 1`: Dekker's splitter for `f64` (53-bit significands split into two 26-bit halves).
const SPLITTER: f64 = 134_217_729.0;

/// `(x, y)` with `x = fl(a + b)` and `x + y = a + b` exactly (Knuth's two-sum).
#[inline]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

/// `(x, y)` with `x = fl(a − b)` and `x + y = a − b` exactly.
#[inline]
pub(crate) fn two_diff(a: f64, b: f64) -> (f64, f64) {
    let x = a - b;
    let bv = a - x;
    let av = x + bv;
    (x, (a - av) + (bv - b))
}

/// Dekker's split: `a = hi + lo` with both halves of at most 26 significant bits.
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = SPLITTER * a;
    let big = c - a;
    let hi = c - big;
    (hi, a - hi)
}

/// `(x, y)` with `x = fl(a·b)` and `x + y = a·b` exactly (Dekker), without a fused
/// multiply-add (Rust never contracts `a * b + c`).
#[inline]
pub(crate) fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    let (ahi, alo) = split(a);
    let (bhi, blo) = split(b);
    let err1 = x - ahi * bhi;
    let err2 = err1 - alo * bhi;
    let err3 = err2 - ahi * blo;
    (x, alo * blo - err3)
}

/// An exact sum of at most `N` non-zero `f64` components, non-overlapping, in increasing
/// magnitude. Capacities are chosen by the callers as proven maxima (each
/// [`Expansion::grow`] adds at most one component); a component that would not fit sets
/// [`Expansion::overflowed`] instead of panicking.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Expansion<const N: usize> {
    c: [f64; N],
    len: usize,
    overflow: bool,
}

impl<const N: usize> Expansion<N> {
    /// The expansion of zero (no component).
    pub(crate) const ZERO: Self = Self {
        c: [0.0; N],
        len: 0,
        overflow: false,
    };

    /// The non-zero components, smallest first.
    #[inline]
    pub(crate) fn components(&self) -> &[f64] {
        self.c.get(..self.len).unwrap_or(&self.c)
    }

    /// `true` when a component was dropped for lack of capacity (never, with the capacities
    /// this module's callers use).
    #[inline]
    pub(crate) fn overflowed(&self) -> bool {
        self.overflow
    }

    /// Adds `b` exactly (Shewchuk's GROW-EXPANSION with zero elimination): the output is
    /// non-overlapping and increasing whenever the input is, and has at most one more
    /// component. Works in place: output `k` is written after input `k` was read.
    pub(crate) fn grow(&mut self, b: f64) {
        let mut q = b;
        let mut out = 0usize;
        for i in 0..self.len {
            let Some(&e) = self.c.get(i) else { break };
            let (s, h) = two_sum(q, e);
            q = s;
            if h != 0.0 {
                if let Some(slot) = self.c.get_mut(out) {
                    *slot = h;
                }
                out += 1;
            }
        }
        if q != 0.0 {
            match self.c.get_mut(out) {
                Some(slot) => {
                    *slot = q;
                    out += 1;
                }
                None => self.overflow = true,
            }
        }
        self.len = out;
    }

    /// Adds `sign · e · f` exactly, `e` and `f` being expansions given by their components
    /// (`sign` is `±1`, applied exactly). Adds at most `2·|e|·|f|` components.
    pub(crate) fn add_product(&mut self, e: &[f64], f: &[f64], sign: f64) {
        for &x in e {
            for &y in f {
                let (hi, lo) = two_product(x, y);
                self.grow(sign * lo);
                self.grow(sign * hi);
            }
        }
    }

    /// The sign of the exact value: `1`, `−1` or `0` (the sign of the largest component).
    #[inline]
    pub(crate) fn sign(&self) -> i32 {
        match self.components().last() {
            Some(&x) if x > 0.0 => 1,
            Some(&x) if x < 0.0 => -1,
            _ => 0,
        }
    }
}

/// The exact difference `a − b` of two `f64` as an expansion of at most two components.
#[inline]
pub(crate) fn diff(a: f64, b: f64) -> Expansion<2> {
    let (x, y) = two_diff(a, b);
    let mut e = Expansion::<2>::ZERO;
    e.grow(y);
    e.grow(x);
    e
}
