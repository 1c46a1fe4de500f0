//! Owned arrays for the acceleration structures, backed by 2 MiB pages where the OS gives them.
//!
//! A ray's walk through a BVH touches a few nodes and triangle groups scattered over many
//! megabytes; with 4 KiB pages most of those reads also miss the TLB. Embree asks Linux for
//! transparent huge pages (`madvise(MADV_HUGEPAGE)`) on its large allocations, and on a
//! machine whose THP mode is `madvise` (the common default) it gets them while a plain `Vec`
//! does not. [`PageArray`] does the same for the frontend's trees: a large array is a mapping
//! of its own, starting on a 2 MiB boundary and advised before any element is written (advice
//! given after the first touch does not change pages already mapped).
//!
//! A build's storage is sized for its worst case (a binary tree's `2n − 1` nodes) and mostly
//! written once by the build itself: [`PageArray::zeroed`] hands such storage out untouched,
//! so that the pages the build never reaches cost nothing and the others are written once
//! after the kernel zeroes them, instead of being filled with a constant first.
//!
//! The advice is a hint: where the OS declines it, or on another OS, the array is an
//! ordinary heap array with the same contents.

use std::ops::{Deref, DerefMut};

/// The huge page size advised for: 2 MiB (x86-64 and aarch64 Linux). Bytes.
pub const HUGE_PAGE: usize = 2 << 20;

/// Arrays smaller than this many bytes are not advised: one huge page. The first touch of a
/// huge page clears all 2 MiB of it (and, with the kernel's `defrag` setting `madvise`, may
/// compact memory to find one), where 4 KiB pages clear only what is touched: below one huge
/// page an array would pay more clearing than it holds, and its 4 KiB pages fit the
/// second-level TLB (the build of a 16 719-triangle mesh, arrays of 0.5–1.2 MiB: 0.96–0.97×
/// Embree's one-thread build time with this threshold, 1.08–1.10× with 512 KiB;
/// `docs/performance.md`). Bytes.
pub const ADVISE_MIN_BYTES: usize = HUGE_PAGE;

/// Types whose all-zero bit pattern is a valid value: [`PageArray::zeroed`] hands out fresh
/// memory that the OS zeroed as such values, without writing it.
///
/// # Safety
///
/// Every byte of `Self` may be zero at once and the result is a valid `Self` (plain numbers
/// and arrays of them: no references, no `NonZero`, no enums without a zero discriminant).
pub unsafe trait ZeroValid: Copy {}

// SAFETY (all four): `BvhNode` is `repr(C)` `[[f32; 3]; 2]`, `u32`, `u32`; `PrimRef` is two
// glam vectors of `f32` (`__m128` on x86-64; elsewhere `Vec3`s and a `u32`); `WideNode<W>` is
// `repr(C)` arrays of `f32` and `u32`; `LeafGroup` is `repr(C)` arrays of `f32` and `u32`
// (`TriangleLanes` is `[[[f32; 4]; 3]; 3]`). Zero is a valid `f32` (+0.0) and `u32`, padding
// included (padding may hold any bytes).
unsafe impl ZeroValid for halfray_core::bvh::BvhNode {}
unsafe impl ZeroValid for halfray_core::bvh::PrimRef {}
unsafe impl<const W: usize> ZeroValid for halfray_core::bvh::wide::WideNode<W> {}
unsafe impl ZeroValid for halfray_core::bvh::wide::LeafGroup {}

/// `len` values in one buffer. Arrays of at least [`ADVISE_MIN_BYTES`] are (on Linux) a
/// private anonymous mapping of their own that starts on a [`HUGE_PAGE`] boundary and is
/// advised for huge pages before anything touches it; smaller ones (and all on other
/// systems, or when the mapping is refused) are an ordinary heap array. Dereferences to `[T]`.
pub struct PageArray<T> {
    buf: Buf<T>,
}

enum Buf<T> {
    Heap(Vec<T>),
    #[cfg(target_os = "linux")]
    Mapped(mapping::Mapping<T>),
}

impl<T: Copy> PageArray<T> {
    /// `len` copies of `value`, each written once.
    #[must_use]
    pub fn filled(value: T, len: usize) -> Self {
        #[cfg(target_os = "linux")]
        if let Some(mut m) = mapping::Mapping::new(len) {
            m.spare().fill(std::mem::MaybeUninit::new(value));
            // SAFETY: every element was just written.
            return Self {
                buf: Buf::Mapped(unsafe { m.assume_init() }),
            };
        }
        Self {
            buf: Buf::Heap(vec![value; len]),
        }
    }
}

