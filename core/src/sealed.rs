//! The crate's two seals, both named from this private module, which no other crate can name.
//!
//! * **Sealed traits.** The public traits that only this crate implements
//!   ([`crate::query::Stack`], [`crate::triangle::ShearedTest`],
//!   [`crate::halfedge::MeshStorage`]) have [`Sealed`] as a supertrait. `Sealed` is public, so
//!   it may appear in their bounds, but no other crate can name it, and so none can implement
//!   those traits (they can still use them: call their methods, write bounds on them).
//! * **Sealed methods.** The provided methods of an open trait that are the crate's own
//!   hooks (the lane culls and SIMD kernels of [`crate::triangle::TriangleIntersector`],
//!   [`crate::query::LeafTest`] and [`crate::triangle::ShearedTest`]) take an [`Inside`] as
//!   their first argument. Another crate can neither write a signature with that type (so it
//!   cannot override the method) nor make a value of it (so it cannot call the method); this
//!   crate's own implementations override them as usual. `Inside` is a zero-sized type: the
//!   argument costs no code (inlined, or passed in no register).
//!
//! [`crate::simd_level::SimdLevel`] has a seal of its own (`simd::level::sealed::Sealed`),
//! which also carries what the crate's modules ask of a level.

/// Implemented by the types of this crate that implement a sealed trait (module docs).
pub trait Sealed {}

/// The first argument of a sealed method (module docs): made only in this crate, as
/// `Inside(())`.
#[derive(Clone, Copy, Debug)]
pub struct Inside(pub(crate) ());
