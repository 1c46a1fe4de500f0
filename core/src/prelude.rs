//! The traits a query needs in scope: `use halfray_core::prelude::*;`.

pub use crate::query::{LeafTest, RayQuery};
pub use crate::triangle::TriangleIntersector;
