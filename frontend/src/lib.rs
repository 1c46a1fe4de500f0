//! # halfray (frontend)
//!
//! Everything the `halfray` binary does, as a library so that tests can call it:
//! scene files ([`scene`]), the renderer ([`render`]), mesh tools ([`mesh_tools`]),
//! benchmarks ([`bench`](mod@bench)) and the Embree cross-check ([`crosscheck`]).

// Stderr is written through `console` (`note!`, `say!`, `eprint_error`), which decides what a
// failed write there does.
#![cfg_attr(not(test), deny(clippy::print_stderr))]

pub mod accel;
pub mod bake;
pub mod bench;
pub mod charts;
pub mod cli_values;
pub mod composite;
pub mod console;
pub mod crosscheck;
#[cfg(feature = "embree")]
pub mod embree;
pub mod error;
pub mod input;
pub mod limits;
pub mod mesh_tools;
pub mod obj;
pub mod outputs;
pub mod pages;
pub mod png;
pub mod raysets;
pub mod render;
pub mod scene;
pub mod simd;
pub mod skips;
pub mod text;
pub mod timing;
pub mod workers;

pub use error::{Error, Location, Result};
