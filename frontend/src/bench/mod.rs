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

/// Bytes of the process beside its rays and mesh: the binary, its libraries, the thread
/// pool's stacks and the report (6.8 MB resident for `bench bvh` on the 12-triangle cube at
/// `--width 4`; rounded up to 16 MiB). Part of [`RayMemory::peak_bytes`], so that the
/// estimate bounds the whole peak for a small mesh.
pub const PROCESS_BASE_BYTES: u64 = 16 << 20;

/// How a benchmark holds its rays, for its memory estimate ([`RayMemory::peak_bytes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayMemory {
    /// `bench accel`: the `width²` camera rays and the `rays` random ones, together for the
    /// whole run (the brute-force sample is a slice of the random rays, its answers at most
    /// 20 000).
    BothSets,
    /// `bench bvh`: one set at a time. A camera set's rays with their batch answers (the
    /// batch check keeps one [`Answer`](crate::accel::Answer) per ray), or while a shadow or
    /// AO set is generated, the camera rays it is derived from beside it: per camera ray
    /// [`CAMERA_RAY_PEAK_BYTES`]. The random set's rays alone.
    OneSetAtATime,
}

/// Bytes one camera ray of `bench bvh` holds at the peak of its set ([`RayMemory`]): the ray,
/// and the larger of its batch answer and the ray derived from it.
pub const CAMERA_RAY_PEAK_BYTES: u64 = {
    let ray = std::mem::size_of::<Ray>() as u64;
    let answer = std::mem::size_of::<crate::accel::Answer>() as u64;
    ray + if answer > ray { answer } else { ray }
};

impl RayMemory {
    /// An upper bound of the run's peak resident memory for `width × width` camera rays and
    /// `rays` random ones on a small mesh: the rays and what is held per ray (see the
    /// variants), plus [`PROCESS_BASE_BYTES`]. The mesh's own structures (its vertices, the
    /// trees built over it, Embree's copy) grow with the mesh, not the rays, and are not
    /// counted. `None` when the size does not fit in 64 bits.
    #[must_use]
    pub fn peak_bytes(self, width: usize, rays: usize) -> Option<u64> {
        let ray = std::mem::size_of::<Ray>() as u64;
        let camera = (width as u64).checked_mul(width as u64)?;
        let random = (rays as u64).checked_mul(ray)?;
        let held = match self {
            Self::BothSets => camera.checked_mul(ray)?.checked_add(random)?,
            Self::OneSetAtATime => camera.checked_mul(CAMERA_RAY_PEAK_BYTES)?.max(random),
        };
        held.checked_add(PROCESS_BASE_BYTES)
    }
}

impl RunArgs {
    /// The checks `bench bvh` and `bench accel` make before any work: `--width` and `--rays`
    /// at least 1 ([`Error::Usage`] otherwise); the run's memory as `held` holds its rays
    /// ([`RayMemory::peak_bytes`]) within [`crate::limits::check_memory`]'s budget; and every
    /// one of `meshes`, in order, a file that opens ([`crate::input::open`]: not a directory
    /// or a device; [`Error::Io`] naming the first that is not, or [`Error::Input`] at
    /// `named_at[k]`, the mesh list's file and line, for a mesh `k` a list named) and parses
    /// as the run will read it ([`crate::obj::read_obj`], the mesh dropped before the next is
    /// read; its error at the file's own line, with the list line after it,
    /// [`noting_list_line`](crate::crosscheck::corpus::noting_list_line)), so that minutes of
    /// work are not spent on a run that then fails on a misspelt or broken last mesh.
    ///
    /// # Errors
    ///
    /// As listed, in that order.
    pub fn check_inputs(
        &self,
        held: RayMemory,
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
        crate::limits::check_memory(
            &format!("--width {width} --rays {rays}"),
            held.peak_bytes(width, rays),
        )?;
        for (k, mesh) in meshes.iter().enumerate() {
            let listed = named_at.get(k).and_then(Option::as_ref);
            crate::input::open(mesh).map_err(|e| match listed {
                Some(at) => Error::input(at.clone(), e.to_string()),
                None => e,
            })?;
            crate::obj::read_obj(mesh)
                .map_err(|e| crate::crosscheck::corpus::noting_list_line(listed, e))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::size_of;

    /// The estimate is the sizes of what each run holds per ray at its peak, plus the process.
    #[test]
    fn the_memory_estimate_counts_what_each_run_holds_per_ray() {
        let ray = size_of::<Ray>() as u64;
        let answer = size_of::<crate::accel::Answer>() as u64;
        let base = PROCESS_BASE_BYTES;
        // `bench bvh`: a camera set's rays beside their answers (or the rays derived from
        // them); the random set alone when it is the larger.
        let camera = 1_000_000 * (ray + answer.max(ray));
        assert_eq!(
            RayMemory::OneSetAtATime.peak_bytes(1000, 10),
            Some(camera + base)
        );
        assert_eq!(
            RayMemory::OneSetAtATime.peak_bytes(10, 10_000_000),
            Some(10_000_000 * ray + base)
        );
        // `bench accel`: both sets' rays together.
        assert_eq!(
            RayMemory::BothSets.peak_bytes(1000, 1_000_000),
            Some(2_000_000 * ray + base)
        );
        for held in [RayMemory::BothSets, RayMemory::OneSetAtATime] {
            assert_eq!(held.peak_bytes(usize::MAX, 1), None, "{held:?}");
        }
    }

    /// A mesh that opens but does not parse is refused by the checks before any work, after
    /// a good mesh, with its own file, line and field (and the list line that named it).
    #[test]
    fn a_later_mesh_that_does_not_parse_is_refused_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("good.obj");
        let bad = dir.path().join("bad.obj");
        std::fs::write(&good, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        std::fs::write(&bad, "v 0 0 0\ngarbage\n").unwrap();
        let run = RunArgs {
            json: None,
            width: 4,
            rays: 4,
            force: false,
        };
        let meshes = [good.clone(), bad.clone()];
        for held in [RayMemory::OneSetAtATime, RayMemory::BothSets] {
            let e = run
                .check_inputs(held, &meshes, &[])
                .unwrap_err()
                .to_string();
            let want = format!("{}:2:1: field `statement`", bad.display());
            assert!(e.contains(&want), "want `{want}` in: {e}");
        }
        let list = crate::error::Location::file(dir.path().join("list.txt")).line(3);
        let e = run
            .check_inputs(RayMemory::OneSetAtATime, &meshes, &[None, Some(list)])
            .unwrap_err()
            .to_string();
        let want = format!("(named at {}:3)", dir.path().join("list.txt").display());
        assert!(e.contains(&want), "want `{want}` in: {e}");
        assert!(
            run.check_inputs(RayMemory::OneSetAtATime, &meshes[..1], &[])
                .is_ok()
        );
    }

    /// A `bench bvh` camera whose rays fit in the limit but not beside their answers is
    /// refused before any work (9000² rays are 2.4 GiB, with their answers 4.8 GiB).
    #[test]
    fn a_camera_set_is_refused_when_its_rays_and_answers_exceed_the_limit() {
        let run = |width| RunArgs {
            json: None,
            width,
            rays: 1,
            force: false,
        };
        let e = run(9000)
            .check_inputs(RayMemory::OneSetAtATime, &[], &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--width 9000 --rays 1 needs about 4.8 GiB"),
            "{e}"
        );
        assert!(
            run(9000)
                .check_inputs(RayMemory::BothSets, &[], &[])
                .is_ok()
        );
    }
}
