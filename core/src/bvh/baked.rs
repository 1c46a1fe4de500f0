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
    /// The first 8 bytes are not [`BAKED_MAGIC`] or the reserved bytes are not zero.
    Magic,
    /// A format version this code does not read.
    Version {
        /// The version found.
        found: u32,
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
        }
    }
}

impl core::error::Error for BakedError {}

/// The counts of a baked buffer, and from them where each array lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BakedLayout {
    /// Vertex positions.
    pub vertices: u32,
    /// Triangles (and primitive indices).
    pub triangles: u32,
    /// BVH nodes.
    pub nodes: u32,
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
    /// The header of `bytes`, checked: magic, version, reserved bytes, and a length that
    /// holds every array it announces (the arrays' contents are not read).
    ///
    /// # Errors
    ///
    /// [`BakedError::Short`] for fewer than [`BAKED_HEADER_BYTES`] bytes or fewer than
    /// [`BakedLayout::byte_len`]; [`BakedError::Magic`]; [`BakedError::Version`].
    pub fn read(bytes: &[u8]) -> Result<Self, BakedError> {
        let Some(header) = bytes.get(..BAKED_HEADER_BYTES) else {
            return Err(BakedError::Short {
                needed: BAKED_HEADER_BYTES as u64,
                available: bytes.len(),
            });
        };
        if header[..8] != BAKED_MAGIC || word(header, 24) != 0 || word(header, 28) != 0 {
            return Err(BakedError::Magic);
        }
        let version = word(header, 8);
        if version != BAKED_VERSION {
            return Err(BakedError::Version { found: version });
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

    /// `start..start + len` as `usize`s; only called on a layout [`BakedLayout::read`] accepted
    /// (every range within the buffer's length, so within `usize`).
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
    const ONE_TRIANGLE: BakedLayout = BakedLayout {
        vertices: 3,
        triangles: 1,
        nodes: 1,
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