impl<T: ZeroValid> PageArray<T> {
    /// `len` all-zero values. A large array is fresh memory the OS zeroes page by page when
    /// it is first touched: nothing is written here, and pages never touched cost neither a
    /// fault nor zeroing (storage sized for a worst case that the build does not reach).
    #[must_use]
    pub fn zeroed(len: usize) -> Self {
        #[cfg(target_os = "linux")]
        if let Some(m) = mapping::Mapping::new(len) {
            // SAFETY: a fresh private anonymous mapping reads as zero bytes (mmap(2): its
            // contents are initialised to zero), and all-zero bytes are a valid `T`
            // (`T: ZeroValid`).
            return Self {
                buf: Buf::Mapped(unsafe { m.assume_init() }),
            };
        }
        // SAFETY: all-zero bytes are a valid `T` (`T: ZeroValid`).
        let zero = unsafe { std::mem::zeroed::<T>() };
        Self {
            buf: Buf::Heap(vec![zero; len]),
        }
    }
}

impl<T: Copy> Clone for PageArray<T> {
    fn clone(&self) -> Self {
        #[cfg(target_os = "linux")]
        if let Some(mut m) = mapping::Mapping::new(self.len()) {
            for (slot, v) in m.spare().iter_mut().zip(self.iter()) {
                slot.write(*v);
            }
            // SAFETY: the mapping has `self.len()` elements, each just written from `self`.
            return Self {
                buf: Buf::Mapped(unsafe { m.assume_init() }),
            };
        }
        Self {
            buf: Buf::Heap(self.to_vec()),
        }
    }
}

impl<T> Deref for PageArray<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        match &self.buf {
            Buf::Heap(v) => v,
            #[cfg(target_os = "linux")]
            Buf::Mapped(m) => m.as_slice(),
        }
    }
}

impl<T> DerefMut for PageArray<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.buf {
            Buf::Heap(v) => v,
            #[cfg(target_os = "linux")]
            Buf::Mapped(m) => m.as_mut_slice(),
        }
    }
}

impl<T> AsRef<[T]> for PageArray<T> {
    fn as_ref(&self) -> &[T] {
        self
    }
}

impl<T> AsMut<[T]> for PageArray<T> {
    fn as_mut(&mut self) -> &mut [T] {
        self
    }
}

impl<T: std::fmt::Debug> std::fmt::Debug for PageArray<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// The mapping behind a large [`PageArray`] (Linux).
#[cfg(target_os = "linux")]
mod mapping {
    use super::{ADVISE_MIN_BYTES, HUGE_PAGE};
    use std::marker::PhantomData;
    use std::mem::MaybeUninit;
    use std::ptr::NonNull;

    /// `len` elements of `T` at `data`, a [`HUGE_PAGE`] boundary inside a private anonymous
    /// mapping of `map_bytes` bytes at `base`, owned (unmapped on drop). Its elements are
    /// initialised once the value is returned by [`Mapping::assume_init`].
    pub(super) struct Mapping<T> {
        base: NonNull<libc::c_void>,
        map_bytes: usize,
        data: NonNull<T>,
        len: usize,
        _owns: PhantomData<T>,
    }

    // SAFETY: a `Mapping<T>` owns its memory alone (no other handle to it exists), as a
    // `Vec<T>` does: sending it or sharing `&` to it is as safe as for the `T`s it holds.
    unsafe impl<T: Send> Send for Mapping<T> {}
    // SAFETY: as above; `&Mapping` only gives `&[T]`.
    unsafe impl<T: Sync> Sync for Mapping<T> {}

    /// `len` elements' bytes, with `align_of::<T>() ≤ HUGE_PAGE`, when they reach
    /// [`ADVISE_MIN_BYTES`].
    fn data_bytes<T>(len: usize) -> Option<usize> {
        let bytes = len.checked_mul(size_of::<T>())?;
        (bytes >= ADVISE_MIN_BYTES && align_of::<T>() <= HUGE_PAGE).then_some(bytes)
    }

    impl<T> Mapping<T> {
        /// Room for `len` elements, not yet initialised (the OS zeroes each page on first
        /// touch), advised for huge pages over whole huge pages from the first element past
        /// the last; `None` for arrays under [`ADVISE_MIN_BYTES`] or when the OS refuses.
        pub(super) fn new(len: usize) -> Option<Self> {
            let span = data_bytes::<T>(len)?.checked_next_multiple_of(HUGE_PAGE)?;
            // One huge page more, to start on a boundary wherever the mapping lands.
            let map_bytes = span.checked_add(HUGE_PAGE)?;
            // SAFETY: a new anonymous private mapping at an address of the kernel's choice
            // (no existing memory is affected); the result is checked for MAP_FAILED.
            let p = unsafe {
                libc::mmap(
                    std::ptr::null_mut(),
                    map_bytes,
                    libc::PROT_READ | libc::PROT_WRITE,
                    libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                    -1,
                    0,
                )
            };
            if p == libc::MAP_FAILED {
                return None;
            }
            let base = NonNull::new(p)?;
            let offset = (p as usize).next_multiple_of(HUGE_PAGE) - p as usize;
            // SAFETY: `offset < HUGE_PAGE`, so `[base + offset, base + offset + span)` lies
            // inside the `span + HUGE_PAGE` bytes mapped at `base`.
            let data = unsafe { base.byte_add(offset) };
            // SAFETY: the range lies in the mapping (above) and nothing of it has been touched;
            // MADV_HUGEPAGE only chooses the page size that will back it. Best effort: a
            // refusal leaves 4 KiB pages, same contents.
            unsafe {
                libc::madvise(data.as_ptr(), span, libc::MADV_HUGEPAGE);
            }
            Some(Self {
                base,
                map_bytes,
                data: data.cast(),
                len,
                _owns: PhantomData,
            })
        }

