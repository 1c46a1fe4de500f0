//! The byte form of a baked BVH (`halfray bake --format bin`): one buffer holding a mesh and
//! its BVH, which a C firmware links into flash or a program reads from a file, and which
//! `halfray-ffi` loads without a copy. This module states the layout once, for the writer and
//! the readers; it reads only the header; the arrays are checked by [`super::Bvh::from_parts`].
//!
//! All fields are little-endian; offsets are from the buffer's start, which must be
//! [`BAKED_ALIGN`]-aligned for the arrays to be read in place:
//!
//! | bytes | field |
//! |---|---|
//! | `0..8` | [`BAKED_MAGIC`] |
//! | `8..12` | format version, [`BAKED_VERSION`] |
//! | `12..16` | `V`, vertices |
//! | `16..20` | `T`, triangles |
//! | `20..24` | `K`, BVH nodes |
//! | `24..32` | zero (reserved) |
//! | `32..` | `K` nodes, 32 bytes each: `min[3]`, `max[3]` (`f32`), `start`, `count` (`u32`), as [`super::BvhNode`]'s `repr(C)` layout |
//! | then | `V` positions, `x, y, z` (`f32`, 12 bytes each) |
//! | then | `T` triangles, three `u32` vertex indices each |
//! | then | `T` primitive indices (`u32`), in leaf order |
//!
//! Nodes come first, so that they stay 32-byte aligned (every section starts on a 4-byte
//! boundary). Bytes after the last section are ignored.

use core::fmt;
use core::ops::Range;

/// The first 8 bytes of a baked buffer.
pub const BAKED_MAGIC: [u8; 8] = *b"halfray\0";
/// The format version this code writes and reads.
pub const BAKED_VERSION: u32 = 1;
/// Bytes every format version starts with: the magic and the version.
const VERSIONED_BYTES: usize = 12;
/// Bytes of the header; the node array starts there.
pub const BAKED_HEADER_BYTES: usize = 32;
/// Alignment, in bytes, a baked buffer's start must have to be read in place: the node's.
pub const BAKED_ALIGN: usize = core::mem::align_of::<super::BvhNode>();
/// Bytes per vertex position, per triangle and per primitive index.
const POSITION_BYTES: u64 = 12;
const TRIANGLE_BYTES: u64 = 12;
const INDEX_BYTES: u64 = 4;

/// Why a buffer's header was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum BakedError {
    /// The buffer is shorter than the header, or than the arrays the header announces.
    Short {
        /// Bytes the header (or the header and its arrays) need.
        needed: u64,
        /// Bytes given.
        available: usize,
    },
    /// The first 8 bytes are not [`BAKED_MAGIC`], or the reserved bytes of a version-1 header
    /// are not zero.
    Magic,
    /// A format version this code does not read.
    Version {
        /// The version found.
        found: u32,
    },
    /// The counts announce more bytes than a buffer can have on this target (`isize::MAX`,
    /// the largest slice: 2 GiB on a 32-bit target), so their byte ranges would not fit a
    /// `usize` ([`BakedLayout::new`]).
    TooLarge {
        /// Bytes of the header and arrays the counts announce.
        needed: u64,
    },
}

impl fmt::Display for BakedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Short { needed, available } => write!(
                f,
                "baked BVH of {available} bytes, its header needs {needed}"
            ),
            Self::Magic => f.write_str("not a baked BVH (magic or reserved bytes differ)"),
            Self::Version { found } => write!(
                f,
                "baked BVH format version {found}, this build reads {BAKED_VERSION}"
            ),
            Self::TooLarge { needed } => write!(
                f,
                "baked BVH of {needed} bytes, more than a buffer on this target can hold"
            ),
        }
    }
}

impl core::error::Error for BakedError {}

