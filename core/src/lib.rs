//! # halfray-core
//!
//! A `#![no_std]`, allocation-free ray/mesh geometry core on `f32`.
//!
//! * [`ray`]: rays with a half-open parametric interval `(t_min, t_max]`.
//! * [`float`]: the floating-point error model (`gamma(n)`) every tolerance derives from.
//! * [`tolerance`]: the named, documented tolerances of the intersectors that need one.
//! * [`hit`]: the hit record shared by every primitive, with a conservative error bound on the
//!   hit point, and [`hit::spawn_ray`] for secondary rays that do not meet their own surface
//!   again (with the watertight triangle test, whose `t` is exact enough; planes, polygons,
//!   boxes, and quadrics where the error box is small against the curvature).
//! * [`aabb`]: axis-aligned boxes and the robust (Ize 2013) slab test.
//! * [`triangle`]: ray–triangle tests behind one trait, the watertight one by default.
//! * [`plane`], [`sphere`], [`quadric`], [`polygon`], [`transform`]: the other primitives.
//! * [`mesh`]: what every structure is built over: primitives by index with their bounds,
//!   and the indexed triangle mesh.
//! * [`bvh`]: a binned-SAH BVH built into caller storage, traversed with a fixed stack; and
//!   [`bvh::collide`], mesh-against-mesh collision (exact triangle–triangle test, BVH against
//!   BVH under a transform) and the minimum distance between two meshes.
//! * [`grid`], [`kdtree`]: the uniform grid (3-D DDA) and the SAH kd-tree beside the BVH, in
//!   caller storage.
//! * [`query`]: one query interface over all of them ([`query::RayQuery`]: closest hit, any
//!   hit, box query; equal to brute force), with the leaf test ([`query::LeafTest`]) and the
//!   query context ([`query::Query`]); [`prelude`] imports the traits.
//! * [`volume`]: bounding spheres, oriented boxes and capsules, and conservative overlap tests.
//! * [`halfedge`]: fixed-capacity half-edge mesh arenas and their editing operations.
//! * [`solids`]: the octahedron and the cube as index lists, for examples and tests.
//!
//! **glam.** Points, vectors and matrices are [glam](https://docs.rs/glam/0.34)'s: `f32`
//! [`Vec3`], [`Mat4`] and the others, and the `f64` `DVec3`, `DMat3` and `DMat4` of
//! [`quadric::Quadric`]'s exact form. This crate re-exports the glam it is built with as
//! [`glam`] (and `Vec2`, `Vec3`, `Mat3`, `Mat4` at the root): name its types through
//! `halfray_core::glam`, or depend on the same glam minor version (0.34). Another 0.x
//! release of glam is another crate, whose `Vec3` is not this crate's; so a move to another
//! glam minor version is a breaking change of this crate.
//!
//! ```
//! use halfray_core::glam::{DMat3, DVec3};
//! use halfray_core::quadric::Quadric;
//! // The unit sphere, x·x − 1 = 0, in the f64 form `Quadric::new` takes.
//! let sphere = Quadric::new(DMat3::IDENTITY, DVec3::ZERO, -1.0).unwrap();
//! assert_eq!(sphere.eval(DVec3::new(0.0, 2.0, 0.0)), 3.0);
//! ```
//!
//! **Traits: which to implement.** Meant to be implemented by other crates:
//! [`mesh::Primitive`] and [`mesh::PrimitiveSource`] (what a structure is built over),
//! [`query::LeafTest`] (a query's test of one primitive; closures implement it),
//! [`triangle::TriangleIntersector`] (a ray–triangle test, for [`query::Triangles`]),
//! [`triangle::VariantVisitor`] (code run with a run-time variant's intersector),
//! [`shape::Shape`] (a surface a ray can hit), [`volume::PointSet`] (points a bounding volume
//! is fitted to) and [`query::RayQuery`] (a structure answering the common queries; another
//! crate's returns its answers through the context's stack kind, `Stack::answer`, and leaves
//! the context's statistics alone, which only this crate's structures fill in). Sealed, so
//! used but not implemented elsewhere, because the crate relies on what their implementations
//! promise: [`query::Stack`] (what a query returns, `StackTooSmall` included),
//! [`triangle::ShearedTest`] (the watertight family, whose shared cull assumes each member's
//! test), [`halfedge::MeshStorage`] and [`simd_level::SimdLevel`]. The open
//! `TriangleIntersector` and `LeafTest` also have sealed methods, hidden from these docs:
//! the lane culls and SIMD kernels the wide trees run, internal hooks that other crates can
//! neither override nor call (see those traits' docs).
//!
//! Nothing in this crate panics on any input, NaN and infinity included: intersectors are
//! total functions that report "no hit" for invalid rays, and constructors that can reject
//! input return a typed error ([`error`]).
//!
//! `unsafe` is denied everywhere except two private modules, x86-64 only with portable
//! fallbacks elsewhere. `simd` holds the lane kernels: a cache prefetch hint, a lane-compare
//! bit mask and a four-lane vector for the triangle tests' lane culls (the compiler scalarises
//! both when written portably), and the AVX2 + FMA kernels of [`simd_level`] behind a token
//! that proves the CPU has them (the 8-wide node test, the child sort, the two-group cull).
//! `triangle::watertight::avx2` is the AVX2 + FMA end of the watertight hit path (the `f64`
//! plane form of a hit's `t`, whose 3-vectors the compiler keeps in scalar registers), entered
//! on the same token. Each is there because the portable form measured slower
//! (`docs/performance.md`); its blocks carry their proofs.
#![no_std]
#![deny(unsafe_code)]
#![deny(missing_docs)]
#![deny(clippy::missing_errors_doc)]

// The host's unit tests only (their oracles and ray sets live in `Vec`s): the library itself
// links neither `std` nor `alloc`, which the CI's builds for targets without them prove.
#[cfg(test)]
extern crate std;

/// The README's quick start, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeQuickStart;

pub mod aabb;
pub mod bvh;
pub mod error;
pub mod float;
mod getters;
pub mod grid;
pub mod halfedge;
pub mod hit;
pub mod kdtree;
pub mod mesh;
pub mod plane;
pub mod polygon;
pub mod predicates;
pub mod prelude;
pub mod quadric;
pub mod query;
pub mod ray;
mod sealed;
pub mod shape;
#[allow(unsafe_code)]
mod simd;
pub mod solids;
pub mod sphere;
mod storage;
#[cfg(test)]
mod test_util;
pub mod tolerance;
pub mod transform;
pub mod triangle;
pub mod volume;

pub use aabb::Aabb;
pub use error::{GeometryError, RayError};
/// The glam this crate is built with (crate docs: use it, or the same minor version).
pub use glam;
pub use glam::{Mat3, Mat4, Vec2, Vec3};
pub use hit::{Hit, shadow_segment, spawn_ray, spawn_ray_between, spawn_ray_to};
pub use ray::Ray;
/// The SIMD level of the wide-BVH node test, chosen by the caller at run time.
pub use simd::level as simd_level;
