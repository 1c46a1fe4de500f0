//! `halfray mesh ...`: mesh tools over the half-edge core (`halfray_core::halfedge`).
//!
//! | command | what it does |
//! |---|---|
//! | `mesh check IN.obj [--json FILE]` | counts, manifoldness, boundary, Euler characteristic, components, genus ([`check()`], [`check`](mod@check)) |
//! | `mesh subdivide IN.obj -o OUT.obj --levels N [--weights warren\|loop]` | Loop subdivision ([`edit::subdivide`]) |
//! | `mesh smooth IN.obj -o OUT.obj --step K --iterations N [--fix-boundary]` | uniform Laplacian diffusion ([`edit::smooth`]) |
//! | `mesh collapse IN.obj -o OUT.obj --shorter-than L` | short-edge collapse ([`edit::collapse`]) |
//! | `mesh generate KIND --seed N -o OUT.obj [--size N]` | a generated mesh of the benchmark corpus ([`generate`](mod@generate)) |
//!
//! Input goes through the strict, order-preserving reader [`crate::obj::read_obj_file_within`]
//! (vertex `i` of the file is vertex `i` of the mesh; unreferenced vertices are kept as
//! isolated vertices) into a [`SliceMesh`] over `Vec`s sized from the input ([`MeshBuffers`]);
//! a file whose parse and half-edge mesh would exceed the memory limit is refused while it is
//! read, at the line where they do ([`MeshBuffers::READ_BUDGET`]). A mesh the
//! half-edge core rejects (non-manifold edge or vertex, inconsistent orientation, a triangle
//! repeating a vertex) is an input error naming the file, the line of the offending `v` or `f`
//! statement, and the offending vertices by their **1-based OBJ vertex numbers**
//! ([`build_mesh`]). Outputs are written atomically ([`crate::obj::write_obj`]); every command
//! reports V/E/F before and after and its timing. Errors exit with status 1 (see `main.rs`).

pub mod check;
pub mod edit;
pub mod generate;

use crate::console::print_out;
use crate::error::{Error, Location, Result};
use crate::obj::{ObjLines, ObjMesh, ReadBudget};
use crate::outputs::{Named, OutputFile, reserve_outputs};
use halfray_core::halfedge::{
    BuildError, Counts, Culprit, EdgeRec, FaceRec, MAX_ELEMENTS, MeshStorage, SliceMesh, VertexRec,
    build_scratch_len,
};
use std::path::{Path, PathBuf};

pub use check::{CheckReport, check};
pub use edit::{EditReport, collapse, smooth, subdivide};

/// `halfray mesh ...`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum MeshCommand {
    /// Check manifoldness, boundary loops, Euler characteristic χ = V − E + F (referenced
    /// vertices) and genus g = (2·components − χ − boundary loops)/2, the genus of a surface
    /// with boundary (given for open meshes too). Exits with status 1 and the reason when the
    /// half-edge core rejects the mesh.
    Check(CheckArgs),
    /// Loop subdivision: original vertices keep their indices, one new vertex per edge is
    /// appended (V' = V + E per level).
    Subdivide(SubdivideArgs),
    /// Uniform Laplacian smoothing (diffusion), every step from the previous step's positions.
    Smooth(SmoothArgs),
    /// Collapse edges shorter than a length (into their midpoints) until none can be collapsed.
    Collapse(CollapseArgs),
    /// Generate a mesh of the benchmark corpus from a seed (displaced sphere, terrain, beams,
    /// room, scatter, far from the origin).
    Generate(generate::GenerateArgs),
}

/// `halfray mesh check`.
#[derive(clap::Args, Debug, Clone)]
pub struct CheckArgs {
    /// Input OBJ.
    pub input: PathBuf,
    /// Also write the report as JSON to this file (written even when the mesh is rejected).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Replace a `--json` file that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
}

/// Vertex weights of Loop subdivision (`--weights`).
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Weights {
    /// Warren's β = 3/(8n) (n > 3), 3/16 (n = 3).
    #[default]
    Warren,
    /// Loop's original β = (5/8 − (3/8 + cos(2π/n)/4)²)/n.
    Loop,
}

impl From<Weights> for halfray_core::halfedge::LoopWeights {
    fn from(w: Weights) -> Self {
        match w {
            Weights::Warren => Self::Warren,
            Weights::Loop => Self::Loop,
        }
    }
}

/// `halfray mesh subdivide`.
#[derive(clap::Args, Debug, Clone)]
pub struct SubdivideArgs {
    /// Input OBJ.
    pub input: PathBuf,
    /// Output OBJ (written atomically; never the input).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
    /// Number of subdivision levels (each multiplies the face count by 4), at most 15
    /// (`MAX_LEVELS`: one triangle's level 15 already outgrows the core).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_LEVELS)))]
    pub levels: u32,
    /// Vertex weights.
    #[arg(long, value_enum, default_value_t = Weights::Warren)]
    pub weights: Weights,
}

