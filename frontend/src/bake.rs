//! `halfray bake MESH -o OUT.rs` (or `--format bin`): the BVH built on the host, written as a
//! Rust source of `static` arrays that a `no_std` firmware includes and queries from flash, with
//! no copy and no allocation (or as a byte buffer, below).
//!
//! The file defines, with the `f32` values as exact bit patterns:
//!
//! | item | type |
//! |---|---|
//! | `POSITIONS` | `[halfray_core::Vec3; V]` |
//! | `TRIANGLES` | `[[u32; 3]; T]` |
//! | `NODES` | `[halfray_core::bvh::BvhNode; K]` (node 0 the root) |
//! | `INDICES` | `[u32; T]` |
//! | `LOAD_SCRATCH_WORDS` | `usize`: the bitset [`halfray_core::bvh::Bvh::from_parts`] needs |
//!
//! and is loaded with
//! `Bvh::from_parts(&NODES[..], &INDICES[..], &TriangleMesh::new(&POSITIONS, &TRIANGLES), &mut [0u32; LOAD_SCRATCH_WORDS])`,
//! which checks it as untrusted input (`halfray_core::bvh::LoadError`). The bake runs that check
//! itself before writing.
//!
//! With `--format bin`, the same mesh and BVH are written as one byte buffer in the layout of
//! [`halfray_core::bvh::BakedLayout`], for C firmware (`halfray-ffi`'s `halfray_load`) or any
//! reader that loads it from a file.

use crate::accel::build_binary;
use crate::error::{Error, Location, Result};
use crate::mesh_tools::reserve_output;
use crate::obj::read_obj;
use halfray_core::bvh::{BakedLayout, BuildOptions, Bvh, BvhNode, load_scratch_len};
use halfray_core::mesh::TriangleMesh;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `halfray bake`.
#[derive(clap::Args, Debug, Clone)]
pub struct BakeArgs {
    /// Input OBJ.
    pub input: PathBuf,
    /// Output file: the Rust source or the byte buffer, as `--format` says (written
    /// atomically; never the input).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace an output that is read-only or hard-linked (keeping its mode).
    #[arg(long)]
    pub force: bool,
    /// What to write: a Rust source of `static` arrays, or the byte buffer C firmware loads.
    #[arg(long, value_enum, default_value_t = BakeFormat::Rust)]
    pub format: BakeFormat,
}

/// The output forms of `halfray bake`.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum BakeFormat {
    /// Rust source of `static` arrays (module docs).
    Rust,
    /// One little-endian byte buffer ([`halfray_core::bvh::BakedLayout`]).
    Bin,
}

/// Runs `halfray bake`: prints one line with the counts and sizes.
pub fn run(args: &BakeArgs) -> Result<()> {
    let out = reserve_output(&args.input, &args.output, args.force)?;
    let mesh = read_obj(&args.input)?;
    let tri = TriangleMesh::new(&mesh.positions, &mesh.triangles);
    let bvh = build_binary(&tri, &BuildOptions::default()).map_err(|e| {
        Error::input(
            Location::file(&args.input),
            format!("building the BVH: {e}"),
        )
    })?;
    // The loader's own check: what is written loads.
    let mut scratch = vec![0u32; load_scratch_len(tri.len())];
    Bvh::from_parts(bvh.nodes(), bvh.indices(), &tri, &mut scratch).map_err(|e| {
        Error::internal(
            format!(
                "{}: the built BVH fails its load check",
                crate::text::path(&args.input)
            ),
            Some(Box::new(e)),
        )
    })?;
    let data = match args.format {
        BakeFormat::Rust => source(
            &args.input,
            &mesh.positions,
            &mesh.triangles,
            bvh.nodes(),
            bvh.indices(),
        )
        .into_bytes(),
        BakeFormat::Bin => bytes(
            &args.input,
            &mesh.positions,
            &mesh.triangles,
            bvh.nodes(),
            bvh.indices(),
        )?,
    };
    out.write(|w| w.write_all(&data))?;
    let flash = std::mem::size_of_val(&mesh.positions[..])
        + std::mem::size_of_val(&mesh.triangles[..])
        + std::mem::size_of_val(bvh.nodes())
        + std::mem::size_of_val(bvh.indices());
    // The binary form's file is the arrays after its header: say both.
    let size = match args.format {
        BakeFormat::Rust => format!("{flash} bytes of static data"),
        BakeFormat::Bin => format!(
            "{} bytes ({flash} of arrays after a {}-byte header)",
            data.len(),
            data.len() - flash
        ),
    };
    crate::console::print_out(&format!(
        "baked {}: {} vertices, {} triangles, {} nodes, {size} -> {}\n",
        crate::text::path(&args.input),
        mesh.positions.len(),
        mesh.triangles.len(),
        bvh.nodes().len(),
        crate::text::path(&args.output)
    ))
}

