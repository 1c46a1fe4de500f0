//! `halfray bench accuracy`: what accuracy costs in time, every variant measured on the same
//! rays in the same run.

pub mod choices;
#[cfg(feature = "embree")]
pub mod embree_rows;
pub mod triangles;

use crate::console::print_out;
use crate::error::{Error, Result};
use crate::obj::{ObjMesh, read_obj};
use crate::outputs::{Named, reserve_outputs, write_together};
use halfray_core::triangle::TriangleVariant;
use std::path::{Path, PathBuf};
use triangles::{Accuracy, Workload};

/// Where the shared test meshes live (beside the repository), unless `HALFRAY_MESHES` says.
pub fn shared_meshes_dir() -> PathBuf {
    std::env::var_os("HALFRAY_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/meshes"))
}

/// Arguments of `halfray bench accuracy`.
#[derive(clap::Args, Debug, Clone)]
pub struct AccuracyArgs {
    /// Meshes (OBJ). Default: the closed shared meshes (tetrahedron, cube, octahedron, spot,
    /// torus) for the accuracy figures, plus the bunny and the dragon for BVH throughput.
    /// With the `embree` feature, `embree` and `embree-robust` rows are added.
    pub meshes: Vec<PathBuf>,
    /// Small workloads (under a minute), for CI.
    #[arg(long)]
    pub quick: bool,
    /// Write the results as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the cost-against-error chart (`.svg` or `.png`; `halfray chart accuracy` draws it
    /// from the JSON later).
    #[arg(long)]
    pub chart: Option<PathBuf>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

/// One variant's row of the report.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VariantRow {
    /// Variant name.
    pub name: String,
    /// Median ns per ray–triangle test (hot loop, mostly misses).
    pub ns_per_test: Option<f64>,
    /// Single-threaded Mrays/s through the BVH, primary rays, on [`Report::bvh_mesh`].
    pub mrays_bvh_primary: Option<f64>,
    /// Single-threaded Mrays/s through the BVH, incoherent rays, on [`Report::bvh_mesh`].
    pub mrays_bvh_incoherent: Option<f64>,
    /// Single-threaded Mrays/s through the BVH, primary rays, on [`Report::largest_mesh`].
    pub mrays_bvh_primary_largest: Option<f64>,
    /// Single-threaded Mrays/s through the BVH, incoherent rays, on [`Report::largest_mesh`].
    pub mrays_bvh_incoherent_largest: Option<f64>,
    /// Edge and vertex rays that hit none of the incident triangles, per million.
    pub leaks_per_million: f64,
    /// Rays aimed just outside a triangle that hit it, per million.
    pub false_hits_per_million: f64,
    /// Largest relative error of `t` against the oracle ([`triangles::oracle_t`]).
    pub max_rel_t_error: f64,
    /// Median relative error of `t` against the oracle ([`triangles::oracle_t`]).
    pub median_rel_t_error: f64,
    /// Hit/miss disagreements with the oracle ([`triangles::oracle_t`]), per million rays.
    pub reference_disagreements_per_million: f64,
    /// Rays behind the leak figure.
    pub leak_rays: usize,
}

impl VariantRow {
    /// The row of variant `name`: `ns_per_test`, the BVH throughputs `mrays` in the columns'
    /// order (`bvh_mesh` primary and incoherent, `largest_mesh` primary and incoherent;
    /// `None` where not measured), and the accuracy figures of `acc`.
    pub fn new(
        name: &str,
        ns_per_test: Option<f64>,
        mrays: [Option<f64>; 4],
        acc: &Accuracy,
    ) -> Self {
        let [primary, incoherent, primary_largest, incoherent_largest] = mrays;
        Self {
            name: name.into(),
            ns_per_test,
            mrays_bvh_primary: primary,
            mrays_bvh_incoherent: incoherent,
            mrays_bvh_primary_largest: primary_largest,
            mrays_bvh_incoherent_largest: incoherent_largest,
            leaks_per_million: acc.leaks_per_million(),
            false_hits_per_million: acc.false_hits_per_million(),
            max_rel_t_error: acc.max_rel_t_error(),
            median_rel_t_error: acc.median_rel_t_error(),
            reference_disagreements_per_million: acc.disagreements_per_million(),
            leak_rays: acc.leak_rays,
        }
    }
}

