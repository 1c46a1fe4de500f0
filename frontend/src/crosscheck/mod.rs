//! `halfray crosscheck` (in progress).

pub mod judge;
pub mod sets;

use crate::error::{Error, Result};
use std::path::PathBuf;

/// Arguments of `halfray crosscheck`.
#[derive(clap::Args, Debug, Clone)]
pub struct CrosscheckArgs {
    /// Mesh to cross-check.
    pub mesh: PathBuf,
}

/// Runs the cross-check.
pub fn run(_args: &CrosscheckArgs) -> Result<()> {
    Err(Error::Other("crosscheck: in progress".into()))
}
