//! A strict Wavefront OBJ reader and writer for triangle meshes.
//!
//! halfray reads OBJ itself rather than through `tobj`: the mesh tools promise that vertex `i`
//! of the file is vertex `i` of the mesh (subdivision appends new vertices after the original
//! ones, unreferenced vertices included), and general-purpose loaders re-index vertices per
//! object and drop unreferenced ones. The reader keeps the file's vertex order, welds nothing,
//! and reports errors with the file, line and column.
//!
//! Accepted (what Blender and MeshLab accept): LF, CRLF and old-Mac CR line ends; a UTF-8
//! byte-order mark; any bytes in comments (statements must be UTF-8); `v x y z`, `v x y z w`
//! and `v x y z r g b` (w and colours are read and not kept); `f a b c ...` with `a`, `a/t`,
//! `a//n`, `a/t/n` tokens and negative (relative) indices; polygons are fan-triangulated
//! `(v0, vi, vi+1)`. Ignored (and counted in [`NotCarried`], so that tools writing OBJ can say
//! what they drop): comments, `vt`, `vn`, `vp`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`.
//! Rejected with a located error (`file:line:column`): non-finite or malformed coordinates,
//! coordinates beyond ±[`MAX_COORDINATE`], a vertex with other than 3, 4 or 6 values, faces
//! with fewer than three vertices, a face token of another shape (`1/x`, `1///`), a vertex,
//! texture or normal index that is 0 or out of range (`1//0`, `1/5/7` before five `vt`),
//! non-UTF-8 statements, unknown statements, and a file that would not fit its [`ReadBudget`]
//! (its bytes, its parse and what the caller will build from it over the memory limit), at the
//! `v` or `f` statement where it would cross it.

use crate::error::{Error, Location, Result};
use crate::outputs::OutputFile;
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::Path;

/// Largest coordinate magnitude a mesh vertex may have: `2^125` (≈ 4.25e37), a quarter of the
/// `f32` range. The intersection tests work on `p − o` and on the sheared `x − s·z` with
/// `|s| ≤ 1`: with every vertex and ray origin within `±2^125`, `|p − o| ≤ 2^126` and the
/// sheared coordinates stay within `±2^127`, below `f32::MAX` (≈ 2^128). Beyond it they can
/// overflow to infinity and a closed mesh lets rays through (a tetrahedron at ±3e38 around
/// the camera leaked 630 of 768 rays), so the reader refuses such vertices.
pub const MAX_COORDINATE: f32 = 4.253_529_6e37;

/// The index of the first position outside the coordinate domain (non-finite, or beyond
/// ±[`MAX_COORDINATE`]), which the reader refuses: what an edit that moves vertices (Laplacian
/// smoothing with a large or negative step) must check before its result is used or written.
pub fn first_outside_domain(positions: &[Vec3]) -> Option<usize> {
    positions
        .iter()
        .position(|p| !(p.abs().max_element() <= MAX_COORDINATE))
}

/// What a file held that [`ObjMesh`] does not keep: statements by keyword (`vt`, `usemtl`,
/// `#` for comments, `v w` / `v rgb` for vertex weights and colours) and polygons split into
/// triangles.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NotCarried {
    /// Statements (and comments, as `#`) not kept, by keyword.
    pub statements: BTreeMap<String, usize>,
    /// Faces with more than three vertices, fan-triangulated.
    pub polygons_split: usize,
}

impl NotCarried {
    /// Nothing was dropped.
    pub fn is_empty(&self) -> bool {
        self.statements.is_empty() && self.polygons_split == 0
    }

    fn note(&mut self, what: &str) {
        *self.statements.entry(what.to_string()).or_insert(0) += 1;
    }
}

