//! Benchmarks: `halfray bench bvh`, `halfray bench accel` and `halfray bench accuracy`.

pub mod accel;
pub mod accuracy;
pub mod bvh;

use crate::error::{Error, Result};
use crate::obj::ObjMesh;
use crate::outputs::{Named, OutputFile, reserve_outputs};
use crate::raysets::{Camera, random_rays};
use halfray_core::{Ray, Vec3};
use std::path::{Path, PathBuf};

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

/// The options `bench bvh` and `bench accel` share: the JSON output and the two ray sets.
#[derive(clap::Args, Debug, Clone)]
pub struct RunArgs {
    /// Also write the results as JSON to this file (atomically): the report object for one
    /// mesh, an array of them for several.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Camera image width and height for the primary rays.
    #[arg(long, default_value_t = 1024)]
    pub width: usize,
    /// Number of incoherent random rays.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

impl RunArgs {
    /// The checks `bench bvh` and `bench accel` make before any work: `--width` and `--rays`
    /// at least 1 ([`Error::Usage`] otherwise); the `width × width` primary and `rays` incoherent rays,
    /// held in memory together, within [`crate::limits::check_memory`]'s budget; and every
    /// one of `meshes` a file that opens ([`crate::input::open`]: not a directory or a
    /// device; [`Error::Io`] naming the first that is not, or [`Error::Input`] at
    /// `named_at[k]`, the mesh list's file and line, for a mesh `k` a list named), so that
    /// minutes of work are not spent on a run that then fails on a misspelt last path.
    ///
    /// # Errors
    ///
    /// As listed, in that order.
    pub fn check_inputs(
        &self,
        meshes: &[PathBuf],
        named_at: &[Option<crate::error::Location>],
    ) -> Result<()> {
        let (width, rays) = (self.width, self.rays);
        if width == 0 || rays == 0 {
            let name = if width == 0 { "--width" } else { "--rays" };
            return Err(Error::Usage(format!(
                "{name} must be at least 1 (a throughput of no rays is no figure)"
            )));
        }
        let ray_bytes = std::mem::size_of::<Ray>() as u64;
        let bytes = (width as u64)
            .checked_mul(width as u64)
            .and_then(|p| p.checked_add(rays as u64))
            .and_then(|n| n.checked_mul(ray_bytes));
        crate::limits::check_memory(&format!("--width {width} --rays {rays}"), bytes)?;
        for (k, mesh) in meshes.iter().enumerate() {
            crate::input::open(mesh).map_err(|e| match named_at.get(k) {
                Some(Some(at)) => Error::input(at.clone(), e.to_string()),
                _ => e,
            })?;
        }
        Ok(())
    }

    /// Reserves `--json` before any work ([`reserve_outputs`]): its folder must exist, and it
    /// may not be one of `meshes` or the file `list` that named some of them (a usage error,
    /// so that a run never replaces its own input with its report). `None` without `--json`.
    ///
    /// # Errors
    ///
    /// As [`reserve_outputs`].
    pub fn reserve_json(
        &self,
        meshes: &[PathBuf],
        list: Option<&Path>,
    ) -> Result<Option<OutputFile>> {
        let Some(json) = &self.json else {
            return Ok(None);
        };
        let inputs = crate::crosscheck::corpus::run_inputs(meshes, list);
        Ok(reserve_outputs(&[Named::new("--json", json)], &inputs, self.force)?.pop())
    }

    /// The two ray sets over `mesh`'s box (the unit cube `[0, 1]³` for a mesh without
    /// vertices): the primary rays of a `width × width` camera framing it
    /// ([`Camera::framing`]), then `rays` incoherent rays ([`random_rays`], seed
    /// [`bvh::INCOHERENT_SEED`]).
    pub fn ray_sets(&self, mesh: &ObjMesh) -> (Vec<Ray>, Vec<Ray>) {
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
        let primary = Camera::framing(lo, hi, self.width, self.width).rays();
        let incoherent = random_rays(lo, hi, self.rays, bvh::INCOHERENT_SEED);
        (primary, incoherent)
    }
}

/// Runs a benchmark subcommand.
pub fn run(cmd: &BenchCommand) -> Result<()> {
    match cmd {
        BenchCommand::Bvh(args) => bvh::run(args),
        BenchCommand::Accel(args) => accel::run(args),
        BenchCommand::Accuracy(args) => accuracy::run(args),
    }
}

/// Writes `reports` as pretty JSON to the reserved output `out` ([`RunArgs::reserve_json`]),
/// atomically, when there is one: the report object itself for one mesh, an array of them for
/// several.
///
/// # Errors
///
/// Encoding or writing the file.
fn write_json_reports<T: serde::Serialize>(out: Option<OutputFile>, reports: &[T]) -> Result<()> {
    if let Some(out) = out {
        let text = match reports {
            [one] => serde_json::to_string_pretty(one),
            all => serde_json::to_string_pretty(all),
        }
        .map_err(|e| Error::encode("the JSON report", e))?;
        out.write(|w| w.write_all(text.as_bytes()))?;
    }
    Ok(())
}
