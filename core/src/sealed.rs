//! The seal of the public traits that only this crate implements ([`crate::query::Stack`],
//! [`crate::triangle::ShearedTest`], [`crate::halfedge::MeshStorage`]): each has [`Sealed`]
//! as a supertrait. `Sealed` is public, so it may appear in their bounds, but it lives in this
//! private module, so no other crate can name it, and so none can implement those traits
//! (they can still use them: call their methods, write bounds on them).
//!
//! [`crate::simd_level::SimdLevel`] has a seal of its own (`simd::level::sealed::Sealed`),
//! which also carries what the crate's modules ask of a level.

/// Implemented by the types of this crate that implement a sealed trait (module docs).
pub trait Sealed {}
