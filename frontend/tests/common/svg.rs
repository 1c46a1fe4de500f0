//! Reading an SVG chart back: shared by the chart module's unit tests (through `#[path]`) and
//! the `halfray chart` integration tests, so both read the output the same way.

/// The trimmed text of every `<text>` element of the SVG `bytes`, after checking they are
/// UTF-8, well-formed XML with an `<svg>` root, and — when `size` is given — that the root's
/// `width` and `height` are `size` (pixels). Panics, naming the failed check, otherwise.
pub fn svg_texts(bytes: &[u8], size: Option<(u32, u32)>) -> Vec<String> {
    let text = std::str::from_utf8(bytes).expect("UTF-8");
    let doc = roxmltree::Document::parse(text).expect("well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg");
    if let Some((w, h)) = size {
        assert_eq!(root.attribute("width"), Some(w.to_string().as_str()));
        assert_eq!(root.attribute("height"), Some(h.to_string().as_str()));
    }
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            n.descendants()
                .filter(|t| t.is_text())
                .filter_map(|t| t.text())
                .collect::<String>()
                .trim()
                .to_string()
        })
        .collect()
}