/// The most levels `mesh subdivide` takes: each level multiplies the face count by 4, so a
/// mesh of one face passes the half-edge core's
/// [`MAX_ELEMENTS`] faces (`2³⁰ − 1`) at this level
/// (`4^15 = 2³⁰`) and no mesh with a face can take more; one without faces is unchanged by any
/// number.
pub const MAX_LEVELS: u32 =
    (usize::BITS - halfray_core::halfedge::MAX_ELEMENTS.leading_zeros()).div_ceil(2);

/// `halfray mesh smooth`.
#[derive(clap::Args, Debug, Clone)]
pub struct SmoothArgs {
    /// Input OBJ.
    pub input: PathBuf,
    /// Output OBJ (written atomically; never the input).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
    /// Step k of x' = x + k·L(x), with L the uniform Laplacian (1 moves every vertex to its
    /// neighbours' centroid; 0 < k ≤ 1 is stable).
    #[arg(long, default_value_t = 0.5, value_parser = crate::cli_values::finite_f32, allow_negative_numbers = true)]
    pub step: f32,
    /// Number of diffusion steps, at most 10 000 (`scene::MAX_SMOOTH_ITERATIONS`, as in a
    /// scene's `smooth`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=i64::from(crate::scene::MAX_SMOOTH_ITERATIONS)))]
    pub iterations: u32,
    /// Keep boundary vertices in place (by default they move towards all their neighbours,
    /// which shrinks open rims).
    #[arg(long)]
    pub fix_boundary: bool,
}

/// `halfray mesh collapse`.
#[derive(clap::Args, Debug, Clone)]
pub struct CollapseArgs {
    /// Input OBJ.
    pub input: PathBuf,
    /// Output OBJ (written atomically; never the input), compacted: the vertices, edges and
    /// faces the collapses free are dropped (the input's own unreferenced vertices are kept, as
    /// the other mesh tools keep them).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
    /// Collapse every edge strictly shorter than this length (in model units).
    #[arg(long, value_name = "L", value_parser = crate::cli_values::finite_f32, allow_negative_numbers = true)]
    pub shorter_than: f32,
}

/// Runs a mesh subcommand, printing its report to stdout (after every file is written).
pub fn run(cmd: &MeshCommand) -> Result<()> {
    match cmd {
        MeshCommand::Check(args) => check::run(args),
        MeshCommand::Subdivide(args) => print_out(&edit::subdivide(args)?.to_string()),
        MeshCommand::Smooth(args) => print_out(&edit::smooth(args)?.to_string()),
        MeshCommand::Collapse(args) => print_out(&edit::collapse(args)?.to_string()),
        MeshCommand::Generate(args) => generate::run(args),
    }
}

/// Reserves an editing command's `-o` before any work (see [`reserve_outputs`]), refusing the
/// input file itself.
pub fn reserve_output(input: &Path, output: &Path, force: bool) -> Result<OutputFile> {
    let mut reserved = reserve_outputs(
        &[Named::new("-o", output)],
        &[Named::new("input", input)],
        force,
    )?;
    Ok(reserved.remove(0))
}

/// Owned record buffers for a [`SliceMesh`]; their lengths are the mesh's capacity.
#[derive(Debug, Default)]
pub struct MeshBuffers {
    vertices: Vec<VertexRec>,
    edges: Vec<EdgeRec>,
    faces: Vec<FaceRec>,
}

impl MeshBuffers {
    /// Buffers for `capacity` vertices, edges and faces.
    pub fn new(capacity: Counts) -> Self {
        Self {
            vertices: vec![VertexRec::EMPTY; capacity.vertices],
            edges: vec![EdgeRec::EMPTY; capacity.edges],
            faces: vec![FaceRec::EMPTY; capacity.faces],
        }
    }

    /// Buffers large enough to build `obj` read from `path`: its vertices, faces, and 3 edges
    /// per face (an upper bound; a closed mesh uses 1.5). Refused before anything is allocated
    /// when they and the build's scratch exceed the memory limit
    /// ([`crate::limits::MEMORY_LIMIT_BYTES`]), an input error naming `path`. A file read
    /// within [`MeshBuffers::READ_BUDGET`] has been refused while it was parsed already.
    pub fn for_obj(obj: &ObjMesh, path: &Path) -> Result<Self> {
        let f = obj.triangles.len();
        crate::limits::check_memory(
            &format!(
                "the half-edge mesh of {} vertices and {f} triangles",
                obj.positions.len()
            ),
            Self::obj_bytes(obj.positions.len(), f),
        )
        .map_err(|e| Error::input(Location::file(path), e.to_string()))?;
        Ok(Self::new(Self::obj_capacity(obj.positions.len(), f)))
    }

