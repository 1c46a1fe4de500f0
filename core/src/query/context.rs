//! The query context: what varies between calls of the same query (the traversal stack, the
//! SIMD level, the statistics), carried by one value ([`Query`]).

use super::TraversalStats;
use crate::query::QueryError;
use crate::simd_level::{Portable, SimdLevel};

/// One entry of a traversal stack (8 bytes): a node still to visit and the distance at which
/// the ray enters its box. A caller that brings its own stack ([`Query::stack`]) makes it of
/// [`StackEntry::EMPTY`]s; its contents between queries mean nothing.
#[derive(Clone, Copy, Debug)]
pub struct StackEntry {
    /// The node (binary BVH) or child reference (wide BVH) still to visit.
    pub(crate) node: u32,
    /// The distance at which the ray enters its box.
    pub(crate) t_enter: f32,
}

impl StackEntry {
    /// An entry to fill a stack with.
    pub const EMPTY: Self = Self {
        node: 0,
        t_enter: 0.0,
    };
}

/// [`StackEntry::EMPTY`].
impl Default for StackEntry {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Entries of a [`QueryStack`]: the stack bound of the widest tree,
/// [`crate::bvh::wide::stack_size`]`(8)` = `7·MAX_DEPTH + 1`, which bounds every structure's
/// (the binary BVH needs at most [`crate::bvh::TRAVERSAL_STACK_SIZE`]).
pub const QUERY_STACK_SIZE: usize = crate::bvh::wide::stack_size(8);

/// A traversal stack that suffices for every tree: [`QUERY_STACK_SIZE`] entries (3.5 KiB).
/// Creating one means writing all of it, so a caller tracing many rays keeps one and passes it
/// in the context ([`Query::stack`]); the queries never fail on it. Its contents between
/// queries mean nothing.
#[derive(Clone, Debug)]
pub struct QueryStack {
    pub(crate) entries: [StackEntry; QUERY_STACK_SIZE],
}

impl QueryStack {
    /// A stack for any tree.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            entries: [StackEntry::EMPTY; QUERY_STACK_SIZE],
        }
    }
}

impl Default for QueryStack {
    fn default() -> Self {
        Self::new()
    }
}

/// Where a query's traversal stack comes from, and so what the query returns:
///
/// * [`OwnStack`] (the default): each query makes a stack of its own in its frame, big
///   enough for any tree. Queries return `Option<(u32, hit)>`.
/// * `&mut `[`QueryStack`]: the caller's stack, big enough for any tree, kept across rays
///   (saves writing it per query). Queries return `Option<(u32, hit)>`.
/// * `&mut [`[`StackEntry`]`]` or `&mut [StackEntry; N]`: the caller's stack of any length,
///   for a firmware that sizes it for its trees (`stack_depth` entries suffice:
///   [`crate::bvh::Bvh::stack_depth`], the longest root-to-leaf path of a binary tree;
///   [`crate::bvh::wide::WideBvh::stack_depth`], [`QUERY_STACK_SIZE`] for a wide tree with
///   nodes, none for one without). Queries return `Result<Option<(u32, hit)>, QueryError>`:
///   [`QueryError::StackTooSmall`] when the ray's path needed more entries than the stack has
///   (a binary tree), or for every ray on a stack shorter than a wide tree's `stack_depth`
///   (no partial answer). An array is its
///   slice: `Query::new().stack(&mut array)` answers as `.stack(&mut array[..])`.
///
/// Structures whose walk needs no such stack (the grid) or has entries of its own (the
/// kd-tree's 12-byte intervals, 64 of them in its frame) ignore it.
///
/// Sealed: implemented by the kinds above only. What a query returns, and that a stack too
/// small is reported as [`QueryError::StackTooSmall`] rather than as a miss, is part of each
/// kind's contract, so no other crate can add one:
///
/// ```compile_fail,E0277
/// use halfray_core::query::{QueryError, Stack, StackEntry};
/// struct Quiet([StackEntry; 4]);
/// // Not possible: `Stack` is sealed. (This one would turn `StackTooSmall` into a miss.)
/// impl Stack for Quiet {
///     type Out<Y> = Option<Y>;
///     fn entries(&mut self) -> Option<&mut [StackEntry]> {
///         Some(&mut self.0)
///     }
///     fn answer<Y>(found: Result<Option<Y>, QueryError>) -> Option<Y> {
///         found.unwrap_or(None)
///     }
/// }
/// ```
pub trait Stack: crate::sealed::Sealed {
    /// What a query returns when its answer is `Option<Y>`.
    type Out<Y>;

    /// The caller's entries; `None` for a stack of the query's own.
    fn entries(&mut self) -> Option<&mut [StackEntry]>;