impl std::fmt::Display for NotCarried {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut parts: Vec<String> = self
            .statements
            .iter()
            .map(|(k, n)| match k.as_str() {
                "#" => format!("{n} comment line(s)"),
                _ => format!("{n} `{k}`"),
            })
            .collect();
        if self.polygons_split > 0 {
            parts.push(format!(
                "{} polygon(s) split into triangles",
                self.polygons_split
            ));
        }
        f.write_str(&parts.join(", "))
    }
}

/// The lines of a file: LF, CRLF and lone CR all end a line.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = Some(bytes);
    std::iter::from_fn(move || {
        let r = rest?;
        match r.iter().position(|&b| b == b'\n' || b == b'\r') {
            Some(i) => {
                let skip = if r[i] == b'\r' && r.get(i + 1) == Some(&b'\n') {
                    2
                } else {
                    1
                };
                rest = Some(&r[i + skip..]);
                Some(&r[..i])
            }
            None => {
                rest = None;
                Some(r)
            }
        }
    })
}

pub use crate::input::BOM;

/// The statement part of a line (before `#`) and whether there was a comment.
pub(crate) fn statement(line: &[u8]) -> (&[u8], bool) {
    match line.iter().position(|&b| b == b'#') {
        Some(i) => (&line[..i], true),
        None => (line, false),
    }
}
/// A triangle mesh as read from an OBJ file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    /// Vertex positions in file order.
    pub positions: Vec<Vec3>,
    /// Triangles as 0-based indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl ObjMesh {
    /// Vertex positions of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Bounding box of the referenced vertices `(min, max)`; `None` for no triangles.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self
            .triangles
            .iter()
            .flatten()
            .map(|&i| self.positions[i as usize]);
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }
}

/// Where each vertex and triangle of an [`ObjMesh`] was read: the 1-based line of its `v`
/// statement, and of the `f` statement it was fan-triangulated from. For messages about them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ObjLines {
    // `u32`: a file read holds at most `limits::MAX_INPUT_BYTES` (2³⁰) bytes, so fewer lines
    // (a longer text saturates at `u32::MAX`).
    vertex: Vec<u32>,
    triangle: Vec<u32>,
}

impl ObjLines {
    /// The line of vertex `i` (0-based, as in [`ObjMesh::positions`]); `None` beyond them.
    pub fn vertex(&self, i: usize) -> Option<usize> {
        self.vertex.get(i).map(|&l| l as usize)
    }

    /// The line of triangle `i` (0-based, as in [`ObjMesh::triangles`]); `None` beyond them.
    pub fn triangle(&self, i: usize) -> Option<usize> {
        self.triangle.get(i).map(|&l| l as usize)
    }
}

/// A parsed OBJ file: the mesh, what the file held that the mesh does not keep, and the lines
/// its vertices and triangles came from.
#[derive(Debug)]
pub struct ObjFile {
    /// The triangle mesh.
    pub mesh: ObjMesh,
    /// The statements read but not kept.
    pub not_carried: NotCarried,
    /// The source line of each vertex and triangle.
    pub lines: ObjLines,
}

/// What an OBJ read may plan to hold: the file's bytes, the parsed vertices and triangles with
/// their lines (the room reserved for them), and what the caller will allocate for a mesh of
/// as many as that room holds (`need`), together at most `limit` bytes. The reader checks it before it reserves
/// room for another vertex or triangle, so a file is refused at the line where the total
/// crosses the limit, before the memory is taken.
#[derive(Clone, Copy, Debug)]
pub struct ReadBudget<'a> {
    /// Most bytes the total may reach.
    pub limit: u64,
    /// Bytes the caller will allocate for a mesh of `(vertices, triangles)`; `None` on
    /// overflow (refused).
    pub need: fn(usize, usize) -> Option<u64>,
    /// What the total is, for the refusal ("reading the file into a half-edge mesh").
    pub what: &'a str,
}

impl ReadBudget<'static> {
    /// The parse alone, within [`crate::limits::MEMORY_LIMIT_BYTES`]: for callers whose own
    /// allocations from the mesh are checked after reading.
    pub const PARSE: Self = Self {
        limit: crate::limits::MEMORY_LIMIT_BYTES,
        need: |_, _| Some(0),
        what: "reading the file",
    };
}

