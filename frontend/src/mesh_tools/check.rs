//! `halfray mesh check`: what the half-edge core thinks of a mesh.
//!
//! # Definitions
//! As in `../shared/meshes/README.md`, except the genus (below).
//! * V = `v` statements (every vertex of the file); **referenced** vertices are those some
//!   triangle uses; unreferenced ones become isolated vertices of the half-edge mesh.
//! * E = distinct undirected vertex pairs used by a triangle side; F = triangles (after fan
//!   triangulation of polygons).
//! * Boundary edges have one face; boundary loops are the closed loops of boundary halfedges
//!   (on a manifold mesh, the connected components of the boundary-edge graph).
//! * **χ = V_referenced − E + F**: unreferenced vertices do not count (they are not part of the
//!   surface; counting them would make the bunny's χ depend on 1113 stray points).
//! * Components: faces connected through shared edges.
//! * **Genus** g = (2·components − χ − boundary_loops)/2, the genus of an orientable surface
//!   with boundary, from χ = Σ (2 − 2gᵢ − bᵢ) over its components; it is the total genus of
//!   all components (bunny: (2 − (−3) − 5)/2 = 0; torus: (2 − 0 − 0)/2 = 1). Reported for every
//!   mesh the core accepts (manifold and consistently oriented by construction), open or
//!   closed. The shared README defines genus as (2·components − χ)/2 for closed meshes only;
//!   on a closed mesh (no boundary loops) the two agree, on an open one only this one is given.
//!
//! A mesh the core rejects gets the counts that need no half-edge structure (V, referenced
//! vertices, E, F, χ), `manifold` false (or unknown, for an orientation error), the reason, and
//! a non-zero exit.

use super::{CheckArgs, MeshBuffers, build_mesh, ms_since};
use crate::console::print_out;
use crate::error::{Error, Location, Result};
use crate::obj::{ObjMesh, read_obj_file_within};
use crate::outputs::{Named, reserve_outputs};
use halfray_core::halfedge::{FaceId, Mesh, MeshStorage};
use std::fmt;
use std::path::Path;
use std::time::Instant;

/// The result of `mesh check`. Fields that need the half-edge structure are `None` for a
/// rejected mesh.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CheckReport {
    /// The input file.
    pub file: String,
    /// `true` when the half-edge core built the mesh.
    pub accepted: bool,
    /// Why the core rejected it (file, line, offending vertices by 1-based OBJ number).
    pub reason: Option<String>,
    /// Where the rejection points (not serialised; used for the error).
    #[serde(skip)]
    pub reason_at: Option<Location>,
    /// `v` statements.
    pub vertices: usize,
    /// Vertices used by some triangle.
    pub referenced_vertices: usize,
    /// Vertices used by no triangle.
    pub unreferenced_vertices: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Triangles.
    pub faces: usize,
    /// χ = referenced vertices − edges + faces.
    pub euler_characteristic: i64,
    /// Edge- and vertex-manifold (`None`: unknown, the core stopped at an orientation error).
    pub manifold: Option<bool>,
    /// Consistently oriented (`None`: unknown).
    pub oriented: Option<bool>,
    /// Edges with one face.
    pub boundary_edges: Option<usize>,
    /// Boundary loops.
    pub boundary_loops: Option<usize>,
    /// No boundary edge.
    pub closed: Option<bool>,
    /// Edge-connected components of the faces.
    pub components: Option<usize>,
    /// (2·components − χ − boundary_loops)/2.
    pub genus: Option<i64>,
    /// Time to read and parse the OBJ, ms.
    pub read_ms: f64,
    /// Time to build the half-edge mesh, ms.
    pub build_ms: f64,
    /// Time for the analysis (validate, boundary, components), ms.
    pub analyse_ms: f64,
}

/// Runs `mesh check`: reserves `--json` (refusing the input itself), checks, writes `--json`,
/// prints the report, and fails with the core's reason for a rejected mesh.
pub fn run(args: &CheckArgs) -> Result<()> {
    let json = match &args.json {
        Some(p) => reserve_outputs(
            &[Named::new("--json", p)],
            &[Named::new("input", &args.input)],
            args.force,
        )?
        .pop(),
        None => None,
    };
    let report = check(&args.input)?;
    if let Some(json) = json {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::encode("the JSON report", e))?;
        json.write(|w| w.write_all(text.as_bytes()))?;
    }
    print_out(&report.to_string())?;
    match (&report.reason, &report.reason_at) {
        (Some(reason), at) => Err(Error::input(
            at.clone().unwrap_or_else(|| Location::file(&args.input)),
            reason.clone(),
        )),
        (None, _) => Ok(()),
    }
}

