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
    /// Adds `other`'s counters to these, saturating at `u64::MAX` (never a panic, never a
    /// wrap to a small count).
    #[inline]
    pub fn add(&mut self, other: &Self) {
        self.nodes_visited = self.nodes_visited.saturating_add(other.nodes_visited);
        self.primitives_tested = self
            .primitives_tested
            .saturating_add(other.primitives_tested);
    }
}

#[cfg(test)]
mod tests {
    use super::TraversalStats;

    #[test]
    fn adding_saturates_at_the_largest_count() {
        let mut s = TraversalStats {
            nodes_visited: u64::MAX - 1,
            primitives_tested: 7,
        };
        s.add(&TraversalStats {
            nodes_visited: 5,
            primitives_tested: u64::MAX,
        });
        assert_eq!((s.nodes_visited, s.primitives_tested), (u64::MAX, u64::MAX));
        s.add(&TraversalStats {
            nodes_visited: 0,
            primitives_tested: 0,
        });
        assert_eq!((s.nodes_visited, s.primitives_tested), (u64::MAX, u64::MAX));
    }
}
