//! `halfray mesh subdivide | smooth | collapse`: edit a mesh through the half-edge core and
//! write it back as OBJ (atomically).

use super::{
    CollapseArgs, MeshBuffers, SmoothArgs, SubdivideArgs, Vef, build_mesh, export, ms_since,
    reserve_output,
};
use crate::error::{Error, Location, Result};
use crate::limits::check_memory;
use crate::obj::{
    MAX_COORDINATE, NotCarried, ObjLines, first_outside_domain, read_obj_file_within, write_obj_to,
};
use crate::text;
use glam::Vec3;
use halfray_core::halfedge::{
    CollapseAt, CollapseError, Counts, DiffuseBoundary, DiffuseError, EdgeId, LoopWeights,
    MAX_ELEMENTS, Mesh, MeshStorage, SliceMesh, SubdivideError,
};
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What an editing command did.
#[derive(Clone, Debug, Default)]
pub struct EditReport {
    /// `subdivide`, `smooth` or `collapse`.
    pub command: &'static str,
    /// Input file.
    pub input: PathBuf,
    /// Output file.
    pub output: PathBuf,
    /// Counts of the input.
    pub before: Vef,
    /// Counts of the output.
    pub after: Vef,
    /// `subdivide`: counts and milliseconds after each level.
    pub levels: Vec<(Vef, f64)>,
    /// `smooth`: mean length of the uniform Laplacian `|L(v)|` over vertices with neighbours,
    /// before and after (a roughness measure in model units).
    pub roughness: Option<(f64, f64)>,
    /// `collapse`: edges collapsed.
    pub collapsed: usize,
    /// `collapse`: passes over the short edges (the last one collapses nothing).
    pub passes: usize,
    /// `collapse`: edges still shorter than the limit at the end, each refused by the core;
    /// counted by the rule that refused it.
    pub refusals: BTreeMap<&'static str, usize>,
    /// Reading and building, ms.
    pub read_ms: f64,
    /// The edit itself, ms.
    pub edit_ms: f64,
    /// Export and write, ms.
    pub write_ms: f64,
}

impl EditReport {
    /// Edges still shorter than the collapse limit (all refused).
    pub fn remaining_short(&self) -> usize {
        self.refusals.values().sum()
    }
}

impl fmt::Display for EditReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "mesh {}: {} -> {}",
            self.command,
            crate::text::path(&self.input),
            crate::text::path(&self.output)
        )?;
        writeln!(f, "  before  {}", self.before)?;
        for (i, (c, ms)) in self.levels.iter().enumerate() {
            writeln!(f, "  level {}  {c}  ({ms:.1} ms)", i + 1)?;
        }
        if let Some((a, b)) = self.roughness {
            writeln!(f, "  roughness (mean |L(v)|)  {a:.6e} -> {b:.6e}")?;
        }
        if self.command == "collapse" {
            writeln!(
                f,
                "  collapsed {} edges in {} passes; {} short edges left",
                self.collapsed,
                self.passes,
                self.remaining_short()
            )?;
            for (reason, n) in &self.refusals {
                writeln!(f, "    refused ({reason}): {n}")?;
            }
        }
        writeln!(f, "  after   {}", self.after)?;
        writeln!(
            f,
            "  time    read+build {:.1} ms, {} {:.1} ms, export+write {:.1} ms",
            self.read_ms, self.command, self.edit_ms, self.write_ms
        )
    }
}

/// Says on stderr what the input held that the output OBJ (positions and triangles only)
/// will not: never a silent loss.
fn warn_not_carried(input: &Path, output: &Path, dropped: &NotCarried) {
    if !dropped.is_empty() {
        crate::note!(
            "note: {} -> {}: not carried over (the output holds vertices and triangles only): {dropped}",
            text::path(input),
            text::path(output)
        );
    }
}

fn core_error(path: &Path, what: impl fmt::Display) -> Error {
    Error::input(Location::file(path), what.to_string())
}