/// The whole report.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    /// Per triangle variant.
    pub variants: Vec<VariantRow>,
    /// Slab test: plain vs conservative.
    pub slab: Vec<choices::ChoiceRow>,
    /// Secondary-ray offsets: fixed epsilon vs error bound.
    pub offsets: Vec<choices::ChoiceRow>,
    /// Sphere quadratic: naive vs stable.
    pub sphere: Vec<choices::ChoiceRow>,
    /// The file stem of the mesh the `mrays_bvh_primary` and `mrays_bvh_incoherent` columns
    /// measure: the mesh named `bunny`, else the first given with triangles; `None` (columns
    /// empty) when none has any.
    pub bvh_mesh: Option<String>,
    /// The file stem of the mesh of the `…_largest` columns: the mesh with the most triangles,
    /// when it is not [`Report::bvh_mesh`] (`None` otherwise: those columns stay empty).
    pub largest_mesh: Option<String>,
    /// Whether `--quick` was used.
    pub quick: bool,
}

fn is_closed(m: &ObjMesh) -> bool {
    let mut edges = std::collections::HashMap::<(u32, u32), u32>::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&n| n == 2)
}

/// The shared meshes ([`shared_meshes_dir`]) measured when none are named, by stem; the
/// dragon too without `--quick`.
pub const DEFAULT_MESHES: [&str; 6] = [
    "tetrahedron",
    "cube",
    "octahedron",
    "spot",
    "torus",
    "bunny",
];

/// The meshes `args` measures: those it names, or else [`DEFAULT_MESHES`] (and the dragon
/// without `--quick`).
fn mesh_paths(args: &AccuracyArgs) -> Vec<PathBuf> {
    if !args.meshes.is_empty() {
        return args.meshes.clone();
    }
    let dragon = (!args.quick).then_some("dragon");
    let dir = shared_meshes_dir();
    DEFAULT_MESHES
        .iter()
        .copied()
        .chain(dragon)
        .map(|n| dir.join(format!("{n}.obj")))
        .collect()
}

/// Runs the benchmark on `paths` (the meshes of `args`, as `mesh_paths` lists them) and returns the
/// report (printing nothing).
pub fn measure(args: &AccuracyArgs, paths: &[PathBuf]) -> Result<Report> {
    let meshes: Vec<(PathBuf, ObjMesh)> = paths
        .iter()
        .map(|p| read_obj(p).map(|m| (p.clone(), m)))
        .collect::<Result<_>>()?;
    let closed: Vec<ObjMesh> = meshes
        .iter()
        .filter(|(_, m)| is_closed(m))
        .map(|(_, m)| m.clone())
        .collect();
    if closed.is_empty() {
        return Err(Error::Usage(
            "bench accuracy needs at least one closed mesh for the leak figures".into(),
        ));
    }
    let (n, reps) = if args.quick {
        (20_000, 3)
    } else {
        (200_000, 9)
    };
    let workload = Workload::new(&closed, &closed, n, args.seed)
        .map_err(|e| Error::Usage(format!("bench accuracy: {e}")))?;
    let mut variants = Vec::new();
    for v in TriangleVariant::ALL {
        let (acc, ns) = triangles::measure(v, &workload, reps);
        variants.push(VariantRow::new(v.name(), Some(ns), [None; 4], &acc));
    }
    let (bunny, other) = throughput_meshes(&meshes);
    let bvh_rays = if args.quick { 20_000 } else { 200_000 };
    let stem = |entry: Option<&(PathBuf, ObjMesh)>| {
        entry.map(|(p, _)| {
            p.file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned()
        })
    };
    let (bvh_mesh, largest_mesh) = (stem(bunny), stem(other));
    let sets = [
        ray_set(bunny, true, bvh_rays, args.seed),
        ray_set(bunny, false, bvh_rays, args.seed),
        ray_set(other, true, bvh_rays, args.seed),
        ray_set(other, false, bvh_rays, args.seed),
    ];
    for (c, entry) in sets.iter().enumerate() {
        let Some((mesh, rays)) = entry else { continue };
        let accel = crate::accel::MeshAccel::new((*mesh).clone())?;
        // Rounds over all variants (one pass each), median per variant: the variants are
        // compared on the same machine state, not one after the other.
        let mut samples = vec![Vec::new(); TriangleVariant::ALL.len()];
        for _ in 0..reps.clamp(1, BVH_ROUNDS) {
            for (k, &v) in TriangleVariant::ALL.iter().enumerate() {
                samples[k].push(triangles::mrays_bvh_variant(v, &accel, rays, 1));
            }
        }
        for (row, s) in variants.iter_mut().zip(samples) {
            let m = Some(crate::timing::median(s));
            match c {
                0 => row.mrays_bvh_primary = m,
                1 => row.mrays_bvh_incoherent = m,
                2 => row.mrays_bvh_primary_largest = m,
                _ => row.mrays_bvh_incoherent_largest = m,
            }
        }
    }
    #[cfg(feature = "embree")]
    variants.extend(embree_rows::rows(&closed, &workload, &sets, reps.min(3))?);
    let choice_n = n / 4;
    Ok(Report {
        variants,
        slab: choices::slab_rows(choice_n, args.seed, reps),
        offsets: choices::offset_rows(choice_n, args.seed, reps),
        sphere: choices::sphere_rows(choice_n, args.seed, reps),
        bvh_mesh,
        largest_mesh,
        quick: args.quick,
    })
}

