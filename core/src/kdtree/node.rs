//! The 8-byte kd-tree node.

/// Tag of a leaf in the low two bits of [`KdNode`]'s second word (0, 1, 2 are split axes).
const LEAF_TAG: u32 = 3;

/// Largest child index or leaf size the 30 upper bits of a node's second word hold.
pub(super) const MAX_FIELD: u32 = (1 << 30) - 1;

/// One kd-tree node, **8 bytes**: two `u32` words.
///
/// * Inner node: word 0 is the split position (an `f32`'s bits, world units); word 1 is
///   `first_child << 2 | axis` (`axis` 0, 1 or 2). The child below the plane is `first_child`,
///   the one above is `first_child + 1` (children are allocated in pairs, after their parent).
/// * Leaf: word 0 is the offset of its run in the reference array; word 1 is `count << 2 | 3`.
///
/// Nodes are written only by the builder ([`super::KdTree::build`]); there is no way to
/// assemble a tree from raw nodes, so every tree obeys the depth bound the traversal stack
/// relies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct KdNode {
    word: u32,
    bits: u32,
}

/// [`KdNode::EMPTY`], the empty leaf storage is filled with (all-zero words would be an inner
/// node whose first child is itself).
impl Default for KdNode {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// What a node is, decoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KdNodeKind {
    /// An inner node: split `axis` at `position`; children `first` (below) and `first + 1`.
    Inner {
        /// Split axis: 0, 1 or 2.
        axis: usize,
        /// Split plane position along `axis`, world units.
        position: f32,
        /// Index of the child below the plane; the one above is the next node.
        first: u32,
    },
    /// A leaf: `count` primitive references starting at `start` in the reference array.
    Leaf {
        /// Offset in the reference array.
        start: u32,
        /// Number of references.
        count: u32,
    },
}

impl KdNode {
    /// An empty leaf (no references): what storage is filled with before a build.
    pub const EMPTY: Self = Self {
        word: 0,
        bits: LEAF_TAG,
    };

    /// A leaf over `count` references from `start` (`count ≤ 2³⁰ − 1`, checked by the builder).
    #[inline]
    pub(super) const fn leaf(start: u32, count: u32) -> Self {
        Self {
            word: start,
            bits: count << 2 | LEAF_TAG,
        }
    }

    /// An inner node splitting `axis` (0..3) at `position`, children `first`, `first + 1`.
    #[inline]
    pub(super) fn inner(axis: usize, position: f32, first: u32) -> Self {
        Self {
            word: position.to_bits(),
            bits: first << 2 | (axis as u32 & 3),
        }
    }

    /// The node decoded.
    #[inline(always)]
    #[must_use]
    pub fn kind(&self) -> KdNodeKind {
        let tag = self.bits & 3;
        if tag == LEAF_TAG {
            KdNodeKind::Leaf {
                start: self.word,
                count: self.bits >> 2,
            }
        } else {
            KdNodeKind::Inner {
                axis: tag as usize,
                position: f32::from_bits(self.word),
                first: self.bits >> 2,
            }
        }
    }

    /// `true` for a leaf.
    #[inline]
    #[must_use]
    pub fn is_leaf(&self) -> bool {
        self.bits & 3 == LEAF_TAG
    }
}

/// Size of a [`KdNode`] in bytes.
pub const NODE_SIZE: usize = core::mem::size_of::<KdNode>();

const _: () = assert!(NODE_SIZE == 8);

#[cfg(test)]
mod tests {
    use super::*;

    /// The two words of the documented layout, worked by hand: an inner node splitting z
    /// (axis 2) at 1.5 with children 7 and 8 is `1.5`'s bits (`0x3FC0_0000`) and
    /// `7 << 2 | 2 = 30`; a leaf of 5 references from offset 9 is `9` and `5 << 2 | 3 = 23`.
    #[test]
    fn nodes_are_the_documented_words() {
        let inner = KdNode::inner(2, 1.5, 7);
        assert_eq!((inner.word, inner.bits), (0x3FC0_0000, 30));
        let want = KdNodeKind::Inner {
            axis: 2,
            position: 1.5,
            first: 7,
        };
        assert_eq!(inner.kind(), want);
        assert!(!inner.is_leaf());
        let leaf = KdNode::leaf(9, 5);
        assert_eq!((leaf.word, leaf.bits), (9, 23));
        assert_eq!(leaf.kind(), KdNodeKind::Leaf { start: 9, count: 5 });
        assert!(leaf.is_leaf());
        let top = KdNode::inner(0, -0.0, MAX_FIELD);
        assert_eq!(top.bits, 0xFFFF_FFFC);
        assert!(matches!(
            top.kind(),
            KdNodeKind::Inner {
                first: MAX_FIELD,
                axis: 0,
                ..
            }
        ));
    }
}