/// The counts of a baked buffer, and from them where each array lies.
///
/// Made by [`BakedLayout::read`] (from a buffer's header) or [`BakedLayout::new`] (from
/// counts, for a writer), both checked: the buffer the counts announce, [`BakedLayout::byte_len`]
/// bytes, is at most `isize::MAX` bytes, so every byte range (`node_bytes` and the others)
/// is exact in `usize` on every target. The fields are private so that no layout skips that
/// check (on a 32-bit target, a hand-made one could announce more than 4 GiB and its ranges
/// would wrap):
///
/// ```compile_fail,E0451
/// use halfray_core::bvh::BakedLayout;
/// let unchecked = BakedLayout { vertices: u32::MAX, triangles: u32::MAX, nodes: u32::MAX };
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BakedLayout {
    /// Vertex positions.
    vertices: u32,
    /// Triangles (and primitive indices).
    triangles: u32,
    /// BVH nodes.
    nodes: u32,
}

/// The little-endian `u32` at `bytes[at..at + 4]` (the caller has checked the length).
fn word(bytes: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(b) = bytes.get(at..at + 4) {
        w.copy_from_slice(b);
    }
    u32::from_le_bytes(w)
}

impl BakedLayout {
    /// The layout of `vertices` positions, `triangles` triangles (and as many primitive
    /// indices) and `nodes` BVH nodes, for writing a buffer ([`BakedLayout::header`], then the
    /// arrays at the byte ranges below).
    ///
    /// # Errors
    ///
    /// [`BakedError::TooLarge`] when the buffer, [`BakedLayout::byte_len`] bytes, would exceed
    /// `isize::MAX` bytes (only possible on targets with pointers narrower than 64 bits).
    pub const fn new(vertices: u32, triangles: u32, nodes: u32) -> Result<Self, BakedError> {
        Self::within(vertices, triangles, nodes, isize::MAX as u64)
    }

    /// [`BakedLayout::new`] with the largest buffer `max_bytes` (this target's `isize::MAX`
    /// there; tests pass a 32-bit target's).
    const fn within(
        vertices: u32,
        triangles: u32,
        nodes: u32,
        max_bytes: u64,
    ) -> Result<Self, BakedError> {
        let layout = Self {
            vertices,
            triangles,
            nodes,
        };
        let needed = layout.byte_len();
        if needed > max_bytes {
            return Err(BakedError::TooLarge { needed });
        }
        Ok(layout)
    }

    /// Vertex positions.
    #[must_use]
    pub const fn vertices(&self) -> u32 {
        self.vertices
    }

    /// Triangles (and primitive indices).
    #[must_use]
    pub const fn triangles(&self) -> u32 {
        self.triangles
    }

    /// BVH nodes.
    #[must_use]
    pub const fn nodes(&self) -> u32 {
        self.nodes
    }

    /// The header of `bytes`, checked: magic, version, reserved bytes, and a length that
    /// holds every array it announces (the arrays' contents are not read).
    ///
    /// # Errors
    ///
    /// [`BakedError::Short`] for fewer than [`BAKED_HEADER_BYTES`] bytes or fewer than
    /// [`BakedLayout::byte_len`]; [`BakedError::Magic`]; [`BakedError::Version`].
    pub fn read(bytes: &[u8]) -> Result<Self, BakedError> {
        // The magic and the version first, from the bytes every version shares: another
        // version may use the reserved bytes, or a longer header, and is reported as itself.
        if let Some(id) = bytes.get(..VERSIONED_BYTES) {
            if id[..8] != BAKED_MAGIC {
                return Err(BakedError::Magic);
            }
            let version = word(id, 8);
            if version != BAKED_VERSION {
                return Err(BakedError::Version { found: version });
            }
        }
        let Some(header) = bytes.get(..BAKED_HEADER_BYTES) else {
            return Err(BakedError::Short {
                needed: BAKED_HEADER_BYTES as u64,
                available: bytes.len(),
            });
        };
        if word(header, 24) != 0 || word(header, 28) != 0 {
            return Err(BakedError::Magic);
        }
        let layout = Self {
            vertices: word(header, 12),
            triangles: word(header, 16),
            nodes: word(header, 20),
        };
        let needed = layout.byte_len();
        if needed > bytes.len() as u64 {
            return Err(BakedError::Short {
                needed,
                available: bytes.len(),
            });
        }
        Ok(layout)
    }