/// A mesh read, with its path.
type MeshRead = (PathBuf, ObjMesh);

/// The meshes of the BVH throughput columns: the one whose file stem is `bunny`, else the
/// first with triangles ([`Report::bvh_mesh`]); and the one with the most triangles (the
/// first of equals) unless it is that one ([`Report::largest_mesh`]). A mesh without
/// triangles is never chosen.
fn throughput_meshes(meshes: &[MeshRead]) -> (Option<&MeshRead>, Option<&MeshRead>) {
    let with_triangles = || meshes.iter().filter(|(_, m)| !m.triangles.is_empty());
    let bunny = with_triangles()
        .find(|(p, _)| p.file_stem().is_some_and(|s| s == "bunny"))
        .or_else(|| with_triangles().next());
    let largest = with_triangles()
        .rev()
        .max_by_key(|(_, m)| m.triangles.len());
    (
        bunny,
        largest.filter(|l| !bunny.is_some_and(|b| std::ptr::eq(*l, b))),
    )
}

/// Interleaved rounds of the BVH throughput columns (median taken).
const BVH_ROUNDS: usize = 5;

/// The primary (camera) or incoherent rays of the throughput columns for one mesh.
fn ray_set(
    entry: Option<&(PathBuf, ObjMesh)>,
    primary: bool,
    count: usize,
    seed: u64,
) -> Option<(&ObjMesh, Vec<halfray_core::Ray>)> {
    let (_, mesh) = entry?;
    let adj = crate::crosscheck::sets::Adjacency::new(mesh);
    let set = if primary { "primary" } else { "random" };
    let rays = crate::crosscheck::sets::generate(
        set,
        mesh,
        &adj,
        count,
        seed,
        &crate::raysets::named::no_hits,
    )
    .unwrap_or_default()
    .into_iter()
    .map(|r| r.ray)
    .collect();
    Some((mesh, rays))
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or_else(|| "–".into(), |v| format!("{v:.digits$}"))
}