/// Bytes the reader holds per vertex: its position and its line.
const VERTEX_BYTES: u64 = (size_of::<Vec3>() + size_of::<u32>()) as u64;
/// Bytes the reader holds per triangle: its indices and its line.
const TRIANGLE_BYTES: u64 = (size_of::<[u32; 3]>() + size_of::<u32>()) as u64;
/// Fewest vertices or triangles (a count) the reader reserves room for at once, when the limit
/// leaves room for them: small files grow without a reallocation per line; above it room
/// doubles, less near the limit.
const MIN_RESERVE: usize = 1024;

impl ReadBudget<'_> {
    /// The planned total with room for `rooms` `[vertices, triangles]`, for a file of `file`
    /// bytes: what the reader holds, and the caller's need for a mesh filling both rooms (so
    /// that pushes into the room of one kind stay within the limit whatever the other kind
    /// does later); `None` on overflow.
    fn planned(&self, file: usize, rooms: [usize; 2]) -> Option<u64> {
        let held = (rooms[0] as u64)
            .checked_mul(VERTEX_BYTES)?
            .checked_add((rooms[1] as u64).checked_mul(TRIANGLE_BYTES)?)?
            .checked_add(file as u64)?;
        held.checked_add((self.need)(rooms[0], rooms[1])?)
    }

    /// Makes room for one more of kind `k` (0: vertices in `items` and their `lines`, 1:
    /// triangles) when it is full, given the room of the other kind: at most doubling, and
    /// only as much as [`ReadBudget::planned`] keeps within the limit. `Err` with the total
    /// room for one more would plan (`None`: overflow) when it exceeds the limit.
    fn room_for_one<T>(
        &self,
        file: usize,
        k: usize,
        items: &mut Vec<T>,
        lines: &mut Vec<u32>,
        other_room: usize,
    ) -> std::result::Result<(), Option<u64>> {
        let len = items.len();
        if len < items.capacity() && len < lines.capacity() {
            return Ok(());
        }
        let plan = |room: usize| {
            let mut rooms = [other_room; 2];
            rooms[k] = room;
            self.planned(file, rooms)
        };
        let fits = |room| plan(room).is_some_and(|b| b <= self.limit);
        if !fits(len + 1) {
            return Err(plan(len + 1));
        }
        let mut extra = len.max(MIN_RESERVE);
        while !fits(len + extra) {
            extra /= 2; // reaches 1, which fits
        }
        items.reserve_exact(extra);
        lines.reserve_exact(extra);
        Ok(())
    }
}

/// Reads and parses an OBJ file within [`ReadBudget::PARSE`].
pub fn read_obj(path: &Path) -> Result<ObjMesh> {
    read_obj_file(path).map(|f| f.mesh)
}

/// Reads and parses an OBJ file within [`ReadBudget::PARSE`], keeping what [`ObjFile`] says of
/// it.
pub fn read_obj_file(path: &Path) -> Result<ObjFile> {
    read_obj_file_within(path, ReadBudget::PARSE)
}

/// Reads and parses an OBJ file within `budget` (see [`parse_obj_bytes_within`]).
pub fn read_obj_file_within(path: &Path, budget: ReadBudget<'_>) -> Result<ObjFile> {
    let bytes = crate::input::read_bytes(path)?;
    parse_obj_bytes_within(&bytes, path, budget)
}

/// Parses OBJ text within [`ReadBudget::PARSE`]; `path` is used only in error messages.
pub fn parse_obj(text: &str, path: &Path) -> Result<ObjMesh> {
    parse_obj_bytes(text.as_bytes(), path).map(|f| f.mesh)
}

/// Parses OBJ bytes (see the module docs) within [`ReadBudget::PARSE`]; `path` is used only
/// in error messages.
pub fn parse_obj_bytes(bytes: &[u8], path: &Path) -> Result<ObjFile> {
    parse_obj_bytes_within(bytes, path, ReadBudget::PARSE)
}

