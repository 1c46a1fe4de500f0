//! Typed element handles.
//!
//! Every handle is a `#[repr(transparent)]` newtype over a `u32` slot index, 4 bytes, `Copy`.
//! Absent links are expressed as `Option<Handle>` in the public API; the stored sentinel
//! ([`NONE`]) never escapes.
//!
//! Halfedges are allocated in twin pairs: halfedge `2e` and `2e + 1` belong to edge `e`, so
//! `twin(h) = h ^ 1` and `edge(h) = h >> 1` are pure arithmetic and stored nowhere.

/// The stored "no element" sentinel (`u32::MAX`). Never returned through the public API.
pub(crate) const NONE: u32 = u32::MAX;

macro_rules! handle {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[repr(transparent)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// A handle for slot `index`. The handle is not checked against any mesh: every
            /// mesh method treats a handle to a dead or out-of-range slot as invalid and
            /// returns `None` or an error, never panics.
            #[inline]
            pub const fn new(index: u32) -> Self {
                Self(index)
            }

            /// The slot index as `u32`.
            #[inline]
            pub const fn raw(self) -> u32 {
                self.0
            }

            /// The slot index as `usize` (for indexing caller arrays).
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

handle!(
    /// A vertex slot.
    VertexId
);
handle!(
    /// An edge slot; its halfedges are `2e` and `2e + 1`.
    EdgeId
);
handle!(
    /// A face (triangle) slot.
    FaceId
);
handle!(
    /// A halfedge slot. Halfedge `h` runs from its *tail* to its *head* vertex; its face (if
    /// any) is on its left, and faces are counter-clockwise seen from the front.
    HalfedgeId
);

impl HalfedgeId {
    /// The oppositely oriented halfedge of the same edge (`h ^ 1`).
    #[inline]
    #[must_use]
    pub const fn twin(self) -> Self {
        Self(self.0 ^ 1)
    }

    /// The edge this halfedge belongs to (`h >> 1`).
    #[inline]
    #[must_use]
    pub const fn edge(self) -> EdgeId {
        EdgeId(self.0 >> 1)
    }
}

impl EdgeId {
    /// Halfedge `side` (0 or 1; any other value is taken modulo 2) of this edge: `2e + side`.
    /// Saturates instead of overflowing for edge indices ≥ 2³¹ (which no mesh can hold).
    #[inline]
    #[must_use]
    pub const fn halfedge(self, side: u32) -> HalfedgeId {
        HalfedgeId(self.0.saturating_mul(2).saturating_add(side & 1))
    }
}
