//! Mesh tools over the half-edge core (in progress).

use crate::error::{Error, Result};
use std::path::PathBuf;

/// `halfray mesh ...`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum MeshCommand {
    /// Check manifoldness, boundary loops, Euler characteristic and genus.
    Check {
        /// Input OBJ.
        input: PathBuf,
    },
}

/// Runs a mesh subcommand.
pub fn run(_cmd: &MeshCommand) -> Result<()> {
    Err(Error::Other("mesh: in progress".into()))
}