/// Parses OBJ bytes (see the module docs); `path` is used only in error messages. A file whose
/// bytes, parse and `budget.need` would exceed `budget.limit` is refused, as an input error at
/// the `v` or `f` statement (line and column) where the total crosses it, before its memory is
/// reserved (see [`ReadBudget`]).
pub fn parse_obj_bytes_within(
    bytes: &[u8],
    path: &Path,
    budget: ReadBudget<'_>,
) -> Result<ObjFile> {
    let file_len = bytes.len();
    let bytes = bytes.strip_prefix(BOM).unwrap_or(bytes);
    let mut mesh = ObjMesh::default();
    let mut dropped = NotCarried::default();
    let mut source = ObjLines::default();
    let (mut texcoords, mut normals) = (0usize, 0usize);
    for (line_no, raw) in lines(bytes).enumerate() {
        let line_no = line_no + 1;
        let line32 = u32::try_from(line_no).unwrap_or(u32::MAX);
        let at =
            |col: usize, field: &str| Location::file(path).line(line_no).column(col).field(field);
        let over = |col: usize, field: &str, mesh: &ObjMesh, total: Option<u64>| {
            let what = format!(
                "at {} vertices and {} triangles, {}",
                mesh.positions.len(),
                mesh.triangles.len(),
                budget.what
            );
            let e = crate::limits::check_memory_within(&what, total, budget.limit)
                .expect_err("a total over the limit");
            Error::input(at(col, field), e.to_string())
        };
        let (content, comment) = statement(raw);
        if comment {
            dropped.note("#");
        }
        let content = std::str::from_utf8(content).map_err(|e| {
            Error::input(
                at(e.valid_up_to() + 1, "text"),
                "not UTF-8 (only comments may hold other bytes)",
            )
        })?;
        let mut tokens = tokens_with_columns(content);
        let Some((_, keyword)) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let mut values = [0.0f32; 6];
                let mut count = 0;
                for (col, tok) in tokens {
                    let name = ["x", "y", "z", "w|r", "g", "b"].get(count).copied();
                    let Some(name) = name else {
                        return Err(Error::input(
                            at(col, "v"),
                            format!(
                                "unexpected `{}`: a vertex is `v x y z`, `v x y z w` or `v x y z r g b`",
                                crate::text::excerpt(tok)
                            ),
                        ));
                    };
                    let v: f32 = tok.parse().map_err(|_| {
                        Error::input(
                            at(col, name),
                            format!("`{}` is not a number", crate::text::excerpt(tok)),
                        )
                    })?;
                    // A number beyond `f32` (`1e39`, `1e400`) reads as infinity: for a
                    // coordinate that is the domain's error below, for a `w` or colour a range
                    // error. Only a spelled-out infinity or NaN is "not finite".
                    let beyond_f32 = v.is_infinite() && !spells_non_finite(tok);
                    let outside_domain = beyond_f32 && count < 3;
                    if !(v.is_finite() || outside_domain) {
                        let why = if beyond_f32 {
                            "is beyond the largest `f32` (3.4e38)"
                        } else {
                            "is not finite"
                        };
                        return Err(Error::input(
                            at(col, name),
                            format!("`{}` {why}", crate::text::excerpt(tok)),
                        ));
                    }
                    if count < 3 && v.abs() > MAX_COORDINATE {
                        return Err(Error::input(
                            at(col, name),
                            format!(
                                "vertex {}: `{}` is outside the coordinate domain ±{MAX_COORDINATE:e} (obj::MAX_COORDINATE: farther vertices overflow the intersection test)",
                                mesh.positions.len() + 1,
                                crate::text::excerpt(tok)
                            ),
                        ));
                    }
                    values[count] = v;
                    count += 1;
                }
                match count {
                    3 => {}
                    4 => dropped.note("v w"),
                    6 => dropped.note("v rgb"),
                    _ => {
                        let name = ["x", "y", "z", "w|r", "g", "b"][count.min(5)];
                        let msg = if count < 3 {
                            "vertex needs 3 coordinates"
                        } else {
                            "a vertex is `v x y z`, `v x y z w` or `v x y z r g b`"
                        };
                        return Err(Error::input(at(content.len() + 1, name), msg));
                    }
                }
                let triangles = mesh.triangles.capacity();
                budget
                    .room_for_one(
                        file_len,
                        0,
                        &mut mesh.positions,
                        &mut source.vertex,
                        triangles,
                    )
                    .map_err(|total| over(1, "v", &mesh, total))?;
                mesh.positions
                    .push(Vec3::new(values[0], values[1], values[2]));
                source.vertex.push(line32);
            }
            "f" => {
                // Fan triangles (v0, vi, vi+1) are added as the tokens are read.
                let (mut first, mut previous, mut count) = (0, 0, 0usize);
                for (col, tok) in tokens {
                    let counts = [mesh.positions.len(), texcoords, normals];
                    let v = face_vertex(tok, counts).map_err(|m| Error::input(at(col, "f"), m))?;
                    match count {
                        0 => first = v,
                        1 => {}
                        _ => {
                            let vertices = mesh.positions.capacity();
                            budget
                                .room_for_one(
                                    file_len,
                                    1,
                                    &mut mesh.triangles,
                                    &mut source.triangle,
                                    vertices,
                                )
                                .map_err(|total| over(col, "f", &mesh, total))?;
                            mesh.triangles.push([first, previous, v]);
                            source.triangle.push(line32);
                        }
                    }
                    previous = v;
                    count += 1;
                }
                if count < 3 {
                    return Err(Error::input(at(1, "f"), "face needs at least 3 vertices"));
                }
                if count > 3 {
                    dropped.polygons_split += 1;
                }
            }
            "vt" | "vn" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => {
                texcoords += usize::from(keyword == "vt");
                normals += usize::from(keyword == "vn");
                dropped.note(keyword);
            }
            other => {
                return Err(Error::input(
                    at(1, "statement"),
                    format!("unknown OBJ statement `{}`", crate::text::excerpt(other)),
                ));
            }
        }
    }
    Ok(ObjFile {
        mesh,
        not_carried: dropped,
        lines: source,
    })
}

