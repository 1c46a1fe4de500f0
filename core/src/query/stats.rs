//! The traversal counters every structure's queries add to.

/// Traversal counters of ray queries. Queries **add** to the counters they are given, so one
/// value can accumulate a whole ray set (divide by the ray count for averages).
///
/// **A measure of work, approximate by contract.** The counts depend on the visiting order
/// and on how early a hit prunes the rest of the walk (and in a wide BVH on the order in
/// which its children are sorted), none of which is part of a query's answer: two
/// traversals that return the same hit may count differently, and the counts may change
/// between versions. Compare them between runs of the same build, never as exact values.
/// One exact relation holds: a wide BVH's closure query, which culls nothing, counts as
/// tested exactly the triangles its closure is called for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Nodes whose boxes were tested, or cells visited: in a binary BVH the root counts once
    /// and each inner node's two children twice; in a wide BVH each node once (its children
    /// are tested together); in a kd-tree each inner node and leaf; in a grid each cell whose
    /// references were tested (a ray that falls back to testing every reference counts every
    /// cell).
    pub nodes_visited: u64,
    /// Primitive intersection tests (a primitive in several kd-tree leaves or grid cells
    /// counts each time; a wide leaf counts every triangle slot of its run, culled or not).
    pub primitives_tested: u64,
}

impl TraversalStats {
    /// Adds `other`'s counters to these.
    #[inline]
    pub fn add(&mut self, other: &Self) {
        self.nodes_visited += other.nodes_visited;
        self.primitives_tested += other.primitives_tested;
    }
}
