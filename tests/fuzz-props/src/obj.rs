//! `obj_file`: the OBJ parser on arbitrary text.

use super::*;

/// The path handed to the OBJ parser; every error message must start with it.
pub const OBJ_PATH: &str = "fuzz/input.obj";

/// Fuzz target `obj_file`: the bytes as lossy UTF-8 text (and, when they are valid UTF-8,
/// as-is) through [`check_obj`].
pub fn obj_file(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    check_obj(&text);
}

/// Properties of `halfray::obj::parse_obj` on any text: never a panic; it agrees with
/// [`reference_obj`], a reader written here from the module documentation of `halfray::obj`
/// (no code of `halfray` involved): where the reference accepts, `parse_obj` gives the
/// same mesh bit for bit (positions, triangles), as it does for the canonical re-write of
/// that mesh (`v x y z` with Rust's shortest round-trip floats, `f a b c` 1-based, as
/// `write_obj` documents); where the reference refuses, `parse_obj` refuses too, with a
/// message starting `path:line:column:` whose line is the first line the reference refuses
/// and whose column is within that line's statement part.
pub fn check_obj(text: &str) {
    // Every outcome below is judged against the reference reader.
    reached();
    let path = Path::new(OBJ_PATH);
    let want = reference_obj(text);
    match (halfray::obj::parse_obj(text, path), want) {
        (Ok(m), Ok(r)) => {
            let bits = |p: &[Vec3]| {
                p.iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&m.positions),
                bits(&r.positions),
                "positions differ from the reference\n{text:?}"
            );
            assert_eq!(
                m.triangles, r.triangles,
                "triangles differ from the reference\n{text:?}"
            );
            let mut canon = String::new();
            for p in &r.positions {
                canon.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
            }
            for t in &r.triangles {
                canon.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
            }
            let again = halfray::obj::parse_obj(&canon, path)
                .unwrap_or_else(|e| panic!("canonical re-write does not parse: {e}\n{canon}"));
            assert_eq!(
                bits(&again.positions),
                bits(&r.positions),
                "canonical positions do not read back\n{canon}"
            );
            assert_eq!(
                again.triangles, r.triangles,
                "canonical triangles do not read back"
            );
        }
        (Ok(m), Err(line)) => panic!(
            "accepted ({} vertices, {} triangles), the reference refuses line {line}\n{text:?}",
            m.positions.len(),
            m.triangles.len()
        ),
        (Err(e), Ok(_)) => panic!("refused ({e}), the reference accepts\n{text:?}"),
        (Err(e), Err(line)) => {
            let msg = e.to_string();
            let lines = reference_lines(text);
            let named = error_position(&msg).and_then(|(l, col)| {
                let content = statement_part(lines.get(l.checked_sub(1)?)?);
                (l == line && (1..=content.len() + 1).contains(&col)).then_some(())
            });
            assert!(
                named.is_some(),
                "error message does not start with `{OBJ_PATH}:{line}:<column>:` (the line the \
                 reference refuses) with a column in that line's statement: {msg:?}\n{text:?}"
            );
        }
    }
}

/// The mesh [`reference_obj`] reads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefMesh {
    /// Positions in file order.
    pub positions: Vec<Vec3>,
    /// Fan-triangulated faces, 0-based.
    pub triangles: Vec<[u32; 3]>,
}

/// `2¹²⁵`, `halfray::obj::MAX_COORDINATE` as its documentation defines it (a quarter of
/// the `f32` range), written out here.
pub const REF_MAX_COORDINATE: f32 = 42_535_295_865_117_307_932_921_825_928_971_026_432.0;

