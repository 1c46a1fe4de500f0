//! The renderer (in progress).

use crate::error::{Error, Result};
use std::path::PathBuf;

/// `halfray render SCENE.toml -o OUT.png`.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs `halfray render`.
pub fn run(_args: &RenderArgs) -> Result<()> {
    Err(Error::Other("render: in progress".into()))
}