/// The report as markdown tables: the BVH throughput columns headed by the meshes they
/// measure ([`Report::bvh_mesh`], [`Report::largest_mesh`]), the number of edge and vertex rays
/// the leak column counts under the variants' table; names and headings as table cells
/// ([`crate::text::table_cell`]).
pub fn markdown(r: &Report) -> String {
    use crate::text::table_cell as cell;
    let named = |m: &Option<String>| m.as_deref().map_or_else(|| "–".into(), cell);
    let (bvh, largest) = (named(&r.bvh_mesh), named(&r.largest_mesh));
    let mut s = format!(
        "| variant | ns/test | Mrays/s BVH primary ({bvh}) | Mrays/s BVH incoherent ({bvh}) | Mrays/s primary ({largest}) | Mrays/s incoherent ({largest}) | leaks / M edge+vertex rays | false hits / M | max rel t err | median rel t err | hit/miss ≠ oracle / M |\n"
    );
    s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for v in &r.variants {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {:.1} | {:.1} | {:.2e} | {:.2e} | {:.1} |\n",
            cell(&v.name),
            opt(v.ns_per_test, 2),
            opt(v.mrays_bvh_primary, 2),
            opt(v.mrays_bvh_incoherent, 2),
            opt(v.mrays_bvh_primary_largest, 2),
            opt(v.mrays_bvh_incoherent_largest, 2),
            v.leaks_per_million,
            v.false_hits_per_million,
            v.max_rel_t_error,
            v.median_rel_t_error,
            v.reference_disagreements_per_million,
        ));
    }
    let mut leak_rays: Vec<usize> = r.variants.iter().map(|v| v.leak_rays).collect();
    leak_rays.sort_unstable();
    leak_rays.dedup();
    if !leak_rays.is_empty() {
        let counts: Vec<String> = leak_rays.iter().map(usize::to_string).collect();
        s.push_str(&format!(
            "\nLeaks per million of {} edge and vertex rays: those generated whose line crosses their edge's or vertex's triangles transversally.\n",
            counts.join(" or ")
        ));
    }
    for (title, rows, what, err) in [
        (
            "Slab test (thin boxes at distance)",
            &r.slab,
            "false rejects / M",
            "–",
        ),
        (
            "Secondary-ray offsets",
            &r.offsets,
            "self-hits / M",
            "mean gap / |p|",
        ),
        (
            "Sphere quadratic (small spheres far away)",
            &r.sphere,
            "false misses / M",
            "max rel t err",
        ),
    ] {
        if rows.is_empty() {
            continue;
        }
        s.push_str(&format!(
            "\n{title}\n\n| choice | trials | {} | {} | ns |\n|---|---:|---:|---:|---:|\n",
            cell(what),
            cell(err)
        ));
        for c in rows {
            s.push_str(&format!(
                "| {} | {} | {:.1} | {:.2e} | {:.2} |\n",
                cell(&c.name),
                c.trials,
                c.failures_per_million,
                c.error,
                c.ns
            ));
        }
    }
    s
}

