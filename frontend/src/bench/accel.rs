//! `halfray bench accel`: the core's acceleration structures side by side on one mesh — the
//! uniform grid, the kd-tree, the binary BVH and the 8-wide BVH — built from the same
//! triangles and traced with the same intersector ([`Watertight`]) on the same rays.
//!
//! Rays as in `bench bvh` ([`super::RunArgs::ray_sets`]): the primary rays of a
//! `width × width` camera framing the mesh and `--rays` incoherent rays (seed
//! [`super::bvh::INCOHERENT_SEED`]). Every throughput is single-threaded and the best of
//! [`TIMED_PASSES`] passes, the structures taking turns pass by pass
//! (`interleaved`) so that a slow spell of the shared machine falls on all of them. Each
//! build is timed once per pass, best kept. `brute_force_mismatches` counts the rays of a
//! sample of the incoherent set (about [`BRUTE_FORCE_TESTS`] triangle tests) where the
//! structure's closest hit (triangle and `t`) differs from a loop over every triangle with
//! the same intersector: every structure promises 0. The answers timed are checked: every
//! structure's hit count on every timed pass must be the 8-wide BVH's on the same rays
//! ([`answers::count_failures`]), and every `brute_force_mismatches` 0; otherwise the run
//! fails with exit 3 once its JSON is written and its tables printed.

use super::bvh::answers::{self, Expected, Side, count_failures};
use super::bvh::{BRUTE_FORCE_TESTS, brute_force};
use crate::accel::{VecBvh, VecBvh8, build_binary, build_wide, closest_simd};
use crate::error::{Error, Location, Result};
use crate::obj::read_obj;
use crate::timing::{TIMED_PASSES, Timed, interleaved};
use halfray_core::Ray;
use halfray_core::bvh::BuildOptions;
use halfray_core::bvh::wide::binary_options;
use halfray_core::grid::{Grid, GridOptions, GridPlan};
use halfray_core::kdtree::{
    KdBuildOptions, KdNode, KdRef, KdTree, node_capacity, reference_capacity,
};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, Triangles};
use halfray_core::triangle::Watertight;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `halfray bench accel`.
#[derive(clap::Args, Debug, Clone)]
pub struct AccelArgs {
    /// Meshes to benchmark (OBJ), one after another.
    #[arg(required = true)]
    pub meshes: Vec<PathBuf>,
    /// The JSON output and the ray sets.
    #[command(flatten)]
    pub run: super::RunArgs,
}

/// One mesh's figures, as written to the JSON file.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AccelReport {
    /// Mesh path.
    pub mesh: String,
    /// Triangles in the mesh.
    pub triangles: usize,
    /// Intersector name (`watertight`).
    pub intersector: String,
    /// Primary rays per set.
    pub primary_rays: usize,
    /// Incoherent rays per set.
    pub incoherent_rays: usize,
    /// Rays of the brute-force sample.
    pub brute_force_rays: usize,
    /// One row per structure: `grid`, `kdtree`, `bvh` (binary), `bvh8` (8 wide).
    pub structures: Vec<StructureRow>,
}

/// One structure's figures.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StructureRow {
    /// `grid`, `kdtree`, `bvh` or `bvh8`.
    pub name: String,
    /// Build time on one thread (best of the passes), ms.
    pub build_ms: f64,
    /// Bytes the structure adds per triangle (the caller's mesh not counted; the wide BVH's
    /// copied triangles counted).
    pub bytes_per_triangle: f64,
    /// Closest hit, primary rays, Mrays/s.
    pub mrays_closest_primary: f64,
    /// Closest hit, incoherent rays, Mrays/s.
    pub mrays_closest_incoherent: f64,
    /// Sample rays whose closest hit differs from brute force (must be 0).
    pub brute_force_mismatches: usize,
}

/// The four structures over one mesh.
struct Built {
    grid: Grid<Vec<u32>, Vec<u32>>,
    kdtree: KdTree<Vec<KdNode>, Vec<u32>>,
    bvh: VecBvh,
    bvh8: VecBvh8,
}

/// Runs the benchmark.
pub fn run(args: &AccelArgs) -> Result<()> {
    args.run
        .check_inputs(super::RayMemory::BothSets, &args.meshes, &[])?;
    let json = args.run.reserve_json(&args.meshes, None)?;
    let mut reports = Vec::with_capacity(args.meshes.len());
    let mut failures = Vec::new();
    for mesh in &args.meshes {
        let (report, mesh_failures) = bench(args, mesh)?;
        reports.push(report);
        failures.extend(mesh_failures);
    }
    super::write_json_reports(json, &reports)?;
    for r in &reports {
        print_report(r);
    }
    answers::verdict(&failures)
}

/// One timed set of a mesh, for [`answer_failures`]: its name, its ray count, and each
/// structure's [`Timed`] in the rows' order (the 8-wide BVH's last).
struct TimedSet<'a> {
    name: &'a str,
    rays: usize,
    timed: &'a [Timed],
}