    /// How an OBJ is read for the half-edge mesh: the file, its parse and
    /// [`MeshBuffers::obj_bytes`] of what has been read, within the memory limit.
    pub const READ_BUDGET: ReadBudget<'static> = ReadBudget {
        limit: crate::limits::MEMORY_LIMIT_BYTES,
        need: Self::obj_bytes,
        what: "reading the file into a half-edge mesh",
    };

    /// The capacity [`MeshBuffers::for_obj`] gives a mesh of `vertices` and `triangles`.
    fn obj_capacity(vertices: usize, triangles: usize) -> Counts {
        Counts {
            vertices,
            edges: triangles.saturating_mul(3),
            faces: triangles,
        }
    }

    /// Bytes [`MeshBuffers::for_obj`] and [`build_mesh`] allocate for a mesh of `vertices` and
    /// `triangles`: the records and the build's scratch; `None` on overflow.
    pub fn obj_bytes(vertices: usize, triangles: usize) -> Option<u64> {
        let scratch = (build_scratch_len(triangles) as u64).checked_mul(size_of::<u32>() as u64)?;
        Self::bytes(Self::obj_capacity(vertices, triangles))?.checked_add(scratch)
    }

    /// Bytes of the records for `capacity`, `None` on overflow.
    pub fn bytes(capacity: Counts) -> Option<u64> {
        let v = (capacity.vertices as u64).checked_mul(size_of::<VertexRec>() as u64)?;
        let e = (capacity.edges as u64).checked_mul(size_of::<EdgeRec>() as u64)?;
        let f = (capacity.faces as u64).checked_mul(size_of::<FaceRec>() as u64)?;
        v.checked_add(e)?.checked_add(f)
    }

    /// An empty mesh over these buffers.
    pub fn mesh(&mut self) -> SliceMesh<'_> {
        SliceMesh::from_slices(&mut self.vertices, &mut self.edges, &mut self.faces)
    }
}

/// V/E/F of a mesh, for reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Vef {
    /// Vertices (including unreferenced ones).
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Faces.
    pub faces: usize,
}

impl From<Counts> for Vef {
    fn from(c: Counts) -> Self {
        Self {
            vertices: c.vertices,
            edges: c.edges,
            faces: c.faces,
        }
    }
}

impl std::fmt::Display for Vef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "V {} E {} F {}", self.vertices, self.edges, self.faces)
    }
}

/// Builds `obj` (read from `path`) into a half-edge mesh over `buffers` (sized by
/// [`MeshBuffers::for_obj`]). The core's rejection becomes an [`Error::Input`] naming `path`,
/// the line of the offending statement (from `lines`, the file's [`ObjLines`]; `None` for a
/// mesh that is no longer the file's, and then no line) and the offending vertices by 1-based
/// OBJ numbers; see [`describe_build_error`].
pub fn build_mesh<'b>(
    obj: &ObjMesh,
    lines: Option<&ObjLines>,
    path: &Path,
    buffers: &'b mut MeshBuffers,
) -> Result<SliceMesh<'b>> {
    if obj.positions.len() > MAX_ELEMENTS || obj.triangles.len() > MAX_ELEMENTS {
        return Err(Error::input(
            Location::file(path),
            format!(
                "too large for the half-edge core: {} vertices, {} triangles (at most {MAX_ELEMENTS} each)",
                obj.positions.len(),
                obj.triangles.len()
            ),
        ));
    }
    let mut mesh = buffers.mesh();
    let mut scratch = vec![0u32; build_scratch_len(obj.triangles.len())];
    match mesh.build(&obj.positions, &obj.triangles, &mut scratch) {
        Ok(()) => Ok(mesh),
        Err(e) => {
            let (at, message) = describe_build_error(&e, lines, path);
            Err(Error::input(at, message))
        }
    }
}

/// The location and message for a build error: the file and, given the file's `lines`, the
/// line of the offending `v` or `f` statement ([`BuildError::culprit`]), and the core's
/// sentence with vertices and triangles numbered from 1 as in the file (triangles counted
/// after fan triangulation, which for all-triangle files is the `f` line order).
pub fn describe_build_error(
    e: &BuildError,
    lines: Option<&ObjLines>,
    path: &Path,
) -> (Location, String) {
    let line = lines.and_then(|l| match e.culprit()? {
        Culprit::Vertex(v) => l.vertex(v.index()),
        Culprit::Face(f) => l.triangle(f.index()),
    });
    let at = Location::file(path);
    let at = match line {
        Some(line) => at.line(line),
        None => at,
    };
    (at, e.numbered_from(1).to_string())
}

/// Exports a compact-or-not mesh to positions and triangles (one position per vertex slot).
pub(crate) fn export<S: MeshStorage>(
    mesh: &halfray_core::halfedge::Mesh<S>,
) -> (Vec<glam::Vec3>, Vec<[u32; 3]>) {
    let mut p = vec![glam::Vec3::ZERO; mesh.slots().vertices];
    let mut t = vec![[0u32; 3]; mesh.len().faces];
    // The buffers are sized exactly as `export` asks, so it cannot fail.
    let _ = mesh.export(&mut p, &mut t);
    (p, t)
}

/// Milliseconds since `start`.
pub(crate) fn ms_since(start: std::time::Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
