//! The traversal counters every structure's queries add to.

/// Traversal counters of ray queries. Queries **add** to the counters they are given, so one
/// value can accumulate a whole ray set (divide by the ray count for averages).
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
