//! User text in messages: offending tokens and whole messages are escaped (control characters
//! as `\u{1b}`, so no escape sequence reaches the terminal; line separators and bidirectional
//! controls too, so no input starts a line of its own or reorders the text shown) and
//! truncated, so a 10 MB token gives a short message.

/// Most characters of an offending token quoted in a message.
pub const MAX_EXCERPT_CHARS: usize = 40;
/// Most characters of a whole message (the location is not counted).
pub const MAX_MESSAGE_CHARS: usize = 400;

/// `s` with control characters escaped, cut to `max` characters (then `…` and the original
/// length in bytes).
pub fn bounded(s: &str, max: usize) -> String {
    bounded_lines(s, max, false)
}

/// [`bounded`], keeping line breaks when `keep_newlines` (for whole multi-line messages).
pub fn bounded_lines(s: &str, max: usize, keep_newlines: bool) -> String {
    let mut out = String::new();
    for (chars, c) in s.chars().enumerate() {
        if chars >= max {
            out.push_str(&format!("… ({} bytes in all)", s.len()));
            return out;
        }
        if hidden_effect(c) && !(keep_newlines && c == '\n') {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Whether `c` acts on the terminal or the text's layout instead of showing as itself: a
/// control character (Unicode's `Cc`: `\n`, ESC, NEL…), the line and paragraph separators
/// (U+2028, U+2029) and the bidirectional formatting characters (U+061C, U+200E, U+200F,
/// U+202A–U+202E, U+2066–U+2069: an override can show a message's text in another order).
fn hidden_effect(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{2028}'
                | '\u{2029}'
                | '\u{061C}'
                | '\u{200E}'
                | '\u{200F}'
                | '\u{202A}'..='\u{202E}'
                | '\u{2066}'..='\u{2069}'
        )
}

/// `s` with every control character escaped (line breaks too), whole: a name or string from
/// input, safe to print inside a message or a table.
pub fn escaped(s: &str) -> String {
    bounded_lines(s, usize::MAX, false)
}

/// A string as a markdown table cell: [`escaped`], and `|` as `\\|` (a bare one would end
/// the cell).
pub fn table_cell(s: &str) -> String {
    escaped(s).replace('|', "\\|")
}

/// A path for a message: [`escaped`] (lossy UTF-8), so a file name cannot move the cursor,
/// set the terminal title or start a line of its own.
pub fn path(p: &std::path::Path) -> String {
    escaped(&p.to_string_lossy())
}

/// A mesh's name in reports: the file name of `p` (lossy UTF-8), or the whole path when it has
/// none (`..`, `/`). Not escaped: the reports store it as given.
pub fn file_name(p: &std::path::Path) -> String {
    p.file_name()
        .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
}

/// Labels of items given as `(name, path)` pairs, in order: each item's name (a file name),
/// or its path where two items share that name, so that no two items of different paths
/// carry the same label (items of one path keep one label).
pub fn unambiguous_names<'a>(items: impl IntoIterator<Item = (String, &'a str)>) -> Vec<String> {
    let items: Vec<(String, &str)> = items.into_iter().collect();
    let mut paths: std::collections::HashMap<&str, std::collections::HashSet<&str>> =
        std::collections::HashMap::new();
    for (name, path) in &items {
        paths.entry(name.as_str()).or_default().insert(path);
    }
    items
        .iter()
        .map(|(name, path)| {
            if paths[name.as_str()].len() > 1 {
                (*path).to_string()
            } else {
                name.clone()
            }
        })
        .collect()
}

/// An offending token for a message: [`bounded`] to [`MAX_EXCERPT_CHARS`].
pub fn excerpt(s: &str) -> String {
    bounded(s, MAX_EXCERPT_CHARS)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A name two paths share becomes each one's path; a name of one path (even when that
    /// path comes twice) stays.
    #[test]
    fn names_two_paths_share_become_the_paths() {
        let items = [
            ("m.obj", "a/m.obj"),
            ("m.obj", "b/m.obj"),
            ("n.obj", "c/n.obj"),
            ("n.obj", "c/n.obj"),
        ];
        assert_eq!(
            unambiguous_names(items.map(|(n, p)| (n.to_string(), p))),
            ["a/m.obj", "b/m.obj", "n.obj", "n.obj"]
        );
    }

    #[test]
    fn escapes_control_characters_and_truncates() {
        assert_eq!(excerpt("abc"), "abc");
        assert_eq!(excerpt("a\u{1b}[31mb\0"), "a\\u{1b}[31mb\\u{0}");
        let long = "x".repeat(10_000_000);
        let e = excerpt(&long);
        assert!(e.len() < 80, "{}", e.len());
        assert!(e.ends_with("… (10000000 bytes in all)"), "{e}");
        assert_eq!(bounded("héllo", 2), "hé… (6 bytes in all)");
        assert_eq!(
            path(std::path::Path::new("a\nerror: \u{1b}]0;x\u{7}")),
            "a\\nerror: \\u{1b}]0;x\\u{7}"
        );
        // A line separator and a right-to-left override: escaped, never shown raw.
        assert_eq!(
            escaped("a\u{2028}error: b\u{202E}jbo.x\u{2069}\u{2029}"),
            "a\\u{2028}error: b\\u{202e}jbo.x\\u{2069}\\u{2029}"
        );
        assert_eq!(escaped("née → ∞"), "née → ∞");
    }
}
