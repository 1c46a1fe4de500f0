//! The `halfray` command line. Exit codes: 0 success, 1 error in input data or I/O,
//! 2 usage error, 3 cross-check found more genuine mismatches than allowed, 141 stdout closed
//! (a broken pipe ends the program quietly). SIGINT/SIGTERM/SIGHUP remove temporary output
//! files and exit with 128 + the signal number.

use clap::{Parser, Subcommand};
use halfray::{bake, bench, charts, composite, crosscheck, mesh_tools, render};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "halfray",
    version,
    about = "Watertight ray/mesh geometry: render scenes, edit meshes, benchmark, cross-check against Embree",
    after_help = "Exit codes: 0 success, 1 bad input or I/O error, 2 usage error, 3 mismatches (crosscheck, bench bvh, bench accel), 141 stdout closed."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to PNG.
    Render(render::RenderArgs),
    /// Half-edge mesh tools.
    #[command(subcommand)]
    Mesh(mesh_tools::MeshCommand),
    /// Benchmarks.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Draw a chart (SVG or PNG) from the JSON of a benchmark or cross-check run.
    Chart(charts::ChartArgs),
    /// Compare halfray's hits with Embree 4, ray by ray.
    Crosscheck(crosscheck::CrosscheckArgs),
    /// Build a mesh's BVH here and write it for firmware: Rust `static` arrays, or the byte
    /// buffer C firmware loads (`--format`).
    Bake(bake::BakeArgs),
    /// Combine two images with a Porter–Duff operator (A the source, B the destination).
    Composite(composite::CompositeArgs),
    /// Find your display's gamma: a calibration chart, and γ = ln 0.5 / ln a from the match.
    Gamma(render::gamma::GammaArgs),
}

fn main() -> ExitCode {
    halfray::console::install_print_panic_guard();
    if let Err(e) = halfray::outputs::temp::install_signal_cleanup() {
        halfray::note!("warning: no signal handler (temporary files may stay after Ctrl-C): {e}");
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return halfray::console::clap_exit(&e),
    };
    let result = halfray::workers::install_global_pool().and_then(|()| match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Mesh(cmd) => mesh_tools::run(&cmd),
        Command::Bench(cmd) => bench::run(&cmd),
        Command::Chart(args) => charts::run(&args),
        Command::Crosscheck(args) => crosscheck::run(&args),
        Command::Bake(args) => bake::run(&args),
        Command::Composite(args) => composite::run(&args),
        Command::Gamma(args) => render::gamma::run(&args),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(halfray::Error::BrokenPipe) => ExitCode::from(halfray::error::EXIT_BROKEN_PIPE),
        Err(e) => {
            halfray::console::eprint_error(&e);
            ExitCode::from(e.exit_code())
        }
    }
}
