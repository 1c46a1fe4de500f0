//! The build scratch's record: a primitive reference with its clipped box.

/// One reference in the build scratch: a primitive's index and its box clipped to the cell
/// of the node it is in (28 bytes). Callers make the scratch of [`KdRef::EMPTY`]s; its
/// contents after a build mean nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdRef {
    pub(super) min: [f32; 3],
    pub(super) max: [f32; 3],
    pub(super) prim: u32,
}

impl KdRef {
    /// A record to fill a scratch array with.
    pub const EMPTY: Self = Self {
        min: [0.0; 3],
        max: [0.0; 3],
        prim: 0,
    };
}