/// Runs `halfray bench accuracy`: reserves `--json` and `--chart` (never one of the meshes
/// it reads, the default ones included), measures, writes both files or neither
/// ([`write_together`]), then prints the table.
pub fn run(args: &AccuracyArgs) -> Result<()> {
    let mut outputs = Vec::new();
    if let Some(p) = &args.json {
        outputs.push(Named::new("--json", p));
    }
    if let Some(p) = &args.chart {
        crate::charts::Format::of(p)?;
        outputs.push(Named::new("--chart", p));
    }
    let paths = mesh_paths(args);
    let inputs: Vec<Named<'_>> = paths.iter().map(|p| Named::new("mesh", p)).collect();
    let mut reserved = reserve_outputs(&outputs, &inputs, args.force)?.into_iter();
    let report = measure(args, &paths)?;
    let mut files = Vec::new();
    if args.json.is_some() {
        let json =
            serde_json::to_vec_pretty(&report).map_err(|e| Error::encode("the JSON report", e))?;
        let out = reserved.next().expect("--json is reserved first");
        files.push((out, json));
    }
    if args.chart.is_some() {
        let out = reserved.next().expect("--chart is reserved after --json");
        // Cost as ns per incoherent ray through each side's BVH (`bvh_mesh`), so that Embree, which
        // has no per-triangle entry point, sits on the same axis.
        let chart = crate::charts::accuracy::AccuracyChart::from_report(&report)?;
        let bytes = crate::charts::render(&chart, crate::charts::Format::of(out.path())?)?;
        files.push((out, bytes));
    }
    write_together(files)?;
    print_out(&markdown(&report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn mesh(name: &str, triangles: usize) -> (PathBuf, ObjMesh) {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let m = ObjMesh {
            positions,
            triangles: vec![[0, 1, 2]; triangles],
        };
        (PathBuf::from(format!("dir/{name}.obj")), m)
    }

    /// A mesh without triangles is never the throughput's mesh: the first with triangles is,
    /// when none is named `bunny`; the largest is a second mesh only when it is another.
    #[test]
    fn the_throughput_meshes_have_triangles() {
        let stems = |ms: &[(PathBuf, ObjMesh)]| {
            let (a, b) = throughput_meshes(ms);
            let stem = |e: Option<&(PathBuf, ObjMesh)>| {
                e.map(|(p, _)| p.file_stem().unwrap().to_str().unwrap().to_owned())
            };
            (stem(a), stem(b))
        };
        let s = |x: &str| Some(x.to_owned());
        assert_eq!(
            stems(&[mesh("empty", 0), mesh("cube", 12)]),
            (s("cube"), None)
        );
        assert_eq!(
            stems(&[mesh("cube", 12), mesh("bunny", 5), mesh("dragon", 40)]),
            (s("bunny"), s("dragon"))
        );
        assert_eq!(
            stems(&[mesh("a", 3), mesh("b", 7), mesh("c", 7)]),
            (s("a"), s("b"))
        );
        assert_eq!(stems(&[mesh("empty", 0)]), (None, None));
    }

    /// Every line of every table has as many cells as its header's separator line, counted
    /// by splitting at the `|` not preceded by `\\`, whatever the names hold; the throughput
    /// columns name their mesh.
    #[test]
    fn the_markdown_tables_have_one_cell_per_column() {
        let row = |name: &str| choices::ChoiceRow {
            name: name.into(),
            trials: 1,
            failures_per_million: 0.0,
            error: 0.0,
            ns: 1.0,
        };
        let acc = Accuracy {
            leak_rays: 4,
            leaks: 1,
            ..Accuracy::default()
        };
        let report = Report {
            variants: vec![
                VariantRow::new("odd | name", Some(1.0), [Some(2.0), None, None, None], &acc),
                VariantRow::new("plain", None, [None; 4], &acc),
            ],
            slab: vec![row("a | b")],
            offsets: vec![row("offset @ |p|=1e0")],
            sphere: vec![row("plain")],
            bvh_mesh: Some("my|mesh".into()),
            largest_mesh: None,
            quick: true,
        };
        let md = markdown(&report);
        let cells = |line: &str| {
            let b = line.as_bytes();
            (0..b.len())
                .filter(|&i| b[i] == b'|' && (i == 0 || b[i - 1] != b'\\'))
                .count()
        };
        let mut tables: Vec<Vec<&str>> = Vec::new();
        let mut in_table = false;
        for line in md.lines() {
            let row = line.starts_with('|');
            if row && !in_table {
                tables.push(Vec::new());
            }
            if row {
                tables.last_mut().unwrap().push(line);
            }
            in_table = row;
        }
        assert_eq!(tables.len(), 4, "{md}");
        for table in &tables {
            assert!(table[1].starts_with("|---"), "{md}");
            let n = cells(table[1]);
            for line in table {
                assert_eq!(cells(line), n, "{line}\n{md}");
            }
        }
        let header = md.lines().next().unwrap();
        assert!(header.contains("primary (my\\|mesh)"), "{header}");
        assert!(header.contains("primary (–)"), "{header}");
        assert!(md.contains("| mean gap / \\|p\\| |"), "{md}");
        assert!(md.contains("\n| odd \\| name | 1.00 | 2.00 | – |"), "{md}");
        assert!(
            md.contains("\nLeaks per million of 4 edge and vertex rays: "),
            "{md}"
        );
    }
}