/// `mesh subdivide`: `levels` levels of Loop subdivision. Vertex `i < V` of the output is input
/// vertex `i` moved by the vertex rule (unreferenced vertices stay put); vertex `V + e` is the
/// new vertex on edge `e` of the level's input, so each level has V + E vertices, 2E + 3F
/// edges and 4F faces (the core's numbering, see `Mesh::subdivide_loop`).
pub fn subdivide(args: &SubdivideArgs) -> Result<EditReport> {
    edit_file(
        "subdivide",
        &args.input,
        &args.output,
        args.force,
        |mesh, lines, report| subdivide_mesh(args, &mesh, lines, report),
    )
}

/// The `mesh subdivide` edit of a built `mesh` (see [`subdivide`]): the exported result. A
/// refusal names the input's vertices by OBJ number and its faces by `f` line (`lines`).
fn subdivide_mesh(
    args: &SubdivideArgs,
    mesh: &SliceMesh<'_>,
    lines: &ObjLines,
    report: &mut EditReport,
) -> Result<Exported> {
    // Refuse before allocating anything when a level would exceed what the core can index
    // or the memory limit (every level's buffers stay alive until the export).
    let mut c = mesh.len();
    let mut bytes = Some(0u64);
    for level in 1..=args.levels {
        c = c.after_loop();
        let over: Vec<String> = [
            (c.vertices, "vertices"),
            (c.edges, "edges"),
            (c.faces, "faces"),
        ]
        .into_iter()
        .filter(|&(n, _)| n > MAX_ELEMENTS)
        .map(|(n, what)| format!("{n} {what}"))
        .collect();
        if !over.is_empty() {
            let each = if over.len() > 1 { " each" } else { "" };
            return Err(Error::Usage(format!(
                "--levels {}: level {level} would need {}, more than the half-edge core's {MAX_ELEMENTS}{each}",
                args.levels,
                over.join(" and ")
            )));
        }
        bytes = bytes.and_then(|b| b.checked_add(level_bytes(c)?));
    }
    check_memory(&format!("--levels {}", args.levels), bytes)?;
    let t1 = Instant::now();
    let mut export_ms = 0.0;
    let exported = subdivide_levels(
        mesh,
        args.levels,
        args.weights.into(),
        &mut report.levels,
        &mut export_ms,
    )
    .map_err(|e| match e {
        // Named by the file's vertex numbers, not the core's edge index. Only the input mesh
        // can have coincident faces (every face of a subdivided one has a vertex of its own),
        // so the edge is the input's.
        SubdivideError::CoincidentFaces(edge) => match mesh.edge_vertices(edge) {
            Some([a, b]) => {
                // Faces are the file's triangles in order, so each has the line of its `f`.
                let face_lines: Vec<usize> = (0..2)
                    .filter_map(|side| mesh.face(edge.halfedge(side)))
                    .filter_map(|f| lines.triangle(f.index()))
                    .collect();
                let (at, on_lines) = match face_lines[..] {
                    [l0, l1] => (
                        Location::file(&args.input).line(l0.min(l1)),
                        format!(" (the `f` lines {} and {})", l0.min(l1), l0.max(l1)),
                    ),
                    _ => (Location::file(&args.input), String::new()),
                };
                Error::input(
                    at,
                    format!(
                        "Loop subdivision refused: the two faces{on_lines} on the edge of vertices {} and {} have the same three vertices",
                        a.index() + 1,
                        b.index() + 1
                    ),
                )
            }
            None => core_error(&args.input, e),
        },
        e => core_error(&args.input, e),
    })?;
    report.edit_ms = ms_since(t1) - export_ms;
    report.after = report.levels.last().map_or(report.before, |l| l.0);
    report.write_ms = export_ms;
    Ok(exported)
}

/// A mesh exported for writing: positions and triangles.
type Exported = (Vec<Vec3>, Vec<[u32; 3]>);

