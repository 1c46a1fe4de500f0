//! Benchmarks: `halfray bench bvh` and `halfray bench accuracy`.

pub mod bvh;

use crate::error::Result;

/// `halfray bench ...`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum BenchCommand {
    /// BVH build time, size and traversal throughput.
    Bvh(bvh::BvhArgs),
}

/// Runs a benchmark subcommand.
pub fn run(cmd: &BenchCommand) -> Result<()> {
    match cmd {
        BenchCommand::Bvh(args) => bvh::run(args),
    }
}
