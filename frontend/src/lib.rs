//! halfray frontend library: everything the `halfray` binary does, callable from tests.

#[cfg(feature = "embree")]
pub mod embree;
