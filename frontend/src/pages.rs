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
//! The advice is a hint: where the OS declines it, or on another OS, the array is a heap
//! block with the same contents. Every array, mapped or not, starts on a cache line
//! ([`CACHE_LINE`]), as the trees' 32-byte rows need.

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

/// Every array starts on a boundary of this many bytes, a cache line of x86-64 and of most
/// aarch64 cores. A wide node (224 bytes) is read in 32-byte rows; from a cache-line boundary
/// no row spans two lines, where from the 16 bytes the allocator promises half of them would
/// (a split load, slower on Intel cores). Bytes.
pub const CACHE_LINE: usize = 64;

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

/// `len` values in one buffer that starts on a cache line ([`CACHE_LINE`]). Arrays of at
/// least [`ADVISE_MIN_BYTES`] are (on Linux) a private anonymous mapping of their own that
/// starts on a [`HUGE_PAGE`] boundary and is advised for huge pages before anything touches
/// it; smaller ones (and all on other systems, or when the mapping is refused) are a heap
/// block. Dereferences to `[T]`.
pub struct PageArray<T> {
    block: block::Block<T>,
}

impl<T: Copy> PageArray<T> {
    /// `len` copies of `value`, each written once.
    #[must_use]
    pub fn filled(value: T, len: usize) -> Self {
        let mut b = block::Block::new(len);
        b.spare().fill(std::mem::MaybeUninit::new(value));
        // SAFETY: every element was just written.
        Self {
            block: unsafe { b.assume_init() },
        }
    }
}

impl<T: ZeroValid> PageArray<T> {
    /// `len` all-zero values. A large array is fresh memory the OS zeroes page by page when
    /// it is first touched: nothing is written here, and pages never touched cost neither a
    /// fault nor zeroing (storage sized for a worst case that the build does not reach).
    #[must_use]
    pub fn zeroed(len: usize) -> Self {
        // SAFETY: the block reads as zero bytes (`Block::zeroed`), and all-zero bytes are a
        // valid `T` (`T: ZeroValid`).
        Self {
            block: unsafe { block::Block::zeroed(len).assume_init() },
        }
    }
}

impl<T: Copy> Clone for PageArray<T> {
    fn clone(&self) -> Self {
        let mut b = block::Block::new(self.len());
        for (slot, v) in b.spare().iter_mut().zip(self.iter()) {
            slot.write(*v);
        }
        // SAFETY: the block has `self.len()` elements, each just written from `self`.
        Self {
            block: unsafe { b.assume_init() },
        }
    }
}

impl<T> Deref for PageArray<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        self.block.as_slice()
    }
}

impl<T> DerefMut for PageArray<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        self.block.as_mut_slice()
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

/// The memory behind a [`PageArray`]: a heap block aligned to a cache line, or (Linux, large
/// arrays) a mapping of its own.
mod block {
    use super::CACHE_LINE;
    #[cfg(target_os = "linux")]
    use super::{ADVISE_MIN_BYTES, HUGE_PAGE};
    use std::alloc::Layout;
    use std::marker::PhantomData;
    use std::mem::MaybeUninit;
    use std::ptr::NonNull;

    /// How a [`Block`]'s memory is given back.
    enum Release {
        /// Nothing was allocated (no bytes: an empty array or a zero-sized `T`).
        Nothing,
        /// A heap block of this layout at `base` (`data` lies inside it).
        Heap { base: NonNull<u8>, layout: Layout },
        /// A private anonymous mapping of `bytes` bytes at `base` (`data` lies inside it).
        #[cfg(target_os = "linux")]
        Mapped {
            base: NonNull<libc::c_void>,
            bytes: usize,
        },
    }

    /// `len` elements of `T` at `data`, aligned to [`CACHE_LINE`] (and to `T`), owned: given
    /// back as `release` says on drop. Its elements are initialised once the value is
    /// returned by [`Block::assume_init`].
    pub(super) struct Block<T> {
        data: NonNull<T>,
        len: usize,
        release: Release,
        _owns: PhantomData<T>,
    }