/// The byte buffer of a baked BVH ([`halfray_core::bvh::BakedLayout`]).
///
/// # Errors
///
/// An input error naming `input` when a count does not fit the format's `u32`, or the buffer
/// would be larger than this target can hold ([`BakedLayout::new`]).
pub fn bytes(
    input: &Path,
    positions: &[glam::Vec3],
    triangles: &[[u32; 3]],
    nodes: &[BvhNode],
    indices: &[u32],
) -> Result<Vec<u8>> {
    let count = |n: usize, what: &str| {
        u32::try_from(n).map_err(|_| {
            Error::input(
                Location::file(input),
                format!("{n} {what}: more than the baked format's u32 count"),
            )
        })
    };
    let layout = BakedLayout::new(
        count(positions.len(), "vertices")?,
        count(triangles.len(), "triangles")?,
        count(nodes.len(), "BVH nodes")?,
    )
    .map_err(|e| Error::input(Location::file(input), e.to_string()))?;
    let mut b = Vec::with_capacity(usize::try_from(layout.byte_len()).unwrap_or(0));
    b.extend_from_slice(&layout.header());
    let mut words = |ws: &[u32]| {
        ws.iter()
            .for_each(|w| b.extend_from_slice(&w.to_le_bytes()))
    };
    for n in nodes {
        let (bounds, start, count) = n.to_raw();
        let [lo, hi] = bounds.map(|v| v.map(f32::to_bits));
        words(&lo);
        words(&hi);
        words(&[start, count]);
    }
    for p in positions {
        words(&p.to_array().map(f32::to_bits));
    }
    for t in triangles {
        words(t);
    }
    words(indices);
    Ok(b)
}

/// `f32::from_bits(0x…)`: exact, and valid in a `static` initialiser.
fn bits(x: f32) -> String {
    format!("f32::from_bits(0x{:08x})", x.to_bits())
}

/// `s` made safe inside a Rust `//` comment: control characters (a line break would end the
/// comment and start code), line and paragraph separators, and the bidirectional-text
/// controls rustc refuses in comments (`text_direction_codepoint_in_comment`) are written as
/// `\u{…}` escapes; everything else stays as is.
pub fn comment_text(s: &str) -> String {
    s.chars()
        .map(|c| {
            let unsafe_char = c.is_control()
                || matches!(
                    c,
                    '\u{2028}'
                        | '\u{2029}'
                        | '\u{061c}'
                        | '\u{200e}'
                        | '\u{200f}'
                        | '\u{202a}'..='\u{202e}'
                        | '\u{2066}'..='\u{2069}'
                );
            if unsafe_char {
                c.escape_unicode().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// The Rust source of a baked BVH (see the module docs).
pub fn source(
    input: &Path,
    positions: &[glam::Vec3],
    triangles: &[[u32; 3]],
    nodes: &[BvhNode],
    indices: &[u32],
) -> String {
    let name = comment_text(
        &input
            .file_name()
            .map_or_else(|| input.to_string_lossy(), |n| n.to_string_lossy()),
    );
    let mut s = String::new();
    // `write!` into a `String` cannot fail.
    let _ = writeln!(
        s,
        "// Baked by `halfray bake` from `{name}`: {} vertices, {} triangles, {} BVH nodes. Do not edit.\n\
         // Load with `halfray_core::bvh::Bvh::from_parts(&NODES[..], &INDICES[..], &halfray_core::mesh::TriangleMesh::new(&POSITIONS, &TRIANGLES), &mut [0u32; LOAD_SCRATCH_WORDS])`.\n",
        positions.len(),
        triangles.len(),
        nodes.len()
    );
    let _ = writeln!(
        s,
        "/// Words of the bitset `Bvh::from_parts` needs.\npub const LOAD_SCRATCH_WORDS: usize = {};\n",
        load_scratch_len(triangles.len())
    );
    let _ = writeln!(
        s,
        "/// Vertex positions.\npub static POSITIONS: [halfray_core::Vec3; {}] = [",
        positions.len()
    );
    for p in positions {
        let _ = writeln!(
            s,
            "    halfray_core::Vec3::new({}, {}, {}),",
            bits(p.x),
            bits(p.y),
            bits(p.z)
        );
    }
    let _ = writeln!(
        s,
        "];\n\n/// Triangles (indices into `POSITIONS`).\npub static TRIANGLES: [[u32; 3]; {}] = [",
        triangles.len()
    );
    for t in triangles {
        let _ = writeln!(s, "    [{}, {}, {}],", t[0], t[1], t[2]);
    }
    let _ = writeln!(
        s,
        "];\n\n/// BVH nodes (`BvhNode::from_raw(bounds, start, count)`).\npub static NODES: [halfray_core::bvh::BvhNode; {}] = [",
        nodes.len()
    );
    for n in nodes {
        let (b, start, count) = n.to_raw();
        let _ = writeln!(
            s,
            "    halfray_core::bvh::BvhNode::from_raw([[{}, {}, {}], [{}, {}, {}]], {start}, {count}),",
            bits(b[0][0]),
            bits(b[0][1]),
            bits(b[0][2]),
            bits(b[1][0]),
            bits(b[1][1]),
            bits(b[1][2])
        );
    }
    let _ = writeln!(
        s,
        "];\n\n/// Primitive indices in leaf order.\npub static INDICES: [u32; {}] = [",
        indices.len()
    );
    for chunk in indices.chunks(16) {
        let line: Vec<String> = chunk.iter().map(u32::to_string).collect();
        let _ = writeln!(s, "    {},", line.join(", "));
    }
    s.push_str("];\n");
    s
}
