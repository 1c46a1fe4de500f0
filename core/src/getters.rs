//! Read-only accessors of `Copy` fields, written once.

/// Expands, inside an inherent `impl` block, to one public `#[inline]`, `#[must_use]` method
/// per entry that returns a copy of the field of the same name, with the entry's doc comment:
///
/// ```text
/// getters! {
///     /// Centre, world units.
///     center: Vec3;
/// }
/// ```
///
/// For types whose fields hold an invariant the constructor checked, so the fields stay
/// private and the accessors are the read-only view.
macro_rules! getters {
    ($($(#[$doc:meta])* $name:ident: $ty:ty;)+) => {
        $(
            $(#[$doc])*
            #[inline]
            #[must_use]
            pub fn $name(&self) -> $ty {
                self.$name
            }
        )+
    };
}

pub(crate) use getters;

/// Expands, inside an inherent `impl` block, to one public `#[inline]`, `#[must_use]` method
/// per entry returning a count kept in a `u32` field as `usize`, with the entry's doc comment:
///
/// ```text
/// count_getters! {
///     /// Number of primitives in the tree.
///     primitive_count = prim_count;
/// }
/// ```
macro_rules! count_getters {
    ($($(#[$doc:meta])* $name:ident = $field:ident;)+) => {
        $(
            $(#[$doc])*
            #[inline]
            #[must_use]
            pub fn $name(&self) -> usize {
                self.$field as usize
            }
        )+
    };
}

pub(crate) use count_getters;