    // SAFETY: a `Block<T>` owns its memory alone (no other handle to it exists), as a `Vec<T>`
    // does: sending it or sharing `&` to it is as safe as for the `T`s it holds.
    unsafe impl<T: Send> Send for Block<T> {}
    // SAFETY: as above; `&Block` only gives `&[T]`.
    unsafe impl<T: Sync> Sync for Block<T> {}

    impl<T> Block<T> {
        /// Room for `len` elements, not yet initialised.
        pub(super) fn new(len: usize) -> Self {
            Self::allocate(len, false)
        }

        /// Room for `len` elements that reads as zero bytes: a fresh mapping (zeroed by the
        /// OS on first touch) or a zeroed heap block.
        pub(super) fn zeroed(len: usize) -> Self {
            Self::allocate(len, true)
        }

        /// The mapping when the array is large enough and the OS gives it, else a heap block
        /// (zeroed when `zero`).
        ///
        /// # Panics
        ///
        /// As `Vec` does: when `len` elements exceed `isize::MAX` bytes; the allocation
        /// error handler runs when the heap refuses.
        fn allocate(len: usize, zero: bool) -> Self {
            const { assert!(align_of::<T>() <= CACHE_LINE) };
            // The elements' bytes, at most `isize::MAX` (`Layout`'s rule, as `Vec`'s).
            let size = Layout::array::<T>(len).expect("capacity overflow").size();
            #[cfg(target_os = "linux")]
            if let Some(b) = Self::mapped(len, size) {
                return b;
            }
            if size == 0 {
                return Self {
                    data: NonNull::dangling(),
                    len,
                    release: Release::Nothing,
                    _owns: PhantomData,
                };
            }
            // A cache line more than the elements need, at byte alignment, used from its first
            // cache-line boundary: asked for an alignment above the C allocator's own
            // (16 bytes), `alloc_zeroed` would write every byte itself, where this way it gets
            // `calloc`'s zeroed memory, fresh pages untouched (as the mapping's).
            let heap = size
                .checked_add(CACHE_LINE)
                .and_then(|bytes| Layout::from_size_align(bytes, 1).ok())
                .expect("capacity overflow");
            // SAFETY: `heap` has a non-zero size (`size`, checked above, plus a line).
            let p = unsafe {
                if zero {
                    std::alloc::alloc_zeroed(heap)
                } else {
                    std::alloc::alloc(heap)
                }
            };
            let Some(base) = NonNull::new(p) else {
                std::alloc::handle_alloc_error(heap)
            };
            let offset = (p as usize).next_multiple_of(CACHE_LINE) - p as usize;
            // SAFETY: `offset < CACHE_LINE`, so `[base + offset, base + offset + size)` lies
            // inside the `size + CACHE_LINE` bytes allocated at `base`.
            let data = unsafe { base.byte_add(offset) };
            Self {
                data: data.cast(),
                len,
                release: Release::Heap { base, layout: heap },
                _owns: PhantomData,
            }
        }

        /// A mapping for `len` elements of `size` bytes in all, advised for huge pages over
        /// whole huge pages from the first element past the last; `None` for arrays under
        /// [`ADVISE_MIN_BYTES`] or when the OS refuses.
        #[cfg(target_os = "linux")]
        fn mapped(len: usize, size: usize) -> Option<Self> {
            if size < ADVISE_MIN_BYTES {
                return None;
            }
            let span = size.checked_next_multiple_of(HUGE_PAGE)?;
            // One huge page more, to start on a boundary wherever the mapping lands.
            let bytes = span.checked_add(HUGE_PAGE)?;
            // SAFETY: a new anonymous private mapping at an address of the kernel's choice
            // (no existing memory is affected); the result is checked for MAP_FAILED.
            let p = unsafe {
                libc::mmap(
                    std::ptr::null_mut(),
                    bytes,
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
                data: data.cast(),
                len,
                release: Release::Mapped { base, bytes },
                _owns: PhantomData,
            })
        }

