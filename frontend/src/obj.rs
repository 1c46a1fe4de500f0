//! A strict Wavefront OBJ reader and writer for triangle meshes.
//!
//! halfray reads OBJ itself rather than through `tobj`: the mesh tools promise that vertex `i`
//! of the file is vertex `i` of the mesh (subdivision appends new vertices after the original
//! ones, unreferenced vertices included), and general-purpose loaders re-index vertices per
//! object and drop unreferenced ones. The reader keeps the file's vertex order, welds nothing,
//! and reports errors with the file, line and column.
//!
//! Accepted: `v x y z [w]`, `f a b c ...` with `a`, `a/t`, `a//n`, `a/t/n` tokens and negative
//! (relative) indices; polygons are fan-triangulated `(v0, vi, vi+1)`. Ignored: comments, `vt`,
//! `vn`, `vp`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`. Rejected with a located error:
//! non-finite or malformed coordinates, faces with fewer than three vertices, index 0 or out
//! of range, unknown statements.

use crate::error::{Error, Location, Result};
use crate::outputs::OutputFile;
use glam::Vec3;
use std::path::Path;

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

/// Reads and parses an OBJ file.
pub fn read_obj(path: &Path) -> Result<ObjMesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| Error::input(Location::file(path), format!("not UTF-8 text: {e}")))?;
    parse_obj(&text, path)
}

/// Parses OBJ text; `path` is used only in error messages.
pub fn parse_obj(text: &str, path: &Path) -> Result<ObjMesh> {
    let mut mesh = ObjMesh::default();
    let mut face: Vec<u32> = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let line_no = line_no + 1;
        let at =
            |col: usize, field: &str| Location::file(path).line(line_no).column(col).field(field);
        let content = line.split('#').next().unwrap_or("");
        let mut tokens = tokens_with_columns(content);
        let Some((_, keyword)) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let mut p = [0.0f32; 3];
                for (k, name) in ["x", "y", "z"].iter().enumerate() {
                    let Some((col, tok)) = tokens.next() else {
                        return Err(Error::input(
                            at(line.len() + 1, name),
                            "vertex needs 3 coordinates",
                        ));
                    };
                    let v: f32 = tok.parse().map_err(|_| {
                        Error::input(at(col, name), format!("`{tok}` is not a number"))
                    })?;
                    if !v.is_finite() {
                        return Err(Error::input(
                            at(col, name),
                            format!("`{tok}` is not finite"),
                        ));
                    }
                    p[k] = v;
                }
                mesh.positions.push(Vec3::from_array(p));
            }
            "f" => {
                face.clear();
                for (col, tok) in tokens {
                    let idx_text = tok.split('/').next().unwrap_or("");
                    let idx: i64 = idx_text.parse().map_err(|_| {
                        Error::input(at(col, "f"), format!("`{tok}` is not a vertex index"))
                    })?;
                    let n = mesh.positions.len() as i64;
                    let resolved = if idx > 0 { idx - 1 } else { n + idx };
                    if idx == 0 || resolved < 0 || resolved >= n {
                        return Err(Error::input(
                            at(col, "f"),
                            format!("vertex index {idx} out of range (1..={n} so far)"),
                        ));
                    }
                    face.push(resolved as u32);
                }
                if face.len() < 3 {
                    return Err(Error::input(at(1, "f"), "face needs at least 3 vertices"));
                }
                for i in 1..face.len() - 1 {
                    mesh.triangles.push([face[0], face[i], face[i + 1]]);
                }
            }
            "vt" | "vn" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => {}
            other => {
                return Err(Error::input(
                    at(1, other),
                    format!("unknown OBJ statement `{other}`"),
                ));
            }
        }
    }
    Ok(mesh)
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
    fn parses_polygons_negative_indices_and_keeps_order() {
        let text = "# c\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nvn 0 0 1\nf 1/1/1 2//1 3 4\nf -5 -4 -3\n";
        let m = parse_obj(text, Path::new("q.obj")).unwrap();
        assert_eq!(m.positions.len(), 5, "unreferenced vertex kept");
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2]]);
    }

    #[test]
    fn errors_name_file_line_column() {
        let e = parse_obj("v 0 0 0\nv 1 nan 0\n", Path::new("a.obj")).unwrap_err();
        assert_eq!(e.to_string(), "a.obj:2:5: field `y`: `nan` is not finite");
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