        /// The elements as uninitialised slots, to be written before [`Self::assume_init`].
        pub(super) fn spare(&mut self) -> &mut [MaybeUninit<T>] {
            // SAFETY: `data` is aligned for `T` (a `HUGE_PAGE` boundary, `align_of::<T>() ≤
            // HUGE_PAGE`) and `len` elements fit in the mapping (`new`), which `self` owns
            // alone for the borrow's lifetime; `MaybeUninit` needs no initialisation.
            unsafe { std::slice::from_raw_parts_mut(self.data.as_ptr().cast(), self.len) }
        }

        /// The mapping as an array of initialised elements.
        ///
        /// # Safety
        ///
        /// Each of the `len` elements holds a valid `T`: written through [`Self::spare`], or
        /// untouched when all-zero bytes are a valid `T`.
        pub(super) unsafe fn assume_init(self) -> Self {
            self
        }

        pub(super) fn as_slice(&self) -> &[T] {
            // SAFETY: aligned, in the mapping, owned (see `spare`); the elements are valid `T`s
            // (`assume_init`'s contract: only such mappings are kept in a `PageArray`).
            unsafe { std::slice::from_raw_parts(self.data.as_ptr(), self.len) }
        }

        pub(super) fn as_mut_slice(&mut self) -> &mut [T] {
            // SAFETY: as in `as_slice`, borrowed mutably through `&mut self`.
            unsafe { std::slice::from_raw_parts_mut(self.data.as_ptr(), self.len) }
        }
    }

    impl<T> Drop for Mapping<T> {
        fn drop(&mut self) {
            // SAFETY: unmaps exactly the mapping `new` made, which no borrow outlives (`self`
            // is being dropped); `T: Copy` in every `PageArray`, so no element needs a drop.
            unsafe {
                libc::munmap(self.base.as_ptr(), self.map_bytes);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use halfray_core::bvh::BvhNode;

    /// Sizes below, at and above the mapped threshold, over one and several huge pages.
    const SIZES: [usize; 5] = [
        1,
        ADVISE_MIN_BYTES / 224 - 1,
        ADVISE_MIN_BYTES / 224 + 1,
        2 * HUGE_PAGE / 224 + 1,
        3 * HUGE_PAGE / 224 + 17,
    ];

    /// A large array starts on a huge page boundary (Linux), every array holds the value,
    /// and a clone is equal and independent.
    #[test]
    fn filled_arrays_hold_the_value_and_large_ones_start_on_a_huge_page() {
        for n in SIZES {
            let a = PageArray::filled([7u32; 56], n);
            assert_eq!(a.len(), n);
            assert!(a.iter().all(|x| *x == [7u32; 56]));
            if cfg!(target_os = "linux") && n * 224 >= ADVISE_MIN_BYTES {
                assert!((a.as_ptr() as usize).is_multiple_of(HUGE_PAGE), "{n}");
            }
            let mut b = a.clone();
            assert_eq!(&a[..], &b[..]);
            b[n - 1] = [1; 56];
            assert_eq!((a[n - 1][0], b[n - 1][0]), (7, 1));
        }
    }

    /// A zeroed array reads as zero bytes everywhere (checked byte by byte, not through the
    /// type's fields), takes writes anywhere, and clones.
    #[test]
    fn zeroed_arrays_read_as_zero_and_take_writes() {
        for n in SIZES.map(|n| n * 224 / size_of::<BvhNode>()) {
            let mut a = PageArray::<BvhNode>::zeroed(n);
            assert_eq!(a.len(), n);
            // SAFETY: `BvhNode` has no padding (32 bytes of `f32`/`u32` fields); the bytes of
            // an initialised slice of it may be read as `u8`.
            let bytes = unsafe {
                std::slice::from_raw_parts(a.as_ptr().cast::<u8>(), n * size_of::<BvhNode>())
            };
            assert!(bytes.iter().all(|&b| b == 0), "{n}");
            a[n / 2] = BvhNode::EMPTY;
            a[n - 1] = BvhNode::EMPTY;
            let b = a.clone();
            assert_eq!(b[n / 2], BvhNode::EMPTY);
            assert_eq!(b[0], BvhNode::from_raw([[0.0; 3]; 2], 0, 0));
        }
    }

    #[test]
    fn empty_arrays_are_empty() {
        let mut e = PageArray::filled(0u8, 0);
        assert!(e.is_empty() && e.as_mut().is_empty());
        assert!(PageArray::<BvhNode>::zeroed(0).is_empty());
    }
}
