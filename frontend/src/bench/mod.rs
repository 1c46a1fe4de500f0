//! Benchmarks: `halfray bench bvh`, `halfray bench accel` and `halfray bench accuracy`.

pub mod accel;
pub mod accuracy;
pub mod bvh;

use crate::error::Result;

/// `halfray bench ...`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum BenchCommand {
    /// BVH build time, size and traversal throughput.
    Bvh(bvh::BvhArgs),
    /// The acceleration structures side by side: grid, kd-tree, binary and wide BVH.
    Accel(accel::AccelArgs),
    /// Cost against accuracy of every intersector variant and robustness choice.
    Accuracy(accuracy::AccuracyArgs),
}

/// Runs a benchmark subcommand.
pub fn run(cmd: &BenchCommand) -> Result<()> {
    match cmd {
        BenchCommand::Bvh(args) => bvh::run(args),
        BenchCommand::Accel(args) => accel::run(args),
        BenchCommand::Accuracy(args) => accuracy::run(args),
    }
}