    /// Bytes of the header and arrays (at most about 2^40: never overflows `u64`).
    #[must_use]
    pub const fn byte_len(&self) -> u64 {
        self.indices_at() + INDEX_BYTES * self.triangles as u64
    }

    /// The header's 32 bytes.
    #[must_use]
    pub fn header(&self) -> [u8; BAKED_HEADER_BYTES] {
        let mut h = [0u8; BAKED_HEADER_BYTES];
        h[..8].copy_from_slice(&BAKED_MAGIC);
        for (k, w) in [BAKED_VERSION, self.vertices, self.triangles, self.nodes]
            .into_iter()
            .enumerate()
        {
            h[8 + 4 * k..12 + 4 * k].copy_from_slice(&w.to_le_bytes());
        }
        h
    }

    const fn positions_at(&self) -> u64 {
        BAKED_HEADER_BYTES as u64 + super::NODE_SIZE as u64 * self.nodes as u64
    }

    const fn triangles_at(&self) -> u64 {
        self.positions_at() + POSITION_BYTES * self.vertices as u64
    }

    const fn indices_at(&self) -> u64 {
        self.triangles_at() + TRIANGLE_BYTES * self.triangles as u64
    }

    /// `start..start + len` as `usize`s. Exact: every layout was checked by
    /// [`BakedLayout::read`] (every range within the buffer's length) or [`BakedLayout::new`]
    /// (the whole layout at most `isize::MAX` bytes), so every range is within `usize`.
    fn range(start: u64, len: u64) -> Range<usize> {
        start as usize..(start + len) as usize
    }

    /// Byte range of the node array.
    #[must_use]
    pub fn node_bytes(&self) -> Range<usize> {
        Self::range(
            BAKED_HEADER_BYTES as u64,
            self.positions_at() - BAKED_HEADER_BYTES as u64,
        )
    }

    /// Byte range of the vertex positions.
    #[must_use]
    pub fn position_bytes(&self) -> Range<usize> {
        Self::range(self.positions_at(), POSITION_BYTES * self.vertices as u64)
    }

    /// Byte range of the triangles.
    #[must_use]
    pub fn triangle_bytes(&self) -> Range<usize> {
        Self::range(self.triangles_at(), TRIANGLE_BYTES * self.triangles as u64)
    }