/// The OBJ reader the module docs of `halfray::obj` describe, written independently:
/// `Ok(mesh)` or `Err(line)`, the 1-based number of the first line it refuses.
///
/// Lines: a leading byte-order mark dropped; LF, CRLF and a lone CR end a line. A line's
/// statement is the text before its first `#`; its tokens are separated by ASCII
/// whitespace (space, tab, form feed: the set of `u8::is_ascii_whitespace` minus the line
/// ends; the docs say "tokens", and a vertical tab is not whitespace there). Statements:
/// * `v` with 3, 4 or 6 numbers (Rust's `f32` syntax, the docs' "malformed" being what it
///   does not read): each finite as an `f32` (a finite decimal beyond `f32` is refused
///   too), the first three within `±2¹²⁵`;
/// * `f` with at least three tokens `v`, `v/t`, `v//n`, `v/t/n`, each index present an
///   integer (optional sign, decimal digits) that is non-zero and in range of the vertices,
///   texture coordinates or normals read so far (a negative one counting back from the
///   last, `−1` the last); the polygon fan-triangulated `(v0, vi, vi+1)`;
/// * `vt`, `vn` (counted), `vp`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p` with anything;
/// * nothing else.
pub fn reference_obj(text: &str) -> Result<RefMesh, usize> {
    let mut mesh = RefMesh::default();
    let (mut texcoords, mut normals) = (0u64, 0u64);
    for (k, line) in reference_lines(text).iter().enumerate() {
        let no = k + 1;
        let tokens: Vec<&str> = statement_part(line)
            .split([' ', '\t', '\x0c'])
            .filter(|t| !t.is_empty())
            .collect();
        let Some((&keyword, args)) = tokens.split_first() else {
            continue;
        };
        match keyword {
            "v" => {
                if !matches!(args.len(), 3 | 4 | 6) {
                    return Err(no);
                }
                let mut xyz = [0.0f32; 3];
                for (j, tok) in args.iter().enumerate() {
                    let x: f32 = tok.parse().map_err(|_| no)?;
                    if !x.is_finite() || (j < 3 && x.abs() > REF_MAX_COORDINATE) {
                        return Err(no);
                    }
                    if j < 3 {
                        xyz[j] = x;
                    }
                }
                mesh.positions.push(Vec3::from_array(xyz));
            }
            "f" => {
                if args.len() < 3 {
                    return Err(no);
                }
                let counts = [mesh.positions.len() as u64, texcoords, normals];
                let corners = args
                    .iter()
                    .map(|tok| face_corner(tok, counts))
                    .collect::<Option<Vec<u32>>>()
                    .ok_or(no)?;
                for i in 1..corners.len() - 1 {
                    mesh.triangles
                        .push([corners[0], corners[i], corners[i + 1]]);
                }
            }
            "vt" => texcoords += 1,
            "vn" => normals += 1,
            "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => {}
            _ => return Err(no),
        }
    }
    Ok(mesh)
}

/// The 0-based vertex of face token `tok` (docs: `v`, `v/t`, `v//n`, `v/t/n`), given the
/// vertex, texture-coordinate and normal counts so far; `None` when the token is refused.
fn face_corner(tok: &str, counts: [u64; 3]) -> Option<u32> {
    let parts: Vec<&str> = tok.split('/').collect();
    // Which parts must be present: the texture coordinate may be empty only with a normal.
    let present: &[usize] = match parts.len() {
        1 => &[0],
        2 => &[0, 1],
        3 if parts[1].is_empty() => &[0, 2],
        3 => &[0, 1, 2],
        _ => return None,
    };
    let mut vertex = None;
    for &k in present {
        let index = reference_index(parts[k], counts[k])?;
        if k == 0 {
            vertex = Some(u32::try_from(index).ok()?);
        }
    }
    vertex
}

/// An OBJ index (optional `+`/`−`, at least one decimal digit) resolved against `count`
/// elements read so far: `i > 0` is element `i − 1`, `i < 0` element `count + i`; `None` for
/// 0, out of range, or not an integer. Exact: the digits are compared, not converted, so no
/// width limits it (an index longer than `count`'s digits is out of range).
fn reference_index(text: &str, count: u64) -> Option<u64> {
    let (negative, digits) = match text.as_bytes().first()? {
        b'+' => (false, &text[1..]),
        b'-' => (true, &text[1..]),
        _ => (false, text),
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let digits = digits.trim_start_matches('0');
    // More than 20 significant digits exceeds any u64 count.
    let magnitude: u64 = if digits.is_empty() {
        0
    } else if digits.len() > 19 {
        return None;
    } else {
        digits.parse().ok()?
    };
    if magnitude == 0 || magnitude > count {
        return None;
    }
    Some(if negative {
        count - magnitude
    } else {
        magnitude - 1
    })
}

/// The part of `line` before its first `#`.
fn statement_part(line: &str) -> &str {
    line.split('#').next().unwrap_or("")
}

/// The `(line, column)` of an error message `<OBJ_PATH>:<line>:<column>: ...` (the
/// frontend's `Location` display), `None` when it does not start that way. Every error of
/// the OBJ parser is about one statement, so every one names its line and column (none
/// names only the file).
fn error_position(msg: &str) -> Option<(usize, usize)> {
    let rest = msg.strip_prefix(OBJ_PATH)?.strip_prefix(':')?;
    let mut parts = rest.splitn(3, ':');
    let line = parts.next()?.parse().ok()?;
    let col = parts.next()?.parse().ok()?;
    parts.next()?;
    Some((line, col))
}

/// The lines of `text` as the OBJ module docs define them: a leading byte-order mark
/// dropped; LF, CRLF and a lone CR each end a line, and the text after the last one
/// (possibly empty) is a line. Columns count bytes from 1.
fn reference_lines(text: &str) -> Vec<&str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(['\n', '\r']) {
        out.push(&rest[..i]);
        rest = rest[i..].strip_prefix("\r\n").unwrap_or(&rest[i + 1..]);
    }
    out.push(rest);
    out
}

