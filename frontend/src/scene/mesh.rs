//! Mesh objects: OBJ loading, optional Laplacian smoothing and Loop subdivision through the
//! half-edge core, the BVH, and the closedness check CSG needs (made by
//! [`MeshShape::boundary_edges`] when a mesh is a CSG operand).

use crate::accel::MeshAccel;
use crate::error::{Error, Location, Result};
use crate::mesh_tools::{MeshBuffers, build_mesh, export};
use crate::obj::{MAX_COORDINATE, ObjFile, ObjLines, ObjMesh, first_outside_domain, read_obj_file};
use crate::scene::geom::MeshShape;
use glam::Vec3;
use halfray_core::halfedge::{DiffuseBoundary, LoopWeights, SliceMesh};
use std::path::Path;

/// Builds `mesh` (read from `path`; `lines` its statements' lines while it is still the
/// file's mesh) into a half-edge mesh over `buffers` (sized by [`MeshBuffers::for_obj`]) with
/// [`build_mesh`]: the core's rejection is an input error on `path` and the offending OBJ
/// line, `what: reason`, numbered from 1 as `mesh check` does.
fn build_half_edge<'b>(
    path: &Path,
    mesh: &ObjMesh,
    lines: Option<&ObjLines>,
    buffers: &'b mut MeshBuffers,
    what: &str,
) -> Result<SliceMesh<'b>> {
    build_mesh(mesh, lines, path, buffers).map_err(|e| match e {
        Error::Input { at, message } => Error::Input {
            at,
            message: format!("{what}: {message}"),
        },
        e => e,
    })
}

/// Area-weighted unit vertex normals, one per position, from the half-edge core
/// (`Mesh::vertex_normals`); a vertex without one (isolated, or whose faces cancel) gets
/// `Vec3::ZERO`, and shading falls back to the face normal there.
fn vertex_normals(path: &Path, mesh: &ObjMesh, lines: Option<&ObjLines>) -> Result<Vec<Vec3>> {
    let mut buffers = MeshBuffers::for_obj(mesh, path)?;
    let m = build_half_edge(
        path,
        mesh,
        lines,
        &mut buffers,
        &needs_manifold("smooth shading"),
    )?;
    let mut out = vec![Vec3::ZERO; m.slots().vertices];
    m.vertex_normals(&mut out)
        .map_err(|e| he_error(path, "vertex normals", e))?;
    out.truncate(mesh.positions.len());
    Ok(out)
}

fn he_error(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
    Error::input(Location::file(path), format!("{what}: {e}"))
}

/// The start of the message when the half-edge core rejects a scene mesh for the treatment
/// `what` (smoothing, subdivision, smooth shading): `what` needs a manifold mesh.
fn needs_manifold(what: &str) -> String {
    format!("{what} needs a manifold mesh; the half-edge core rejects this one")
}

/// One smoothing pass set: `iterations` Jacobi steps `x += step·L(x)`, boundary fixed.
fn smooth(
    path: &Path,
    mesh: &mut ObjMesh,
    lines: Option<&ObjLines>,
    step: f32,
    iterations: u32,
) -> Result<()> {
    let mut buffers = MeshBuffers::for_obj(mesh, path)?;
    let mut m = build_half_edge(path, mesh, lines, &mut buffers, &needs_manifold("smooth"))?;
    let mut tmp = vec![Vec3::ZERO; m.slots().vertices];
    for _ in 0..iterations {
        m.diffuse(step, DiffuseBoundary::Fixed, &mut tmp)
            .map_err(|e| he_error(path, "smoothing failed", e))?;
    }
    (mesh.positions, mesh.triangles) = export(&m);
    Ok(())
}