        /// The elements as uninitialised slots, to be written before [`Self::assume_init`].
        pub(super) fn spare(&mut self) -> &mut [MaybeUninit<T>] {
            // SAFETY: `data` is aligned for `T` (a cache-line or huge page boundary, and
            // `align_of::<T>() ≤ CACHE_LINE`; `dangling` for no bytes) and `len` elements fit
            // in the block (`allocate`), which `self` owns alone for the borrow's lifetime;
            // `MaybeUninit` needs no initialisation.
            unsafe { std::slice::from_raw_parts_mut(self.data.as_ptr().cast(), self.len) }
        }

        /// The block as an array of initialised elements.
        ///
        /// # Safety
        ///
        /// Each of the `len` elements holds a valid `T`: written through [`Self::spare`], or
        /// untouched in a [`Self::zeroed`] block when all-zero bytes are a valid `T`.
        pub(super) unsafe fn assume_init(self) -> Self {
            self
        }

        pub(super) fn as_slice(&self) -> &[T] {
            // SAFETY: aligned, in the block, owned (see `spare`); the elements are valid `T`s
            // (`assume_init`'s contract: only such blocks are kept in a `PageArray`).
            unsafe { std::slice::from_raw_parts(self.data.as_ptr(), self.len) }
        }

        pub(super) fn as_mut_slice(&mut self) -> &mut [T] {
            // SAFETY: as in `as_slice`, borrowed mutably through `&mut self`.
            unsafe { std::slice::from_raw_parts_mut(self.data.as_ptr(), self.len) }
        }
    }

    impl<T> Drop for Block<T> {
        fn drop(&mut self) {
            match self.release {
                Release::Nothing => {}
                // SAFETY: frees exactly the block `allocate` took at `base` with this layout,
                // which no borrow outlives (`self` is being dropped); `T: Copy` in every
                // `PageArray`, so no element needs a drop.
                Release::Heap { base, layout } => unsafe {
                    std::alloc::dealloc(base.as_ptr(), layout);
                },
                // SAFETY: unmaps exactly the mapping `mapped` made, which no borrow outlives;
                // no element needs a drop (as above).
                #[cfg(target_os = "linux")]
                Release::Mapped { base, bytes } => unsafe {
                    libc::munmap(base.as_ptr(), bytes);
                },
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

    /// A large array starts on a huge page boundary (Linux), every array on a cache line,
    /// every array holds the value, and a clone is equal and independent.
    #[test]
    fn filled_arrays_hold_the_value_and_large_ones_start_on_a_huge_page() {
        for n in SIZES {
            let a = PageArray::filled([7u32; 56], n);
            assert_eq!(a.len(), n);
            assert!((a.as_ptr() as usize).is_multiple_of(CACHE_LINE), "{n}");
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
            for p in [a.as_ptr(), b.as_ptr()] {
                assert!((p as usize).is_multiple_of(CACHE_LINE), "{n}");
            }
            assert_eq!(b[n / 2], BvhNode::EMPTY);
            assert_eq!(b[0], BvhNode::from_raw([[0.0; 3]; 2], 0, 0));
        }
    }

    /// The trees' own element types, in the sizes a small mesh's tree has (heap blocks), start
    /// on a cache line however the allocator's other blocks fall: `Vec`'s 16-byte alignment
    /// put them 16 or 48 bytes past one.
    #[test]
    fn small_tree_arrays_start_on_a_cache_line() {
        use halfray_core::bvh::wide::{LeafGroup, WideNode};
        let mut keep = Vec::new();
        for n in 1..200 {
            // Heap blocks of other sizes in between, so that the arrays land at many offsets.
            keep.push(vec![0u8; n * 24 + 8]);
            let nodes = PageArray::<WideNode<8>>::zeroed(n);
            let groups = PageArray::<LeafGroup>::zeroed(2 * n + 1);
            let copy = nodes.clone();
            for p in [
                nodes.as_ptr() as usize,
                groups.as_ptr() as usize,
                copy.as_ptr() as usize,
            ] {
                assert!(p.is_multiple_of(CACHE_LINE), "{n}: {p:#x}");
            }
        }
    }

    #[test]
    fn empty_arrays_are_empty() {
        let mut e = PageArray::filled(0u8, 0);
        assert!(e.is_empty() && e.as_mut().is_empty());
        assert!(PageArray::<BvhNode>::zeroed(0).is_empty());
    }
}
