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

/// Properties of `halfray::obj::parse_obj` on any text: never a panic; `Ok` has every
/// position finite and every triangle index in range, and writing it back in the canonical
/// form (`v x y z` with Rust's shortest round-trip floats, `f a b c` 1-based) and parsing
/// again gives the same mesh bit for bit; `Err`'s message starts with `path:line:column:`,
/// the line one of the input's holding a statement, the column within its statement part.
pub fn check_obj(text: &str) {
    let path = Path::new(OBJ_PATH);
    match halfray::obj::parse_obj(text, path) {
        Ok(m) => {
            let n = m.positions.len();
            for p in &m.positions {
                assert!(
                    p.is_finite(),
                    "non-finite position {p:?} accepted\n{text:?}"
                );
            }
            for t in &m.triangles {
                assert!(
                    t.iter().all(|&i| (i as usize) < n),
                    "triangle {t:?} indexes past {n} positions\n{text:?}"
                );
            }
            let mut canon = String::new();
            for p in &m.positions {
                canon.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
            }
            for t in &m.triangles {
                canon.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
            }
            let again = halfray::obj::parse_obj(&canon, path)
                .unwrap_or_else(|e| panic!("canonical re-write does not parse: {e}\n{canon}"));
            let bits = |m: &halfray::obj::ObjMesh| {
                m.positions
                    .iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&again),
                bits(&m),
                "positions do not round-trip\n{text:?}"
            );
            assert_eq!(again.triangles, m.triangles, "triangles do not round-trip");
        }
        Err(e) => {
            let msg = e.to_string();
            let lines = obj_lines(text);
            let named = error_position(&msg).and_then(|(line, col)| {
                let content = lines.get(line.checked_sub(1)?)?.split('#').next()?;
                let statement = content.split_ascii_whitespace().next().is_some();
                (statement && (1..=content.len() + 1).contains(&col)).then_some(())
            });
            assert!(
                named.is_some(),
                "error message does not start with `{OBJ_PATH}:<line>:<column>:` naming a \
                 statement of the input's {} lines and a column in it: {msg:?}\n{text:?}",
                lines.len()
            );
        }
    }
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
fn obj_lines(text: &str) -> Vec<&str> {
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
