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
