//! Mesh-vs-mesh collision and minimum distance: two [`Bvh`]s, the second
//! placed in the first one's frame by a [`Transform`], descended together on a fixed stack.
//!
//! * [`colliding_pairs`]: every intersecting triangle pair, into a caller slice, with the
//!   total count ([`CollideError::OutputTooSmall`] still reports it when the slice is short).
//! * [`first_contact`]: the first intersecting pair found, or `None`.
//! * [`min_distance`]: the closest triangle pair and its distance, up to a bound.
//! * The narrow phase on its own: [`triangles_intersect`] (exact, closed triangles,
//!   Devillers–Guigue with exact orientation predicates: [`orient3d`], [`orient2d`]) and
//!   [`triangle_distance`] (`f64`).
//!
//! **Frames.** The first body is tested as given; the second body's triangles are mapped by
//! `b_to_a` with [`Transform::point_to_world`] (the `f32` vertices a renderer would draw),
//! and every answer is exact (collision) or within [`DISTANCE_ERR_REL`] (distance) for those
//! vertices. Node boxes of the second tree are mapped as centre ± `|L|`·half-extents in `f64`
//! and padded by [`PLACED_BOX_PAD_REL`] and [`PLACED_BOX_PAD_ABS`], so they contain the mapped triangles: the broad phase
//! never loses a pair, and the results equal brute force over all pairs.
//!
//! **Stack bound.** A node pair `(a, b)` has pair depth `depth(a) + depth(b)`. Each step
//! descends into one tree, so a child pair has pair depth one more than its parent; one of
//! two surviving children is pushed, the other visited at once. The pending pairs therefore
//! have strictly increasing pair depths from the bottom of the stack to the top (a push is
//! one deeper than everything below it; a pop resumes the deepest), each in
//! `1..=2·MAX_DEPTH`: at most [`PAIR_STACK_SIZE`] = `2·`[`MAX_DEPTH`] entries. Trees come
//! from [`Bvh::build`] or [`Bvh::from_parts`], which refuse depths beyond [`MAX_DEPTH`];
//! a push on a full stack is still a typed error ([`CollideError::TreeTooDeep`]), never a
//! panic or a skipped node.
//!
//! Nothing allocates; no storage is needed beyond the output slice.
//!
//! [`Bvh`]: crate::bvh::Bvh
//! [`Bvh::build`]: crate::bvh::Bvh::build
//! [`Bvh::from_parts`]: crate::bvh::Bvh::from_parts
//! [`Transform`]: crate::transform::Transform
//! [`Transform::point_to_world`]: crate::transform::Transform::point_to_world
//! [`MAX_DEPTH`]: crate::bvh::MAX_DEPTH

mod body;
mod distance;
mod error;
mod nearest;
mod pairs;
mod tri_tri;

#[cfg(test)]
mod tests;

pub use crate::predicates::{ORIENT2D_FILTER_REL, ORIENT3D_FILTER_REL, orient2d, orient3d};
pub use body::{Body, PLACED_BOX_PAD_ABS, PLACED_BOX_PAD_REL};
pub use distance::{DISTANCE_ERR_REL, triangle_distance};
pub use error::CollideError;
pub use nearest::{Closest, min_distance};
pub use pairs::{colliding_pairs, first_contact};
pub use tri_tri::{is_degenerate, triangles_intersect};

/// Entries of the fixed node-pair stack of every query: `2·MAX_DEPTH` (module docs), 8 bytes
/// each for collisions, 16 for distances.
pub const PAIR_STACK_SIZE: usize = 2 * crate::bvh::MAX_DEPTH;