/// The vertex of a face token `v`, `v/t`, `v//n` or `v/t/n` (0-based), given how many
/// vertices, texture coordinates and normals precede it: each index present must be a
/// non-zero integer in range (negative ones count back from the last), the texture and
/// normal indices too although they are not kept. The message otherwise.
fn face_vertex(tok: &str, [vertices, texcoords, normals]: [usize; 3]) -> Result<u32, String> {
    let parts: Vec<&str> = tok.split('/').collect();
    let shape_ok = match parts.as_slice() {
        [v] => !v.is_empty(),
        [v, t] => !v.is_empty() && !t.is_empty(),
        [v, _, n] => !v.is_empty() && !n.is_empty(),
        _ => false,
    };
    if !shape_ok {
        return Err(format!(
            "`{}` is not a face vertex (`v`, `v/t`, `v//n` or `v/t/n`)",
            crate::text::excerpt(tok)
        ));
    }
    let mut vertex = 0;
    for (k, (text, (count, what))) in parts
        .iter()
        .zip([
            (vertices, "vertex"),
            (texcoords, "texture coordinate"),
            (normals, "normal"),
        ])
        .enumerate()
    {
        if text.is_empty() {
            continue; // `v//n`: no texture coordinate.
        }
        let idx: i64 = text.parse().map_err(|_| {
            format!(
                "`{}` in `{}` is not a {what} index",
                crate::text::excerpt(text),
                crate::text::excerpt(tok)
            )
        })?;
        let n = count as i64;
        let resolved = if idx > 0 { idx - 1 } else { n + idx };
        if idx == 0 || resolved < 0 || resolved >= n {
            return Err(format!("{what} index {idx} out of range (1..={n} so far)"));
        }
        if k == 0 {
            vertex = resolved as u32;
        }
    }
    Ok(vertex)
}