/// The failed checks of one mesh's answers (`mesh` as messages name it), each a message: a
/// structure whose hit count on some timed pass of a set is not the 8-wide BVH's on its first
/// pass (the structures promise the same answers), or whose closest hits differ from brute force on the
/// sample ([`StructureRow::brute_force_mismatches`]).
fn answer_failures(mesh: &str, sets: &[TimedSet<'_>], rows: &[StructureRow]) -> Vec<String> {
    let mut failures = Vec::new();
    for set in sets {
        let sides: Vec<Side<'_>> = rows
            .iter()
            .zip(set.timed)
            .map(|(row, timed)| Side {
                name: row.name.clone(),
                timed,
                embree: false,
            })
            .collect();
        failures.extend(count_failures(
            mesh,
            set.name,
            set.rays,
            Expected::same(set.timed.last().map_or(0, |t| t.hits[0])),
            &sides,
        ));
    }
    failures.extend(
        rows.iter()
            .filter(|r| r.brute_force_mismatches > 0)
            .map(|r| {
                format!(
                    "{mesh}: {} and brute force disagree on {} sample rays (must be 0)",
                    r.name, r.brute_force_mismatches
                )
            }),
    );
    failures
}

/// Builds the four structures over `mesh`, each timed; `(structures, build seconds per
/// structure in [`Built`]'s order)` of the last pass, with the best times.
fn build_all(mesh: &TriangleMesh<'_>, path: &Path) -> Result<(Built, [f64; 4])> {
    let err = |e: &dyn std::fmt::Display| Error::input(Location::file(path), e.to_string());
    let n = mesh.len();
    let mut best = [f64::INFINITY; 4];
    let mut built = None;
    for _ in 0..TIMED_PASSES {
        let t = Instant::now();
        let plan = GridPlan::new(mesh, &GridOptions::default()).map_err(|e| err(&e))?;
        let grid = Grid::build(
            mesh,
            &plan,
            vec![0u32; plan.required_offsets()],
            vec![0u32; plan.required_references()],
        )
        .map_err(|e| err(&e))?;
        best[0] = best[0].min(t.elapsed().as_secs_f64());

        let t = Instant::now();
        let mut scratch = vec![KdRef::EMPTY; reference_capacity(n)];
        let kdtree = KdTree::build(
            mesh,
            vec![KdNode::EMPTY; node_capacity(n)],
            vec![0u32; reference_capacity(n)],
            &mut scratch,
            &KdBuildOptions::default(),
        )
        .map_err(|e| err(&e))?;
        best[1] = best[1].min(t.elapsed().as_secs_f64());

        let t = Instant::now();
        let bvh = build_binary(mesh, &BuildOptions::default()).map_err(|e| err(&e))?;
        best[2] = best[2].min(t.elapsed().as_secs_f64());

        let t = Instant::now();
        let collapsed =
            build_binary(mesh, &binary_options(BuildOptions::default())).map_err(|e| err(&e))?;
        let bvh8 = build_wide(mesh, &collapsed).map_err(|e| err(&e))?;
        best[3] = best[3].min(t.elapsed().as_secs_f64());
        built = Some(Built {
            grid,
            kdtree,
            bvh,
            bvh8,
        });
    }
    let built = built.ok_or_else(|| Error::internal("no timed build ran", None))?;
    Ok((built, best))
}

fn bench(args: &AccelArgs, path: &Path) -> Result<(AccelReport, Vec<String>)> {
    let obj = read_obj(path)?;
    let mesh = TriangleMesh::new(&obj.positions, &obj.triangles);
    let n = mesh.len();
    let isect = Watertight;
    let (s, build_s) = build_all(&mesh, path)?;

    let (primary, incoherent) = args.run.ray_sets(&obj);

    type Closest<'a> = Box<dyn Fn(&Ray) -> Option<(u32, f32)> + 'a>;
    let closest: [Closest<'_>; 4] = [
        Box::new(|r| {
            s.grid
                .closest_hit(r, &mut Triangles::new(&mesh, &isect), &mut Query::new())
                .map(|(p, h)| (p, h.t))
        }),
        Box::new(|r| {
            s.kdtree
                .closest_hit(r, &mut Triangles::new(&mesh, &isect), &mut Query::new())
                .map(|(p, h)| (p, h.t))
        }),
        Box::new(|r| {
            s.bvh
                .closest_hit(r, &mut Triangles::new(&mesh, &isect), &mut Query::new())
                .map(|(p, h)| (p, h.t))
        }),
        Box::new(|r| closest_simd(&s.bvh8, &mesh, &isect, r, None).map(|(p, h)| (p, h.t))),
    ];
    let closest = &closest;
    let hit = |i: usize| move |r: &Ray| closest[i](r).is_some();
    let (h0, h1, h2, h3) = (hit(0), hit(1), hit(2), hit(3));
    let refs: [&dyn Fn(&Ray) -> bool; 4] = [&h0, &h1, &h2, &h3];
    let mrays_primary = interleaved(&primary, &refs);
    let mrays_incoherent = interleaved(&incoherent, &refs);

    let sample_len = (BRUTE_FORCE_TESTS / n.max(1))
        .clamp(16, 20_000)
        .min(incoherent.len());
    let sample = &incoherent[..sample_len];
    let brute: Vec<Option<(u32, f32)>> = sample
        .iter()
        .map(|r| brute_force(&mesh, &isect, r))
        .collect();

    let bytes = [
        s.grid.bytes_per_triangle(),
        s.kdtree.bytes_per_triangle(),
        s.bvh.bytes_per_triangle(),
        s.bvh8.bytes_per_triangle(),
    ];
    let structures: Vec<StructureRow> = ["grid", "kdtree", "bvh", "bvh8"]
        .iter()
        .enumerate()
        .map(|(i, name)| StructureRow {
            name: (*name).to_string(),
            build_ms: build_s[i] * 1e3,
            bytes_per_triangle: bytes[i],
            mrays_closest_primary: mrays_primary[i].mrays,
            mrays_closest_incoherent: mrays_incoherent[i].mrays,
            brute_force_mismatches: sample
                .iter()
                .zip(&brute)
                .filter(|(r, b)| closest[i](r) != **b)
                .count(),
        })
        .collect();
    let failures = answer_failures(
        &crate::text::path(path),
        &[
            TimedSet {
                name: "primary",
                rays: primary.len(),
                timed: &mrays_primary,
            },
            TimedSet {
                name: "incoherent",
                rays: incoherent.len(),
                timed: &mrays_incoherent,
            },
        ],
        &structures,
    );
    let report = AccelReport {
        mesh: path.display().to_string(),
        triangles: n,
        intersector: "watertight".into(),
        primary_rays: primary.len(),
        incoherent_rays: incoherent.len(),
        brute_force_rays: sample_len,
        structures,
    };
    Ok((report, failures))
}

fn print_report(r: &AccelReport) {
    crate::sayln!(
        "bench accel: {} ({} triangles, {}, one thread; brute-force sample {} rays)",
        crate::text::escaped(&r.mesh),
        r.triangles,
        r.intersector,
        r.brute_force_rays
    );
    crate::sayln!(
        "  {:<8} {:>10} {:>8} {:>16} {:>19} {:>11}",
        "",
        "build ms",
        "B/tri",
        "closest primary",
        "closest incoherent",
        "mismatches"
    );
    for s in &r.structures {
        crate::sayln!(
            "  {:<8} {:>10.1} {:>8.1} {:>16.2} {:>19.2} {:>11}",
            s.name,
            s.build_ms,
            s.bytes_per_triangle,
            s.mrays_closest_primary,
            s.mrays_closest_incoherent,
            s.brute_force_mismatches
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(name: &str, brute_force_mismatches: usize) -> StructureRow {
        StructureRow {
            name: name.into(),
            build_ms: 1.0,
            bytes_per_triangle: 1.0,
            mrays_closest_primary: 1.0,
            mrays_closest_incoherent: 1.0,
            brute_force_mismatches,
        }
    }

    /// A structure whose count on one timed pass differs from the 8-wide BVH's, and one that
    /// disagrees with brute force, each fail naming mesh, set and structure; the same answers
    /// everywhere pass.
    #[test]
    fn a_structure_answering_otherwise_fails_the_run() {
        let right = Timed {
            mrays: 1.0,
            hits: [5; TIMED_PASSES],
        };
        let mut off = right.clone();
        off.hits[1] = 4;
        let rows = [
            row("grid", 0),
            row("kdtree", 0),
            row("bvh", 0),
            row("bvh8", 0),
        ];
        let set = |timed| TimedSet {
            name: "primary",
            rays: 9,
            timed,
        };
        let all_right = vec![right.clone(); 4];
        assert!(answer_failures("m.obj", &[set(&all_right)], &rows).is_empty());
        let one_off = [right.clone(), off, right.clone(), right];
        assert_eq!(
            answer_failures("m.obj", &[set(&one_off)], &rows),
            [
                "m.obj set primary: kdtree hit 4 of 9 rays on timed pass 2, halfray's closest-hit query 5 (allowed difference 0)"
            ]
        );
        let rows = [
            row("grid", 0),
            row("kdtree", 0),
            row("bvh", 2),
            row("bvh8", 0),
        ];
        assert_eq!(
            answer_failures("m.obj", &[set(&all_right)], &rows),
            ["m.obj: bvh and brute force disagree on 2 sample rays (must be 0)"]
        );
    }
}