/// The frame of every editing command: reserves `output` (refusing an output that is the
/// input, and one that is read-only or hard-linked without `force`), reads `input` (warning
/// about what the output will not carry) and builds the half-edge mesh, then runs `edit` on it
/// and the file's lines (face `i` of the mesh is triangle `i` of the file) and writes the mesh
/// it returns. The report it hands `edit` has the command, paths, `before` counts and
/// `read_ms` filled in; `edit` fills in the rest, and the time of the write is added to
/// `write_ms`.
fn edit_file(
    command: &'static str,
    input: &Path,
    output: &Path,
    force: bool,
    edit: impl FnOnce(SliceMesh<'_>, &ObjLines, &mut EditReport) -> Result<Exported>,
) -> Result<EditReport> {
    let out = reserve_output(input, output, force)?;
    let t0 = Instant::now();
    let file = read_obj_file_within(input, MeshBuffers::READ_BUDGET)?;
    warn_not_carried(input, output, &file.not_carried);
    let mut buffers = MeshBuffers::for_obj(&file.mesh, input)?;
    let mesh = build_mesh(&file.mesh, Some(&file.lines), input, &mut buffers)?;
    let mut report = EditReport {
        command,
        input: input.to_path_buf(),
        output: output.to_path_buf(),
        before: mesh.len().into(),
        read_ms: ms_since(t0),
        ..EditReport::default()
    };
    let (p, t) = edit(mesh, &file.lines, &mut report)?;
    refuse_outside_domain(command, output, &p)?;
    let t2 = Instant::now();
    write_obj_to(out, &p, &t)?;
    report.write_ms += ms_since(t2);
    Ok(report)
}

/// Refuses an edit whose result has a vertex the OBJ reader would refuse (non-finite, or
/// beyond [`MAX_COORDINATE`]: `mesh smooth` with a huge `--step` moves vertices that far),
/// so that no command writes a mesh that halfray cannot read back.
fn refuse_outside_domain(command: &str, output: &Path, positions: &[Vec3]) -> Result<()> {
    match first_outside_domain(positions) {
        None => Ok(()),
        Some(i) => {
            let p = positions[i];
            Err(Error::Usage(format!(
                "mesh {command}: the result's vertex {} ({:e}, {:e}, {:e}) is outside the coordinate domain ±{MAX_COORDINATE:e} (obj::MAX_COORDINATE), so `{}` would not read back; nothing written",
                i + 1,
                p.x,
                p.y,
                p.z,
                text::path(output)
            )))
        }
    }
}

/// Ends an in-place edit begun at `t1`: records its time and the counts after it, and exports
/// the mesh (the export's time counted in `write_ms`).
fn export_edited<S: MeshStorage>(mesh: &Mesh<S>, report: &mut EditReport, t1: Instant) -> Exported {
    report.edit_ms = ms_since(t1);
    report.after = mesh.len().into();
    let t2 = Instant::now();
    let exported = export(mesh);
    report.write_ms = ms_since(t2);
    exported
}

/// Bytes of one subdivision level's half-edge records plus its export (positions and
/// triangles), `None` on overflow.
fn level_bytes(c: Counts) -> Option<u64> {
    use std::mem::size_of;
    let v = (c.vertices as u64).checked_mul(size_of::<Vec3>() as u64)?;
    let f = (c.faces as u64).checked_mul(size_of::<[u32; 3]>() as u64)?;
    MeshBuffers::bytes(c)?.checked_add(v)?.checked_add(f)
}

/// Subdivides `levels` times (each level in fresh buffers of exactly the needed size) and
/// exports the result.
fn subdivide_levels<S: MeshStorage>(
    m: &Mesh<S>,
    levels: u32,
    weights: LoopWeights,
    stats: &mut Vec<(Vef, f64)>,
    export_ms: &mut f64,
) -> std::result::Result<(Vec<Vec3>, Vec<[u32; 3]>), SubdivideError> {
    if levels == 0 {
        let t = Instant::now();
        let out = export(m);
        *export_ms = ms_since(t);
        return Ok(out);
    }
    let mut buffers = MeshBuffers::new(m.len().after_loop());
    let mut out = buffers.mesh();
    let t = Instant::now();
    m.subdivide_loop(&mut out, weights)?;
    stats.push((out.len().into(), ms_since(t)));
    subdivide_levels(&out, levels - 1, weights, stats, export_ms)
}

/// Mean `|L(v)|` over live vertices with at least one neighbour.
fn roughness<S: MeshStorage>(m: &Mesh<S>) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for v in m.vertices() {
        if m.is_isolated(v) {
            continue;
        }
        // The length in `f64`: an `f32` one overflows for components beyond 1.8e19.
        sum += m.laplacian(v).unwrap_or(Vec3::ZERO).as_dvec3().length();
        n += 1;
    }
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// `mesh smooth`: `iterations` Jacobi steps `x' = x + k·L(x)` (uniform Laplacian over the
/// one-ring), each computed entirely from the previous step's positions. Boundary vertices move
/// like the others unless `fix_boundary`; unreferenced vertices never move. Vertex and face
/// order are unchanged.
pub fn smooth(args: &SmoothArgs) -> Result<EditReport> {
    if !args.step.is_finite() {
        return Err(Error::Usage(format!(
            "--step {}: must be a finite number",
            args.step
        )));
    }
    edit_file(
        "smooth",
        &args.input,
        &args.output,
        args.force,
        |mut mesh, _, report| smooth_mesh(args, &mut mesh, report),
    )
}

/// The `mesh smooth` edit of a built `mesh` (see [`smooth`]), in place: the exported result.
fn smooth_mesh(
    args: &SmoothArgs,
    mesh: &mut SliceMesh<'_>,
    report: &mut EditReport,
) -> Result<Exported> {
    let boundary = if args.fix_boundary {
        DiffuseBoundary::Fixed
    } else {
        DiffuseBoundary::Free
    };
    let t1 = Instant::now();
    let before = roughness(mesh);
    let mut scratch = vec![Vec3::ZERO; mesh.slots().vertices];
    for i in 0..args.iterations {
        mesh.diffuse(args.step, boundary, &mut scratch)
            .map_err(|e| match e {
                // The input's vertices are finite and within the coordinate domain (the reader
                // checks), so a position that overflows is the step's doing: a usage error,
                // as `refuse_outside_domain`'s.
                DiffuseError::NonFinite => Error::Usage(format!(
                    "mesh smooth: smoothing step {} with --step {} moves a vertex beyond f32's range; use a smaller --step or fewer --iterations; nothing written",
                    i + 1,
                    args.step
                )),
                e => core_error(&args.input, format!("smoothing step {}: {e}", i + 1)),
            })?;
    }
    report.roughness = Some((before, roughness(mesh)));
    Ok(export_edited(mesh, report, t1))
}

/// The rule that refused a collapse, as a short name for the report.
pub fn refusal_name(e: &CollapseError) -> &'static str {
    match e {
        CollapseError::Dead => "dead edge",
        CollapseError::LinkCondition(_) => "link condition",
        CollapseError::WingsCoincide => "wings coincide",
        CollapseError::Ear(_) => "ear (two boundary edges)",
        CollapseError::InteriorEdgeJoinsBoundaries => "interior edge joins two boundaries",
        CollapseError::WingValence(_) => "wing valence 3",
        CollapseError::FoldOver(_) => "fold-over",
        CollapseError::NonFinitePosition => "non-finite position",
        // A rule added to the core after this list: its own text.
        _ => "another rule",
    }
}