/// Reads and checks `path`. A mesh the core rejects is an `Ok` report with `accepted: false`
/// and the reason; `Err` is for unreadable or malformed files.
pub fn check(path: &Path) -> Result<CheckReport> {
    let t0 = Instant::now();
    let file = read_obj_file_within(path, MeshBuffers::READ_BUDGET)?;
    let obj = &file.mesh;
    let read_ms = ms_since(t0);

    let mut used = vec![false; obj.positions.len()];
    for &i in obj.triangles.iter().flatten() {
        used[i as usize] = true;
    }
    let referenced = used.iter().filter(|&&u| u).count();
    let edges = count_edges(obj);
    let faces = obj.triangles.len();
    let chi = referenced as i64 - edges as i64 + faces as i64;
    let mut report = CheckReport {
        file: path.display().to_string(),
        accepted: false,
        reason: None,
        reason_at: None,
        vertices: obj.positions.len(),
        referenced_vertices: referenced,
        unreferenced_vertices: obj.positions.len() - referenced,
        edges,
        faces,
        euler_characteristic: chi,
        manifold: None,
        oriented: None,
        boundary_edges: None,
        boundary_loops: None,
        closed: None,
        components: None,
        genus: None,
        read_ms,
        build_ms: 0.0,
        analyse_ms: 0.0,
    };

    let t1 = Instant::now();
    let mut buffers = MeshBuffers::for_obj(obj, path)?;
    let built = build_mesh(obj, Some(&file.lines), path, &mut buffers);
    report.build_ms = ms_since(t1);
    let mesh = match built {
        Ok(m) => m,
        Err(Error::Input { at, message }) => {
            let orientation = message.starts_with("inconsistent orientation");
            report.manifold = if orientation { None } else { Some(false) };
            report.oriented = if orientation { Some(false) } else { None };
            report.reason = Some(message);
            report.reason_at = Some(at);
            return Ok(report);
        }
        Err(e) => return Err(e),
    };

    let t2 = Instant::now();
    mesh.validate().map_err(|e| {
        Error::internal(
            format!("{}: built mesh fails validation", crate::text::path(path)),
            Some(Box::new(e)),
        )
    })?;
    let c = mesh.len();
    if c.edges != edges || c.faces != faces || c.vertices != obj.positions.len() {
        return Err(Error::internal(
            format!(
                "{}: half-edge counts {c:?} disagree with the triangle list (E {edges}, F {faces})",
                crate::text::path(path)
            ),
            None,
        ));
    }
    let boundary_edges = mesh.edges().filter(|&e| mesh.is_boundary_edge(e)).count();
    let loops = boundary_loop_count(&mesh);
    let components = face_components(&mesh);
    let numerator = 2 * components as i64 - chi - loops as i64;
    report.accepted = true;
    report.manifold = Some(true);
    report.oriented = Some(true);
    report.boundary_edges = Some(boundary_edges);
    report.boundary_loops = Some(loops);
    report.closed = Some(boundary_edges == 0);
    report.components = Some(components);
    report.genus = (numerator >= 0 && numerator % 2 == 0).then_some(numerator / 2);
    report.analyse_ms = ms_since(t2);
    Ok(report)
}

/// Distinct undirected edges of the triangle list (sorted keys, no hashing).
fn count_edges(obj: &ObjMesh) -> usize {
    let mut keys: Vec<u64> = obj
        .triangles
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (u64::from(a.min(b)) << 32) | u64::from(a.max(b)))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

/// Boundary loops, in O(boundary halfedges): walk each unvisited boundary halfedge's loop.
fn boundary_loop_count<S: MeshStorage>(mesh: &Mesh<S>) -> usize {
    let mut seen = vec![false; mesh.slots().edges * 2];
    let mut loops = 0;
    for h in mesh.halfedges() {
        if !mesh.is_boundary_halfedge(h) || seen[h.raw() as usize] {
            continue;
        }
        loops += 1;
        for g in mesh.loop_halfedges(h) {
            seen[g.raw() as usize] = true;
        }
    }
    loops
}

/// Edge-connected components of the faces (depth-first over face neighbours).
fn face_components<S: MeshStorage>(mesh: &Mesh<S>) -> usize {
    let mut seen = vec![false; mesh.slots().faces];
    let mut stack: Vec<FaceId> = Vec::new();
    let mut components = 0;
    for f in mesh.faces() {
        if seen[f.index()] {
            continue;
        }
        components += 1;
        seen[f.index()] = true;
        stack.push(f);
        while let Some(g) = stack.pop() {
            for n in mesh.face_neighbors(g) {
                if !seen[n.index()] {
                    seen[n.index()] = true;
                    stack.push(n);
                }
            }
        }
    }
    components
}

fn yes_no(b: Option<bool>) -> &'static str {
    match b {
        Some(true) => "yes",
        Some(false) => "no",
        None => "unknown",
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", crate::text::escaped(&self.file))?;
        writeln!(
            f,
            "  vertices        {} ({} referenced, {} unreferenced)",
            self.vertices, self.referenced_vertices, self.unreferenced_vertices
        )?;
        match self.boundary_edges {
            Some(b) => writeln!(f, "  edges           {} ({b} boundary)", self.edges)?,
            None => writeln!(f, "  edges           {}", self.edges)?,
        }
        writeln!(f, "  faces           {}", self.faces)?;
        match &self.reason {
            Some(reason) => {
                writeln!(f, "  half-edge build rejected: {reason}")?;
                writeln!(f, "  manifold        {}", yes_no(self.manifold))?;
                writeln!(f, "  oriented        {}", yes_no(self.oriented))?;
            }
            None => {
                writeln!(
                    f,
                    "  manifold        yes (half-edge build accepted, validated)"
                )?;
                writeln!(f, "  oriented        yes")?;
                writeln!(f, "  closed          {}", yes_no(self.closed))?;
                writeln!(
                    f,
                    "  boundary loops  {}",
                    self.boundary_loops.unwrap_or_default()
                )?;
                writeln!(
                    f,
                    "  components      {}",
                    self.components.unwrap_or_default()
                )?;
            }
        }
        writeln!(
            f,
            "  Euler χ         {} (= V_referenced − E + F = {} − {} + {})",
            self.euler_characteristic, self.referenced_vertices, self.edges, self.faces
        )?;
        if self.accepted {
            match self.genus {
                Some(g) => writeln!(
                    f,
                    "  genus           {g} (= (2·components − χ − boundary loops)/2)"
                )?,
                None => writeln!(f, "  genus           undefined")?,
            }
        }
        writeln!(
            f,
            "  time            read {:.1} ms, build {:.1} ms, analyse {:.1} ms",
            self.read_ms, self.build_ms, self.analyse_ms
        )
    }
}