    /// The answer of a traversal as the query returns it.
    fn answer<Y>(found: Result<Option<Y>, QueryError>) -> Self::Out<Y>;
}

/// The default [`Stack`]: every query makes its own, enough for any tree.
#[derive(Clone, Copy, Debug, Default)]
pub struct OwnStack;

impl crate::sealed::Sealed for OwnStack {}

impl Stack for OwnStack {
    type Out<Y> = Option<Y>;

    #[inline(always)]
    fn entries(&mut self) -> Option<&mut [StackEntry]> {
        None
    }

    /// A stack of the query's own never overflows: the `Err` never happens.
    #[inline(always)]
    fn answer<Y>(found: Result<Option<Y>, QueryError>) -> Option<Y> {
        found.unwrap_or(None)
    }
}

impl crate::sealed::Sealed for &mut QueryStack {}

impl Stack for &mut QueryStack {
    type Out<Y> = Option<Y>;

    #[inline(always)]
    fn entries(&mut self) -> Option<&mut [StackEntry]> {
        Some(&mut self.entries)
    }

    /// A [`QueryStack`] suffices for every tree: the `Err` never happens.
    #[inline(always)]
    fn answer<Y>(found: Result<Option<Y>, QueryError>) -> Option<Y> {
        found.unwrap_or(None)
    }
}

impl crate::sealed::Sealed for &mut [StackEntry] {}

impl<const N: usize> crate::sealed::Sealed for &mut [StackEntry; N] {}

impl Stack for &mut [StackEntry] {
    type Out<Y> = Result<Option<Y>, QueryError>;

    #[inline(always)]
    fn entries(&mut self) -> Option<&mut [StackEntry]> {
        Some(self)
    }

    #[inline(always)]
    fn answer<Y>(found: Result<Option<Y>, QueryError>) -> Result<Option<Y>, QueryError> {
        found
    }
}

/// The array as its slice (`&mut [StackEntry]`): the same answers, the same refusals.
impl<const N: usize> Stack for &mut [StackEntry; N] {
    type Out<Y> = Result<Option<Y>, QueryError>;

    #[inline(always)]
    fn entries(&mut self) -> Option<&mut [StackEntry]> {
        Some(self.as_mut_slice())
    }

    #[inline(always)]
    fn answer<Y>(found: Result<Option<Y>, QueryError>) -> Result<Option<Y>, QueryError> {
        found
    }
}

/// What varies between calls of the same query: the traversal stack (`S`, see [`Stack`]), the
/// SIMD level of the wide trees' node and leaf kernels (`L`, see [`crate::simd_level`]; the
/// same answers at every level, other structures ignore it) and optional statistics, which
/// every query **adds** to.
///
/// ```
/// use halfray_core::query::{Query, QueryStack, TraversalStats};
/// let mut stats = TraversalStats::default();
/// let mut stack = QueryStack::new();
/// // One context for many rays: the caller's stack, counters summed over all of them.
/// let ctx = Query::new().stack(&mut stack).stats(&mut stats);
/// # let _ = ctx;
/// ```
#[derive(Debug)]
pub struct Query<'a, L = Portable, S = OwnStack> {
    pub(crate) level: L,
    pub(crate) stack: S,
    pub(crate) stats: Option<&'a mut TraversalStats>,
}

impl Query<'_> {
    /// The default context: a stack of the query's own, the portable kernels, no statistics.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            level: Portable,
            stack: OwnStack,
            stats: None,
        }
    }
}

impl Default for Query<'_> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a, L: SimdLevel, S: Stack> Query<'a, L, S> {
    /// This context with the kernels of SIMD `level` (a token that proves the CPU has them).
    #[must_use]
    pub fn on<M: SimdLevel>(self, level: M) -> Query<'a, M, S> {
        Query {
            level,
            stack: self.stack,
            stats: self.stats,
        }
    }

    /// This context on the caller's `stack` (see [`Stack`] for what each kind returns).
    #[must_use]
    pub fn stack<T: Stack>(self, stack: T) -> Query<'a, L, T> {
        Query {
            level: self.level,
            stack,
            stats: self.stats,
        }
    }

    /// This context adding every query's counters to `stats` (`&mut TraversalStats`, or an
    /// `Option` of one: `None` counts nothing).
    #[must_use]
    pub fn stats(self, stats: impl Into<Option<&'a mut TraversalStats>>) -> Self {
        Self {
            stats: stats.into(),
            ..self
        }
    }

    /// The SIMD level.
    #[inline(always)]
    #[must_use]
    pub fn level(&self) -> L {
        self.level
    }
}
