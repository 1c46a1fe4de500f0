//! `halfray bench bvh` (in progress).

use crate::error::{Error, Result};
use std::path::PathBuf;

/// Arguments of `halfray bench bvh`.
#[derive(clap::Args, Debug, Clone)]
pub struct BvhArgs {
    /// Mesh to benchmark.
    pub mesh: PathBuf,
}

/// Runs the BVH benchmark.
pub fn run(_args: &BvhArgs) -> Result<()> {
    Err(Error::Other("bench bvh: in progress".into()))
}