/// Whether `tok` is one of the spellings `f32` parses as infinity or NaN (`inf`, `infinity`,
/// `nan`, in any case, with an optional sign), rather than a number too large for `f32`.
fn spells_non_finite(tok: &str) -> bool {
    let word = tok.strip_prefix(['+', '-']).unwrap_or(tok);
    ["inf", "infinity", "nan"]
        .iter()
        .any(|w| word.eq_ignore_ascii_case(w))
}

fn tokens_with_columns(s: &str) -> impl Iterator<Item = (usize, &str)> {
    s.split_ascii_whitespace().map(move |tok| {
        let col = tok.as_ptr() as usize - s.as_ptr() as usize + 1;
        (col, tok)
    })
}

/// Writes a triangle mesh as OBJ (`v` then `f` lines, 1-based), atomically. Coordinates are
/// written with Rust's shortest round-trip formatting, so reading the file back gives the
/// same `f32` values bit for bit.
pub fn write_obj(path: &Path, positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<()> {
    write_obj_to(OutputFile::reserve(path, false)?, positions, triangles)
}

/// [`write_obj`] to an output reserved before the work.
pub fn write_obj_to(out: OutputFile, positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<()> {
    out.write(|w| {
        for p in positions {
            writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
        }
        for t in triangles {
            writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coordinate_domain_is_two_to_the_125() {
        assert_eq!(MAX_COORDINATE, 2f32.powi(125));
        // Two points at opposite ends, sheared by |s| = 1: the sum still fits in f32.
        let d = MAX_COORDINATE - -MAX_COORDINATE;
        assert!((d + d).is_finite());
    }

    #[test]
    fn parses_polygons_negative_indices_and_keeps_order() {
        let text = "# c\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nvt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3 4\nf -5 -4 -3\n";
        let m = parse_obj(text, Path::new("q.obj")).unwrap();
        assert_eq!(m.positions.len(), 5, "unreferenced vertex kept");
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2]]);
    }

    #[test]
    fn errors_name_file_line_column() {
        let e = parse_obj("v 0 0 0\nv 1 nan 0\n", Path::new("a.obj")).unwrap_err();
        assert_eq!(e.to_string(), "a.obj:2:5: field `y`: `nan` is not finite");
        // A finite number beyond `f32` is outside the domain (a coordinate) or out of range,
        // not "not finite".
        let e = parse_obj("v 0 0 1e39\n", Path::new("a.obj")).unwrap_err();
        assert!(
            e.to_string().starts_with(
                "a.obj:1:7: field `z`: vertex 1: `1e39` is outside the coordinate domain"
            ),
            "{e}"
        );
        let e = parse_obj("v 0 0 0 1e39\n", Path::new("a.obj")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.obj:1:9: field `w|r`: `1e39` is beyond the largest `f32` (3.4e38)"
        );
        // So is one beyond `f64` (`1e400`), while a spelled-out infinity is not finite.
        for big in ["1e400", "-1E400", "+1e99999"] {
            let e = parse_obj(&format!("v 0 0 {big}\n"), Path::new("a.obj")).unwrap_err();
            assert!(
                e.to_string().starts_with(&format!(
                    "a.obj:1:7: field `z`: vertex 1: `{big}` is outside the coordinate domain"
                )),
                "{e}"
            );
        }
        let e = parse_obj("v 0 0 0 1e400\n", Path::new("a.obj")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.obj:1:9: field `w|r`: `1e400` is beyond the largest `f32` (3.4e38)"
        );
        for spelled in ["inf", "-Infinity", "+INF", "NaN", "-nan"] {
            let e = parse_obj(&format!("v 0 0 {spelled}\n"), Path::new("a.obj")).unwrap_err();
            assert_eq!(
                e.to_string(),
                format!("a.obj:1:7: field `z`: `{spelled}` is not finite")
            );
        }
        let e = parse_obj("v 0 0 0\nf 1 2 3\n", Path::new("b.obj")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("b.obj:2:5: field `f`: vertex index 2 out of range"),
            "{e}"
        );
        let e = parse_obj("v 0 0\n", Path::new("c.obj")).unwrap_err();
        assert!(e.to_string().contains("needs 3 coordinates"), "{e}");
        let e = parse_obj("v 0 0 0\nf 1 1\n", Path::new("d.obj")).unwrap_err();
        assert!(e.to_string().contains("at least 3"), "{e}");
        let e = parse_obj("bogus 1\n", Path::new("e.obj")).unwrap_err();
        assert!(e.to_string().contains("unknown OBJ statement"), "{e}");
    }

    fn parse_bytes(b: &[u8]) -> Result<(ObjMesh, NotCarried)> {
        parse_obj_bytes(b, Path::new("d.obj")).map(|f| (f.mesh, f.not_carried))
    }

    #[test]
    fn line_ends_bom_and_non_utf8_comments_are_accepted() {
        let tri = vec![[0, 1, 2]];
        for text in [
            &b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"[..],
            b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n",
            b"v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r",
            b"\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3",
            b"# caf\xe9 cr\xe8me\nv 0 0 0\nv 1 0 0 # \xff\nv 0 1 0\nf 1 2 3\n",
        ] {
            let (m, _) = parse_bytes(text).unwrap();
            assert_eq!(m.positions.len(), 3, "{text:?}");
            assert_eq!(m.triangles, tri, "{text:?}");
        }
        // Line numbers count CR-only and CRLF line ends.
        for text in [&b"v 0 0 0\rv 1 x 0\r"[..], b"v 0 0 0\r\nv 1 x 0\r\n"] {
            let e = parse_bytes(text).unwrap_err().to_string();
            assert!(e.starts_with("d.obj:2:5: field `y`"), "{e}");
        }
        let e = parse_bytes(b"v 0 0 0\nv 1 \xe9 0\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "d.obj:2:5: field `text`: not UTF-8 (only comments may hold other bytes)"
        );
    }

    #[test]
    fn vertices_take_w_or_rgb_and_nothing_else() {
        let (m, d) = parse_bytes(b"v 1 2 3 0.5\nv 4 5 6 0.1 0.2 0.3\nv 7 8 9\n").unwrap();
        assert_eq!(m.positions[1], Vec3::new(4.0, 5.0, 6.0));
        assert_eq!(d.statements["v w"], 1);
        assert_eq!(d.statements["v rgb"], 1);
        let e = parse_bytes(b"v 0 0 0 garbage\n").unwrap_err().to_string();
        assert_eq!(e, "d.obj:1:9: field `w|r`: `garbage` is not a number");
        let e = parse_bytes(b"v 0 0 0 1 2\n").unwrap_err().to_string();
        assert!(
            e.starts_with("d.obj:1:12:") && e.contains("v x y z r g b"),
            "{e}"
        );
        let e = parse_bytes(b"v 0 0 0 1 2 3 4\n").unwrap_err().to_string();
        assert!(
            e.starts_with("d.obj:1:15: field `v`: unexpected `4`"),
            "{e}"
        );
    }

    #[test]
    fn dropped_statements_are_counted_and_tokens_in_messages_are_bounded() {
        let text = b"# c\nmtllib a.mtl\no cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nusemtl m\ns 1\nf 1 2 3 4\n";
        let (m, d) = parse_bytes(text).unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(d.polygons_split, 1);
        assert_eq!(
            d.to_string(),
            "1 comment line(s), 1 `mtllib`, 1 `o`, 1 `s`, 1 `usemtl`, 1 `vn`, 1 `vt`, 1 polygon(s) split into triangles"
        );
        let mut hostile = b"v 0 0 \x1b[2J".to_vec();
        hostile.extend(std::iter::repeat_n(b'9', 10_000_000));
        let e = parse_bytes(&hostile).unwrap_err().to_string();
        assert!(e.len() < 200, "{} bytes", e.len());
        assert!(e.contains("\\u{1b}[2J") && !e.contains('\x1b'), "{e}");
    }

    /// A parse is refused at the statement where the file's bytes, what the reader holds (16
    /// bytes a vertex: position and line; 16 a triangle: indices and line) and the caller's
    /// need first exceed the limit, and accepted when they reach it exactly.
    #[test]
    fn the_parse_is_refused_where_its_budget_is_crossed() {
        fn parse(text: &str, limit: u64, need: fn(usize, usize) -> Option<u64>) -> Result<ObjFile> {
            let what = "the test";
            let budget = ReadBudget { limit, need, what };
            parse_obj_bytes_within(text.as_bytes(), Path::new("m.obj"), budget)
        }
        // Vertices alone, 56 bytes each with the caller's 40: the 1501st crosses.
        let text = "v 0 0 0\n".repeat(2000);
        let file = text.len() as u64;
        let limit = file + 56 * 1500 + 10;
        let e = parse(&text, limit, |v, _| Some(40 * v as u64)).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "m.obj:1501:1: field `v`: at 1500 vertices and 0 triangles, the test needs {} bytes, more than the {limit}-byte limit",
                file + 56 * 1501
            )
        );
        let exact = file + 56 * 2000;
        assert_eq!(
            parse(&text, exact, |v, _| Some(40 * v as u64))
                .unwrap()
                .mesh
                .positions
                .len(),
            2000
        );
        let e = parse(&text, exact - 1, |v, _| Some(40 * v as u64)).unwrap_err();
        assert!(e.to_string().starts_with("m.obj:2000:1: field `v`"), "{e}");

        // Then triangles, 116 bytes each with the caller's 100, after 1024 vertices (whose room
        // is exactly their count): triangle 2000 crosses, on its `f` line or at its token.
        let vertices = "v 0 0 0\n".repeat(1024);
        let need = |_, t: usize| Some(100 * t as u64);
        let lines = format!("{vertices}{}", "f 1 2 3\n".repeat(3000));
        let held = lines.len() as u64 + 1024 * 16;
        let e = parse(&lines, held + 116 * 1999 + 50, need).unwrap_err();
        assert!(
            e.to_string().starts_with(
                "m.obj:3024:7: field `f`: at 1024 vertices and 1999 triangles, the test needs"
            ),
            "{e}"
        );
        // One polygon: token i (from 0) at column 3 + 2i adds triangle i − 1 (from 1).
        let polygon = format!("{vertices}f{}\n", " 1 2".repeat(1500));
        let held = polygon.len() as u64 + 1024 * 16;
        let e = parse(&polygon, held + 116 * 1999 + 50, need).unwrap_err();
        assert!(
            e.to_string().starts_with(&format!(
                "m.obj:1025:{}: field `f`: at 1024 vertices and 1999 triangles",
                3 + 2 * 2001
            )),
            "{e}"
        );
        let whole = parse(&polygon, held + 116 * 2998, need).unwrap();
        assert_eq!(whole.mesh.triangles.len(), 2998);
        assert_eq!(whole.mesh.triangles[..2], [[0, 1, 0], [0, 0, 1]]);
    }

    #[test]
    fn write_then_read_round_trips_bits() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        let pos = vec![
            Vec3::new(0.1, -1.0e-20, 3.0e30),
            Vec3::ONE,
            Vec3::new(1.0 / 3.0, 2.0, 0.0),
        ];
        write_obj(&path, &pos, &[[0, 1, 2]]).unwrap();
        let m = read_obj(&path).unwrap();
        assert_eq!(m.positions, pos);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }
}