/// One level of Loop subdivision (Warren weights).
fn subdivide(path: &Path, mesh: &ObjMesh, lines: Option<&ObjLines>) -> Result<ObjMesh> {
    let mut buffers = MeshBuffers::for_obj(mesh, path)?;
    let m = build_half_edge(
        path,
        mesh,
        lines,
        &mut buffers,
        &needs_manifold("subdivide"),
    )?;
    let mut out_buffers = MeshBuffers::new(m.len().after_loop());
    let mut out = out_buffers.mesh();
    m.subdivide_loop(&mut out, LoopWeights::Warren)
        .map_err(|e| he_error(path, "Loop subdivision failed", e))?;
    let (positions, triangles) = export(&out);
    Ok(ObjMesh {
        positions,
        triangles,
    })
}

/// Bytes a scene mesh costs per triangle of its final (subdivided) form, for the memory check
/// before subdividing: the last level's half-edge buffers (~100 B per face), the exported mesh
/// (~20 B), and the BVH build (binary nodes and indices ~68 B, scratch 32 B, wide tree ~63 B),
/// rounded up. Bytes per triangle.
const SCENE_MESH_BYTES_PER_TRIANGLE: u64 = 320;

/// The setting of a scene's `[mesh.NAME]` that an error of [`load_mesh`] belongs to (where the
/// scene's message points).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshField {
    /// `file`: reading the OBJ, or building the mesh's tree.
    File,
    /// `smooth`: the smoothing failed, or moved a vertex outside the coordinate domain.
    Smooth,
    /// `subdivide`: the subdivision failed, or would exceed the memory limit.
    Subdivide,
    /// `shading`: the vertex normals of smooth shading could not be built.
    Shading,
}