    /// Byte range of the primitive indices.
    #[must_use]
    pub fn index_bytes(&self) -> Range<usize> {
        Self::range(self.indices_at(), INDEX_BYTES * self.triangles as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A buffer of the given counts: header, then zeros.
    /// One triangle over three vertices in a one-node tree.
    const ONE_TRIANGLE: BakedLayout = match BakedLayout::new(3, 1, 1) {
        Ok(l) => l,
        Err(_) => panic!("a one-triangle layout fits"),
    };

    fn buffer(l: BakedLayout) -> [u8; 256] {
        let mut b = [0u8; 256];
        b[..32].copy_from_slice(&l.header());
        b
    }

    #[test]
    fn the_header_reads_back_and_the_arrays_follow_the_table() {
        let l = ONE_TRIANGLE;
        let b = buffer(l);
        // The table: magic, version 1, V, T, K, zero, then 32-byte nodes, 12-byte positions,
        // 12-byte triangles, 4-byte indices.
        assert_eq!(&b[..8], b"halfray\0");
        assert_eq!(&b[8..24], &[1, 0, 0, 0, 3, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0]);
        assert_eq!(BakedLayout::read(&b), Ok(l));
        assert_eq!(l.node_bytes(), 32..64);
        assert_eq!(l.position_bytes(), 64..100);
        assert_eq!(l.triangle_bytes(), 100..112);
        assert_eq!(l.index_bytes(), 112..116);
        assert_eq!(l.byte_len(), 116);
        assert_eq!(BakedLayout::read(&b[..116]), Ok(l));
        assert_eq!(BAKED_ALIGN, 32);
    }

    #[test]
    fn short_foreign_and_future_buffers_are_refused() {
        let l = ONE_TRIANGLE;
        let b = buffer(l);
        assert_eq!(
            BakedLayout::read(&b[..115]),
            Err(BakedError::Short {
                needed: 116,
                available: 115
            })
        );
        assert_eq!(
            BakedLayout::read(&b[..31]),
            Err(BakedError::Short {
                needed: 32,
                available: 31
            })
        );
        let mut bad = b;
        bad[0] = b'H';
        assert_eq!(BakedLayout::read(&bad), Err(BakedError::Magic));
        let mut bad = b;
        bad[31] = 1;
        assert_eq!(BakedLayout::read(&bad), Err(BakedError::Magic));
        let mut bad = b;
        bad[8] = 2;
        assert_eq!(
            BakedLayout::read(&bad),
            Err(BakedError::Version { found: 2 })
        );
        // Another version is reported as itself whatever it puts in the reserved bytes, and
        // from its first 12 bytes (its header may be shorter or longer).
        bad[24] = 1;
        assert_eq!(
            BakedLayout::read(&bad),
            Err(BakedError::Version { found: 2 })
        );
        assert_eq!(
            BakedLayout::read(&bad[..12]),
            Err(BakedError::Version { found: 2 })
        );
        assert_eq!(
            BakedLayout::read(&b"halfrax\0\x01\0\0\0"[..]),
            Err(BakedError::Magic)
        );
    }

    /// `new` accepts the counts whose buffer a target can hold and refuses the others: with a
    /// 32-bit target's limit (`2³¹ − 1` bytes), `2²⁶ − 1` nodes (with the header, 2 GiB) are
    /// refused and one node fewer is taken, while a 64-bit host takes every `u32` count. The layouts it accepts read back from their
    /// own header, and their ranges tile the buffer.
    #[test]
    fn new_refuses_layouts_beyond_the_targets_largest_buffer() {
        let i32_max = i32::MAX as u64;
        assert_eq!(
            BakedLayout::within(0, 0, (1 << 26) - 1, i32_max),
            Err(BakedError::TooLarge { needed: 1 << 31 })
        );
        let fits = BakedLayout::within(0, 0, (1 << 26) - 2, i32_max).unwrap();
        assert_eq!(fits.byte_len(), (1 << 31) - 32);
        assert!(BakedLayout::within(u32::MAX, 0, 0, i32_max).is_err());
        let l = BakedLayout::new(3, 1, 1).unwrap();
        assert_eq!((l.vertices(), l.triangles(), l.nodes()), (3, 1, 1));
        assert_eq!(BakedLayout::read(&buffer(l)), Ok(l));
        assert_eq!(l.node_bytes().end, l.position_bytes().start);
        assert_eq!(l.position_bytes().end, l.triangle_bytes().start);
        assert_eq!(l.triangle_bytes().end, l.index_bytes().start);
        assert_eq!(l.index_bytes().end as u64, l.byte_len());
        #[cfg(target_pointer_width = "64")]
        {
            let big = BakedLayout::new(u32::MAX, u32::MAX, u32::MAX).unwrap();
            assert_eq!(big.index_bytes().end as u64, big.byte_len());
        }
        let e = std::format!("{}", BakedError::TooLarge { needed: 5 << 30 });
        assert!(e.contains("5368709120 bytes"), "{e}");
    }

    #[test]
    fn counts_at_the_u32_limit_do_not_overflow() {
        let l = BakedLayout {
            vertices: u32::MAX,
            triangles: u32::MAX,
            nodes: u32::MAX,
        };
        let b = buffer(l);
        // 32 + 32·K + 12·V + 16·T, exactly, in u64.
        let needed = 32 + 60 * u64::from(u32::MAX);
        assert_eq!(
            BakedLayout::read(&b),
            Err(BakedError::Short {
                needed,
                available: 256
            })
        );
    }
}