/// The seed inputs, by name.
const SEEDS: [(&str, &str); 12] = [
    (
        "quad",
        "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
    ),
    (
        "slashes-negative",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3/1\nf -3 -2 -1\n",
    ),
    (
        "crlf-comments",
        "o thing\r\ng g\r\nv 0 0 0 1\r\nv 1 0 0 # c\r\nv 0 1 0\r\ns off\r\nf 1 2 3\r\n",
    ),
    (
        "extreme-floats",
        "v 3.4028235e38 -1e-45 1.17549435e-38\nv -0 0 inf\nv nan 0 0\nf 1 2 3\n",
    ),
    ("overflowing-float", "v 1e39 0 0\n"),
    ("index-zero", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
    ("index-out-of-range", "v 0 0 0\nf 1 2 3\nf -4 1 1\n"),
    (
        "big-index",
        "v 0 0 0\nf 99999999999999999999 1 1\nf 4294967297 1 1\n",
    ),
    ("short-face", "v 0 0 0\nf 1 1\n"),
    ("unknown", "bogus 1 2\n"),
    ("unicode", "v 0 0 0 \u{00e9}\nv\u{3000}1 0 0\nf 1 1 1\n"),
    ("empty", ""),
];

pub(crate) fn seeds(s: &mut Vec<Seed>) {
    for (name, text) in SEEDS {
        s.push(("obj_file", format!("seed-{name}"), text.as_bytes().to_vec()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference reader on hand-written texts, with the meshes and refused lines read
    /// off the module docs by hand.
    #[test]
    fn reference_reader_follows_the_documented_rules() {
        let v = Vec3::new;
        let quad = reference_obj(
            "\u{feff}v 0 0 0\r\nv 1 0 0 1\rv 1 1 0 1 0.5 0\nv 0 1 0 # c\nf 1 2/7//x -2//1 -1\n",
        );
        // `2/7//x` has four parts: refused on line 5.
        assert_eq!(quad, Err(5));
        let quad = reference_obj(
            "v 0 0 0\r\nv 1 0 0 1\rv 1 1 0 1 0.5 0\nvt 0 0\nvn 0 0 1\nv 0 1 0 # c\nf 1 +2/1 -2//1 -1/1/1\n",
        )
        .unwrap();
        assert_eq!(
            quad.positions,
            vec![
                v(0.0, 0.0, 0.0),
                v(1.0, 0.0, 0.0),
                v(1.0, 1.0, 0.0),
                v(0.0, 1.0, 0.0)
            ]
        );
        assert_eq!(quad.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        for (text, line) in [
            ("v 0 0\n", 1),
            ("v 0 0 0 1 2\n", 1),
            ("v 0 0 0 1 2 3 4\n", 1),
            ("\n\nv 0 0 nan\n", 3),
            ("v 0 0 1e39\n", 1),
            ("v 0 0 4.3e37\n", 1),
            ("v 0 0 0 1e39\n", 1),
            ("v 0 0 0\nf 1 1\n", 2),
            ("v 0 0 0\nf 1 1 0\n", 2),
            ("v 0 0 0\nf 1 1 -2\n", 2),
            ("v 0 0 0\nf 1 1 1/1\n", 2),
            ("v 0 0 0\nvn 0 0 1\nf 1 1 1//2\n", 3),
            ("v 0 0 0\nf 1 1 99999999999999999999999\n", 2),
            ("v 0 0 0\nf 1 1 1/\n", 2),
            ("bogus\n", 1),
            ("v\u{3000}0 0 0\n", 1),
        ] {
            assert_eq!(reference_obj(text).map(|_| ()), Err(line), "{text:?}");
        }
        assert_eq!(
            reference_obj("v 0 0 4.2535295e37\nv 1 0 0\nv 0 1 0\nf 1 2 3\ns off\n#x\n")
                .map(|m| m.triangles),
            Ok(vec![[0, 1, 2]])
        );
        assert_eq!(REF_MAX_COORDINATE, 2f32.powi(125));
        assert_eq!(REF_MAX_COORDINATE, halfray::obj::MAX_COORDINATE);
        // And `check_obj` runs clean on all of these against the reader under test.
        for (_, text) in SEEDS {
            check_obj(text);
        }
    }
}