/// The squared length of edge `e`, in `f64` from its `f32` end points: each difference is
/// exact unless the coordinates' magnitudes are more than `2²⁹` apart, and the sum of squares
/// is within a relative `3·2⁻⁵³` of the exact square, so that only an edge that close to the
/// limit can be judged either way (in `f32` one `√5` long was not shorter than `2.236068`).
fn edge_length_squared<S: MeshStorage>(m: &Mesh<S>, e: EdgeId) -> Option<f64> {
    let [a, b] = m.edge_vertices(e)?;
    Some((m.position(a)?.as_dvec3() - m.position(b)?.as_dvec3()).length_squared())
}

/// `mesh collapse`: collapses every edge strictly shorter than `shorter_than` (the length
/// compared in `f64`, `edge_length_squared`, with the limit as read, an `f32`) into its
/// midpoint. Each pass visits the short edges shortest first (re-measured when visited, since
/// earlier collapses move vertices) and collapses those the core allows; passes repeat until
/// one collapses nothing. The edges still short after that pass were all refused; they are
/// counted by the refusing rule. The mesh is then validated, compacted (vertices renumbered)
/// and written.
pub fn collapse(args: &CollapseArgs) -> Result<EditReport> {
    let limit = args.shorter_than;
    if !(limit.is_finite() && limit > 0.0) {
        return Err(Error::Usage(format!(
            "--shorter-than {limit}: must be a finite positive length"
        )));
    }
    edit_file(
        "collapse",
        &args.input,
        &args.output,
        args.force,
        |mut mesh, _, report| collapse_mesh(args, &mut mesh, report),
    )
}