/// Loads an OBJ, applies smoothing (`(step, iterations)`) then `subdivide` Loop levels, and
/// builds the BVH; with `smooth_shading`, also the area-weighted vertex normals. Subdivision is
/// refused before it starts when the final mesh would exceed the memory limit
/// ([`crate::limits::MEMORY_LIMIT_BYTES`]; each level multiplies the triangles by 4); smoothing
/// that moves a vertex outside the coordinate domain the OBJ reader enforces
/// ([`crate::obj::MAX_COORDINATE`]: beyond it a closed mesh lets rays through) is refused after
/// it. Each error comes with the setting it belongs to.
pub fn load_mesh(
    name: &str,
    path: &Path,
    smoothing: Option<(f32, u32)>,
    levels: u32,
    smooth_shading: bool,
) -> std::result::Result<MeshShape, (MeshField, Error)> {
    let file = |e| (MeshField::File, e);
    let ObjFile {
        mut mesh, lines, ..
    } = read_obj_file(path).map_err(file)?;
    // The file's lines name a rejected statement while the mesh is still the file's: through
    // smoothing (positions move, the triangles stay), not after a subdivision.
    let mut lines = Some(&lines);
    if mesh.triangles.is_empty() {
        return Err(file(Error::input(
            Location::file(path),
            "mesh has no triangles",
        )));
    }
    if levels > 0 {
        let bytes = (mesh.triangles.len() as u64)
            .checked_mul(4u64.checked_pow(levels).unwrap_or(u64::MAX))
            .and_then(|t| t.checked_mul(SCENE_MESH_BYTES_PER_TRIANGLE));
        crate::limits::check_memory(
            &format!(
                "`subdivide = {levels}` on {} triangles",
                mesh.triangles.len()
            ),
            bytes,
        )
        .map_err(|e| {
            (
                MeshField::Subdivide,
                Error::input(Location::file(path), e.to_string()),
            )
        })?;
    }
    if let Some((step, iterations)) = smoothing {
        let smoothing = |e| (MeshField::Smooth, e);
        smooth(path, &mut mesh, lines, step, iterations).map_err(smoothing)?;
        if let Some(i) = first_outside_domain(&mesh.positions) {
            let p = mesh.positions[i];
            return Err(smoothing(Error::input(
                Location::file(path),
                format!(
                    "smoothing moved vertex {} to ({:e}, {:e}, {:e}), outside the coordinate domain ±{MAX_COORDINATE:e} (obj::MAX_COORDINATE: beyond it a closed mesh lets rays through); use a smaller `step` or fewer `iterations`",
                    i + 1,
                    p.x,
                    p.y,
                    p.z
                ),
            )));
        }
    }
    for _ in 0..levels {
        mesh = subdivide(path, &mesh, lines).map_err(|e| (MeshField::Subdivide, e))?;
        lines = None;
    }
    let normals = if smooth_shading {
        Some(vertex_normals(path, &mesh, lines).map_err(|e| (MeshField::Shading, e))?)
    } else {
        None
    };
    Ok(MeshShape::new(
        name,
        MeshAccel::new(mesh).map_err(file)?,
        normals,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::boundary_edge_count;

    #[test]
    fn boundary_edges_of_open_and_closed_meshes() {
        assert_eq!(boundary_edge_count(&[[0, 1, 2]]), 3);
        let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        assert_eq!(boundary_edge_count(&tet), 0);
        // One face flipped: its three directed edges now repeat their neighbours'.
        let bad = [[0, 1, 2], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        assert!(boundary_edge_count(&bad) > 0);
    }

    /// A mesh shape of `triangles` over the unit cube's corners (`i` at `(i & 1, i >> 1 & 1,
    /// i >> 2)`).
    fn shape(triangles: &[[u32; 3]]) -> MeshShape {
        let positions = (0..8u32)
            .map(|i| Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2) as f32))
            .collect();
        let mesh = ObjMesh {
            positions,
            triangles: triangles.to_vec(),
        };
        MeshShape::new("m", crate::accel::MeshAccel::new(mesh).unwrap(), None)
    }

    /// The closedness is computed on the first call only, and is the count made by hand: a
    /// square (two triangles) has its 4 sides open, the cube without its top face the 4 edges
    /// of the hole, the closed cube and tetrahedron none.
    #[test]
    fn boundary_edges_are_counted_on_first_use() {
        // The cube's faces, outward, two triangles each: −z, +z, −y, +y, −x, +x.
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let cube: Vec<[u32; 3]> = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        let lidless: Vec<[u32; 3]> = cube[..2].iter().chain(&cube[4..]).copied().collect();
        let tetrahedron = [[0, 2, 1], [0, 1, 4], [1, 2, 4], [2, 0, 4]];
        for (triangles, open) in [
            (&cube[..2], 4),
            (&lidless[..], 4),
            (&cube[..], 0),
            (&tetrahedron[..], 0),
        ] {
            let m = shape(triangles);
            assert_eq!(m.closedness.get(), None);
            assert_eq!(m.boundary_edges(), open, "{triangles:?}");
            assert_eq!(m.closedness.get(), Some(&open));
        }
    }

    /// A scene's mesh is checked for closedness only where it is a CSG operand.
    #[test]
    fn only_csg_operands_count_boundary_edges() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/x.toml");
        let head = "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 6\n\n\
                    [material.m]\ndiffuse = [1, 0, 0]\n\n[mesh.cube]\nfile = \"meshes/cube.obj\"\n\n";
        let plain =
            format!("{head}[[object]]\ntype = \"mesh\"\nmesh = \"cube\"\nmaterial = \"m\"\n");
        let scene = crate::scene::parse(&plain, &dir).unwrap();
        assert_eq!(scene.meshes[0].closedness.get(), None);
        let csg = format!(
            "{head}[[object]]\ntype = \"csg\"\nop = \"union\"\nmaterial = \"m\"\noperands = [\n  \
             {{ type = \"mesh\", mesh = \"cube\" }},\n  {{ type = \"sphere\", center = [0, 0, 0], radius = 1 }},\n]\n"
        );
        let scene = crate::scene::parse(&csg, &dir).unwrap();
        assert_eq!(scene.meshes[0].closedness.get(), Some(&0));
    }
}