/// The `mesh collapse` edit of a built `mesh` (see [`collapse`]), in place: the exported result.
fn collapse_mesh(
    args: &CollapseArgs,
    mesh: &mut SliceMesh<'_>,
    report: &mut EditReport,
) -> Result<Exported> {
    let limit = f64::from(args.shorter_than).powi(2);
    let t1 = Instant::now();
    loop {
        report.passes += 1;
        let mut short: Vec<(f64, EdgeId)> = mesh
            .edges()
            .filter_map(|e| edge_length_squared(mesh, e).map(|l| (l, e)))
            .filter(|&(l, _)| l < limit)
            .collect();
        short.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut refusals = BTreeMap::new();
        let mut collapsed = 0;
        for (_, e) in short {
            // Earlier collapses in this pass may have removed or stretched the edge.
            match edge_length_squared(mesh, e) {
                Some(l) if l < limit => {}
                _ => continue,
            }
            match mesh.collapse_edge(e.halfedge(0), CollapseAt::Midpoint) {
                Ok(_) => collapsed += 1,
                Err(err) => *refusals.entry(refusal_name(&err)).or_insert(0) += 1,
            }
        }
        report.collapsed += collapsed;
        if collapsed == 0 {
            report.refusals = refusals;
            break;
        }
    }
    mesh.validate().map_err(|e| {
        Error::internal(
            format!(
                "{}: mesh invalid after collapsing",
                crate::text::path(&args.input)
            ),
            Some(Box::new(e)),
        )
    })?;
    mesh.compact(|_| {});
    Ok(export_edited(mesh, report, t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use halfray_core::halfedge::{FaceId, VertexId};

    /// Every rule the core names has its own name in the report: none falls through to the
    /// catch-all kept for rules added later.
    #[test]
    fn every_collapse_refusal_has_its_own_name() {
        let (v, f) = (VertexId::new(0), FaceId::new(0));
        let rules = [
            CollapseError::Dead,
            CollapseError::LinkCondition(v),
            CollapseError::WingsCoincide,
            CollapseError::Ear(f),
            CollapseError::InteriorEdgeJoinsBoundaries,
            CollapseError::WingValence(v),
            CollapseError::FoldOver(f),
            CollapseError::NonFinitePosition,
        ];
        let names: std::collections::BTreeSet<_> = rules.iter().map(refusal_name).collect();
        assert_eq!(names.len(), rules.len(), "{names:?}");
        assert!(!names.contains("another rule"), "{names:?}");
    }

    /// A level's estimate is what it allocates: the half-edge buffers of its counts (measured
    /// on the buffers themselves) plus its export, a position per vertex and three indices
    /// per face.
    #[test]
    fn a_levels_estimate_is_its_buffers_and_its_export() {
        let c = Counts {
            vertices: 7,
            edges: 11,
            faces: 5,
        };
        let b = MeshBuffers::new(c);
        let records = std::mem::size_of_val(&b.vertices[..])
            + std::mem::size_of_val(&b.edges[..])
            + std::mem::size_of_val(&b.faces[..]);
        let export = 7 * std::mem::size_of::<Vec3>() + 5 * 3 * std::mem::size_of::<u32>();
        assert_eq!(level_bytes(c), Some((records + export) as u64));
        let huge = Counts {
            vertices: usize::MAX,
            ..c
        };
        assert_eq!(level_bytes(huge), None);
    }
}
