//! halfray-ffi: a C ABI over halfray-core's query path for BVHs baked on a host
//! (`halfray bake --format bin`): check a baked buffer and load it in place, then closest and
//! any hit of one ray with the watertight test without `f64` (`WatertightF32Exact`), on a
//! traversal stack the caller provides. The header, `include/halfray.h`, is generated from
//! this file by cbindgen; each item's doc comment below is its contract there.
//!
//! Nothing allocates and nothing is copied: the handle refers to the caller's buffer. No
//! panic path is linked: the panic handler calls a symbol nothing defines, so a C program
//! whose reachable code could panic fails to link (`scripts/test-ffi.sh` links one for each
//! target with `--gc-sections`).
#![no_std]
#![deny(missing_docs)]

#[cfg(not(target_endian = "little"))]
compile_error!("the baked format is little-endian and read in place: little-endian targets only");

use core::mem::{align_of, size_of};
use halfray_core::bvh::{
    load_scratch_len, BakedError, BakedLayout, Bvh, BvhNode, LoadError, BAKED_ALIGN,
    TRAVERSAL_STACK_SIZE,
};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, StackEntry, Triangles};
use halfray_core::ray::Ray;
use halfray_core::triangle::{TriangleHit, WatertightF32Exact};
use halfray_core::Vec3;

/// What a call did. `HALFRAY_STATUS_OK` is 0; every other value is an error, after which
/// the call's outputs are as its documentation says (untouched unless stated). The
/// functions' documentation names the codes without their `HALFRAY_STATUS_` prefix.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HalfrayStatus {
    /// Success.
    Ok = 0,
    /// A pointer the call needs is NULL (a buffer of count 0 may be NULL).
    Null = 1,
    /// A pointer is not aligned as its type (or, for a baked buffer, `HALFRAY_BAKED_ALIGN`)
    /// requires.
    Misaligned = 2,
    /// The baked buffer is shorter than its header, or than the arrays its header announces.
    ShortBuffer = 3,
    /// The buffer does not start with the baked format's magic bytes (or, in a header of this
    /// library's version, its reserved bytes are not zero): not a baked BVH.
    NotBaked = 4,
    /// A baked format version this library does not read.
    Version = 5,
    /// The load scratch holds fewer words than `HalfrayBakedInfo::scratch_words`.
    ScratchTooSmall = 6,
    /// Baked data refused: the index count is not the triangle count. (The baked layout
    /// stores as many indices as triangles, so through this API only a tree of more than
    /// 2^31 - 1 triangles, the core's `MAX_PRIMITIVES`, gets it.)
    IndexCount = 7,
    /// Baked data refused: more nodes than a tree over the mesh can have, or none for a
    /// non-empty mesh.
    NodeCount = 8,
    /// Baked data refused: an inner node's children are not after it or lie past the nodes.
    ChildOutOfRange = 9,
    /// Baked data refused: an inner node deeper than `HALFRAY_MAX_STACK_ENTRIES`.
    TooDeep = 10,
    /// Baked data refused: a node is reached by two paths.
    SharedNode = 11,
    /// Baked data refused: a box is not finite, inverted, or does not contain its children
    /// or its triangles.
    BadBox = 12,
    /// Baked data refused: a leaf's index range is empty, out of order or past the indices.
    LeafRange = 13,
    /// Baked data refused: an index names no triangle, or one already listed.
    BadIndex = 14,
    /// Baked data refused: a triangle's vertex index is out of range or its vertex not finite.
    BadTriangle = 15,
    /// Baked data refused: the leaves do not cover every index.
    Uncovered = 16,
    /// Baked data refused for a reason this header's codes do not name.
    BadBvh = 17,
    /// The handle was not filled by a successful `halfray_load` (zeroed, or its load failed).
    NotLoaded = 18,
    /// The ray is invalid: a non-finite origin or direction, a zero direction, a NaN bound,
    /// `t_min` = +infinity, or `t_min` > `t_max`.
    InvalidRay = 19,
    /// The ray's path needed more traversal stack entries than given (never with
    /// `halfray_stack_entries` of them); no answer is written.
    StackTooSmall = 20,
    /// Two areas of one call overlap: a load's handle or scratch lies in its baked buffer, or
    /// a query's traversal stack overlaps the handle or its buffer. Nothing is written.
    Overlap = 21,
}

/// Alignment, in bytes, of a baked buffer's start (its nodes are read in place).
pub const HALFRAY_BAKED_ALIGN: usize = 32;
/// Traversal stack entries that suffice for every tree `halfray_load` accepts.
pub const HALFRAY_MAX_STACK_ENTRIES: usize = 64;
/// Pointer-sized words of a `HalfrayBvh`.
pub const HALFRAY_BVH_WORDS: usize = 16;
/// `HalfrayHit::primitive` of a ray that hits nothing.
pub const HALFRAY_NO_HIT: u32 = u32::MAX;

const _: () = assert!(HALFRAY_BAKED_ALIGN == BAKED_ALIGN);
const _: () = assert!(HALFRAY_MAX_STACK_ENTRIES == TRAVERSAL_STACK_SIZE);

/// A loaded baked BVH: opaque, filled by `halfray_load`, read by the queries. It refers to
/// the baked buffer, which must stay in place and unchanged while the handle is used. Any
/// storage of this type will do (static, stack), zero-initialised (`= {0}`: "not loaded") or
/// filled by `halfray_load` before any other call reads it: a handle of other contents is
/// refused as `NOT_LOADED` only with high probability (its tag is a check of its buffer's
/// address), not with certainty.
#[repr(C)]
pub struct HalfrayBvh {
    opaque: [usize; HALFRAY_BVH_WORDS],
}

/// One traversal stack entry (opaque): the caller provides `halfray_stack_entries` of them
/// (or `HALFRAY_MAX_STACK_ENTRIES`, enough for any tree) to each query. Contents need no
/// initialisation and mean nothing between queries.
#[repr(C)]
pub struct HalfrayStackEntry {
    opaque: [u32; 2],
}

/// What a baked buffer's header announces, and the sizes it needs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HalfrayBakedInfo {
    /// Vertex positions.
    pub vertices: u32,
    /// Triangles.
    pub triangles: u32,
    /// BVH nodes.
    pub nodes: u32,
    /// `uint32_t` words of load scratch `halfray_load` needs: one bit per triangle.
    pub scratch_words: u32,
    /// Bytes of the buffer the header and its arrays occupy.
    pub byte_len: u64,
}

/// A ray over the interval (`t_min`, `t_max`], in units of the direction's length.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfrayRay {
    /// Origin, world units.
    pub origin: [f32; 3],
    /// Direction, not necessarily normalised; finite and non-zero.
    pub direction: [f32; 3],
    /// Exclusive lower end (0 for a ray that starts at its origin); not NaN or +infinity,
    /// at most `t_max`.
    pub t_min: f32,
    /// Inclusive upper end (+infinity for an unbounded ray); not NaN.
    pub t_max: f32,
}

/// The closest hit of a ray.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfrayHit {
    /// The triangle's index in the baked mesh, or `HALFRAY_NO_HIT` (then the other fields
    /// are 0).
    pub primitive: u32,
    /// Ray parameter of the hit, in (`t_min`, `t_max`].
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub b2: f32,
    /// Unnormalised geometric normal (v1 - v0) x (v2 - v0) (Embree's Ng), finite and non-zero:
    /// where that product overflows or underflows `f32`, the same direction rescaled (the
    /// core's `TriangleHit::ng`).
    pub ng: [f32; 3],
    /// `true` when the ray arrives against `ng` (the counter-clockwise side).
    pub front_face: bool,
}

/// What a `HalfrayBvh` holds: a tag set only by a successful load ([`tag_of`] the buffer's
/// address, the next word; its length follows), then the tree and mesh over the caller's buffer
/// (`'static`: the caller keeps the buffer, as documented). The first words are plain
/// integers, so that a handle is checked before anything in it is read as a reference.
#[repr(C)]
struct Loaded {
    tag: usize,
    buffer: usize,
    buffer_len: usize,
    bvh: Bvh<&'static [BvhNode], &'static [u32]>,
    mesh: TriangleMesh<'static>,
}

/// The base of a loaded handle's tag ("HRAY" in ASCII).
const LOADED: usize = 0x4852_4159;

/// The tag of a handle loaded over the buffer at address `buffer`: odd (`LOADED` is odd and
/// a buffer's address a multiple of `HALFRAY_BAKED_ALIGN`), so never 0: a zeroed handle is
/// "not loaded", and a tag of 0 matches only the buffer word `LOADED`, which no load writes
/// (a failed load clears both words: its scratch may have spelled it); for other contents a
/// match only by chance: made-up contents would have to hold a buffer's address in the next
/// word and this function of it in the first.
fn tag_of(buffer: usize) -> usize {
    LOADED ^ buffer
}

const _: () = assert!(!LOADED.is_multiple_of(2) && HALFRAY_BAKED_ALIGN.is_multiple_of(2));

/// `true` when the `a_len` bytes at address `a` and the `b_len` bytes at `b` share no byte
/// (an empty area shares none); ends past the address space count as its end. Out of line:
/// one copy for every check (the microcontroller image's size).
#[inline(never)]
fn disjoint(a: usize, a_len: usize, b: usize, b_len: usize) -> bool {
    a_len == 0 || b_len == 0 || a.saturating_add(a_len) <= b || b.saturating_add(b_len) <= a
}

const _: () = assert!(size_of::<Loaded>() <= size_of::<HalfrayBvh>());
const _: () = assert!(align_of::<Loaded>() <= align_of::<HalfrayBvh>());
const _: () = assert!(size_of::<HalfrayStackEntry>() == size_of::<StackEntry>());
const _: () = assert!(align_of::<HalfrayStackEntry>() == align_of::<StackEntry>());
// The baked arrays, read in place, have the layouts of these types (`BakedLayout`'s table):
// 12-byte positions of three `f32`, 12-byte triangles, 32-byte nodes.
const _: () = assert!(size_of::<Vec3>() == 12 && align_of::<Vec3>() == 4);
const _: () = assert!(size_of::<BvhNode>() == 32 && align_of::<BvhNode>() == 32);

/// `true` when `p` is a multiple of `align`.
fn aligned<T>(p: *const T, align: usize) -> bool {
    (p as usize).is_multiple_of(align)
}

/// The slice of `count` `T`s at `p`, written with `fill` first (the caller's memory may hold
/// anything): empty for `count` 0 whatever `p` is; `Null` or `Misaligned` for such a `p`.
///
/// # Safety
///
/// Unless `count` is 0 or `p` is NULL, `p` points to `count` writable `T`s that nothing else
/// accesses during `'a`.
unsafe fn filled<'a, T: Copy>(
    p: *mut T,
    count: usize,
    fill: T,
) -> Result<&'a mut [T], HalfrayStatus> {
    if count == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(HalfrayStatus::Null);
    }
    if !aligned(p, align_of::<T>()) {
        return Err(HalfrayStatus::Misaligned);
    }
    for k in 0..count {
        // SAFETY: `p` is non-NULL and aligned, and `p + k` for `k < count` lies in the
        // caller's `count` elements (the function's contract).
        unsafe { p.add(k).write(fill) };
    }
    // SAFETY: the same `count` elements, now initialised, borrowed exclusively (contract).
    Ok(unsafe { core::slice::from_raw_parts_mut(p, count) })
}

/// The `len` bytes at `bytes` and their header, checked.
///
/// # Safety
///
/// Unless NULL, `bytes` points to `len` readable bytes that stay unchanged during `'a`.
unsafe fn baked<'a>(
    bytes: *const u8,
    len: usize,
) -> Result<(&'a [u8], BakedLayout), HalfrayStatus> {
    if bytes.is_null() {
        return Err(HalfrayStatus::Null);
    }
    if !aligned(bytes, HALFRAY_BAKED_ALIGN) {
        return Err(HalfrayStatus::Misaligned);
    }
    // SAFETY: non-NULL and `len` readable, unchanging bytes (contract).
    let b = unsafe { core::slice::from_raw_parts(bytes, len) };
    match BakedLayout::read(b) {
        Ok(layout) => Ok((b, layout)),
        Err(BakedError::Short { .. }) => Err(HalfrayStatus::ShortBuffer),
        Err(BakedError::Version { .. }) => Err(HalfrayStatus::Version),
        Err(_) => Err(HalfrayStatus::NotBaked),
    }
}

/// The `T`s in `range` of `bytes`, in place.
///
/// # Safety
///
/// `range` lies within `bytes` (a range of a layout `BakedLayout::read` accepted for it),
/// its start is aligned for `T` and its length a multiple of `size_of::<T>()`, and every bit
/// pattern of that size is a valid `T`.
unsafe fn array<T>(bytes: &[u8], range: core::ops::Range<usize>) -> &[T] {
    // SAFETY: within `bytes`, aligned, whole elements of a type with no invalid bit patterns
    // (contract); shared, like `bytes`, for as long as `bytes` is.
    unsafe {
        core::slice::from_raw_parts(
            bytes.as_ptr().add(range.start).cast::<T>(),
            (range.end - range.start) / size_of::<T>(),
        )
    }
}

impl From<LoadError> for HalfrayStatus {
    fn from(e: LoadError) -> Self {
        match e {
            LoadError::IndexCount { .. } => Self::IndexCount,
            LoadError::NodeCount { .. } => Self::NodeCount,
            LoadError::Capacity(_) => Self::ScratchTooSmall,
            LoadError::ChildOutOfRange { .. } => Self::ChildOutOfRange,
            LoadError::TooDeep { .. } => Self::TooDeep,
            LoadError::SharedNode { .. } => Self::SharedNode,
            LoadError::BadBox { .. } => Self::BadBox,
            LoadError::LeafRange { .. } => Self::LeafRange,
            LoadError::BadIndex { .. } => Self::BadIndex,
            LoadError::BadTriangle { .. } => Self::BadTriangle,
            LoadError::Uncovered { .. } => Self::Uncovered,
            _ => Self::BadBvh,
        }
    }
}

/// Reads the header of the baked buffer `bytes` (`len` bytes) into `*info`: the counts, the
/// load scratch and the buffer length `halfray_load` needs. The arrays are not checked (that
/// is `halfray_load`'s work).
///
/// Returns `HALFRAY_STATUS_OK`; `NULL` when `bytes` or `info` is NULL; `MISALIGNED` when
/// `bytes` is not `HALFRAY_BAKED_ALIGN`-aligned or `info` not aligned as its type; `SHORT_BUFFER` when `len` is shorter than the
/// header or than the arrays it announces; `NOT_BAKED` or `VERSION` for a foreign header.
/// `*info` is written only on success.
///
/// # Safety
///
/// `bytes`, unless NULL, points to `len` readable bytes; `info`, unless NULL, to a writable
/// `HalfrayBakedInfo`.
#[no_mangle]
pub unsafe extern "C" fn halfray_baked_info(
    bytes: *const u8,
    len: usize,
    info: *mut HalfrayBakedInfo,
) -> HalfrayStatus {
    if info.is_null() {
        return HalfrayStatus::Null;
    }
    // SAFETY: `len` readable bytes at `bytes` (contract).
    let (_, l) = match unsafe { baked(bytes, len) } {
        Ok(v) => v,
        Err(e) => return e,
    };
    if !aligned(info, align_of::<HalfrayBakedInfo>()) {
        return HalfrayStatus::Misaligned;
    }
    // SAFETY: non-NULL, aligned, writable (contract).
    unsafe {
        info.write(HalfrayBakedInfo {
            vertices: l.vertices(),
            triangles: l.triangles(),
            nodes: l.nodes(),
            scratch_words: load_scratch_len(l.triangles() as usize) as u32,
            byte_len: l.byte_len(),
        });
    }
    HalfrayStatus::Ok
}

/// Checks the baked buffer `bytes` (`len` bytes, `HALFRAY_BAKED_ALIGN`-aligned; in flash or
/// RAM) as untrusted input and, when it holds a valid mesh and BVH, fills `*bvh` to refer to
/// it in place: nothing is copied, so the buffer must stay in place and unchanged while
/// `*bvh` is used. `scratch` is `scratch_words` words of working memory (contents ignored,
/// overwritten; free again on return), at least `HalfrayBakedInfo::scratch_words` of them.
///
/// The checks (linear time, fixed stack) cover the header and what a query can read: the
/// header as `halfray_baked_info`; walking the nodes from the root, children after their
/// parent and inside the node array, depth at most `HALFRAY_MAX_STACK_ENTRIES`, no node
/// reached twice, finite boxes (min <= max) that contain their children's boxes and their
/// triangles' vertices; leaves whose index ranges cover the index list once, in depth-first
/// order; each index a distinct triangle, so every triangle is listed; each triangle's
/// vertex indices in range and its three vertices finite. Not checked, since no query reads
/// them: nodes the walk does not reach (the baker's padding), vertices no triangle uses (a
/// NaN there loads), and bytes past `HalfrayBakedInfo::byte_len`. A tree that passes answers
/// every query as a freshly built one would.
///
/// Returns `HALFRAY_STATUS_OK`; `NULL` when `bvh` or `bytes` is NULL, or `scratch` is NULL
/// with a non-zero `scratch_words`; `MISALIGNED` for a misaligned `bytes`, `scratch` or `bvh`;
/// `OVERLAP` when the handle or the scratch lies in the buffer (checked first: a NULL pointer
/// with a length that reaches the other area is reported as `OVERLAP`, not `NULL`);
/// `SHORT_BUFFER`, `NOT_BAKED`, `VERSION` as `halfray_baked_info`; `SCRATCH_TOO_SMALL`; or the
/// code of the first check that fails (`INDEX_COUNT` to `BAD_BVH`). A NULL or misaligned `bvh`
/// and `OVERLAP` leave `*bvh` as it was (a handle in the buffer is never written; zero it to
/// unload an earlier tree); on every other error, a NULL or misaligned `bytes` or `scratch`
/// included, `*bvh` is left "not loaded": queries on it return `NOT_LOADED`.
///
/// # Safety
///
/// `bytes`, unless NULL, points to `len` readable bytes that stay unchanged while `*bvh` is
/// used; `scratch`, unless NULL, to `scratch_words` writable words; `bvh`, unless NULL, to
/// a writable `HalfrayBvh` not used by another call meanwhile. The handle and the scratch
/// must lie outside the buffer (checked: `OVERLAP`); they may share memory with each other
/// (the scratch is dead before the handle is filled).
#[no_mangle]
pub unsafe extern "C" fn halfray_load(
    bytes: *const u8,
    len: usize,
    scratch: *mut u32,
    scratch_words: usize,
    bvh: *mut HalfrayBvh,
) -> HalfrayStatus {
    if bvh.is_null() {
        return HalfrayStatus::Null;
    }
    if !aligned(bvh, align_of::<HalfrayBvh>()) {
        return HalfrayStatus::Misaligned;
    }
    if load_areas_overlap(bytes, len, scratch, scratch_words, bvh) {
        return HalfrayStatus::Overlap;
    }
    // SAFETY: non-NULL, aligned, writable (contract), and outside the buffer (checked): with
    // its tag 0 the handle is "not loaded" from here until a load succeeds (its buffer word is
    // 0 or an earlier buffer's aligned address, whose tag is not 0). It may share the
    // scratch's memory: the failing arm below clears both words once the check is over.
    unsafe { bvh.cast::<usize>().write(0) };
    // SAFETY: `len` readable bytes at `bytes`, unchanged while the handle is used (contract).
    let (b, l) = match unsafe { baked(bytes, len) } {
        Ok(v) => v,
        Err(e) => return e,
    };
    // SAFETY: `scratch_words` writable words at `scratch` (contract).
    let scratch = match unsafe { filled(scratch, scratch_words, 0u32) } {
        Ok(s) => s,
        Err(e) => return e,
    };
    // SAFETY: ranges of the layout `read` accepted for `b`; `b` starts 32-byte aligned, the
    // nodes at byte 32 and the other arrays at multiples of 4 (the table); every bit pattern
    // is a valid `f32` or `u32`, and `BvhNode` is `repr(C)` `[[f32; 3]; 2], u32, u32` and
    // `Vec3` `repr(C)` three `f32` (sizes asserted above). The arrays are checked below
    // before any query reads them as a tree.
    let (nodes, positions, triangles, indices) = unsafe {
        (
            array::<BvhNode>(b, l.node_bytes()),
            array::<Vec3>(b, l.position_bytes()),
            array::<[u32; 3]>(b, l.triangle_bytes()),
            array::<u32>(b, l.index_bytes()),
        )
    };
    let mesh = TriangleMesh::new(positions, triangles);
    match Bvh::from_parts(nodes, indices, &mesh, scratch) {
        Ok(tree) => {
            // SAFETY: `bvh` is aligned and large enough for a `Loaded` (asserted above) and
            // writable (contract).
            unsafe {
                bvh.cast::<Loaded>().write(Loaded {
                    tag: tag_of(bytes as usize),
                    buffer: bytes as usize,
                    buffer_len: len,
                    bvh: tree,
                    mesh,
                });
            }
            HalfrayStatus::Ok
        }
        Err(e) => {
            // SAFETY: as the write above, two words (`HALFRAY_BVH_WORDS` ≥ 2); the check is
            // over, so the scratch is dead. It wrote one bit per listed triangle into the
            // scratch, which may share the handle's memory: the buffer chose those bits, so
            // they could spell a tag and a buffer word that match (tag 0 and buffer word
            // `LOADED` among them); zeroed, the handle is "not loaded" whatever the scratch
            // holds. (Every earlier return wrote at most zeros to the scratch.)
            unsafe { bvh.cast::<[usize; 2]>().write([0; 2]) };
            e.into()
        }
    }
}

/// `true` when `halfray_load`'s buffer overlaps its handle or its scratch: the buffer is read
/// while those are written. (The scratch is dead before the handle is filled, so those two
/// may share memory.) Out of line, so that the load's own code stays small enough for its
/// checks to be inlined (the microcontroller image's size).
#[inline(never)]
fn load_areas_overlap(
    bytes: *const u8,
    len: usize,
    scratch: *mut u32,
    scratch_words: usize,
    bvh: *mut HalfrayBvh,
) -> bool {
    !(disjoint(bytes as usize, len, bvh as usize, size_of::<HalfrayBvh>())
        && disjoint(
            bytes as usize,
            len,
            scratch as usize,
            scratch_words.saturating_mul(size_of::<u32>()),
        ))
}

/// The tree in `*bvh`, when a load filled it.
///
/// # Safety
///
/// `bvh`, unless NULL, points to a `HalfrayBvh` (its first word readable).
unsafe fn loaded<'a>(bvh: *const HalfrayBvh) -> Result<&'a Loaded, HalfrayStatus> {
    if bvh.is_null() {
        return Err(HalfrayStatus::Null);
    }
    if !aligned(bvh, align_of::<HalfrayBvh>()) {
        return Err(HalfrayStatus::Misaligned);
    }
    // SAFETY: an aligned, readable handle whose first two words are readable integers
    // (contract: a zero-initialised or loaded `HalfrayBvh`).
    let [tag, buffer] = unsafe { bvh.cast::<[usize; 2]>().read() };
    if tag != tag_of(buffer) {
        return Err(HalfrayStatus::NotLoaded);
    }
    // SAFETY: a matching tag is written only with a whole `Loaded` by a successful
    // `halfray_load`; the tag is zeroed at the start of every load that gets past its pointer
    // checks, and both words once its check has failed (its scratch, which may share the
    // handle, can spell any bits); a zeroed handle never matches (`tag_of(0)` is `LOADED`).
    // Contents a caller made up could match only by chance, which the contract excludes.
    Ok(unsafe { &*bvh.cast::<Loaded>() })
}

/// Writes to `*entries` how many traversal stack entries queries on `*bvh` can need: the
/// inner nodes on its longest root-to-leaf path (at most `HALFRAY_MAX_STACK_ENTRIES`). A
/// query given that many never returns `STACK_TOO_SMALL`. Walks the tree once (integers only).
///
/// Returns `HALFRAY_STATUS_OK`; `NULL` when `bvh` or `entries` is NULL; `MISALIGNED`;
/// `NOT_LOADED` when `*bvh` was not filled by a successful `halfray_load`.
///
/// # Safety
///
/// `bvh`, unless NULL, points to a `HalfrayBvh` whose buffer is still in place; `entries`,
/// unless NULL, to a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn halfray_stack_entries(
    bvh: *const HalfrayBvh,
    entries: *mut usize,
) -> HalfrayStatus {
    if entries.is_null() {
        return HalfrayStatus::Null;
    }
    // SAFETY: a readable handle (contract).
    let l = match unsafe { loaded(bvh) } {
        Ok(l) => l,
        Err(e) => return e,
    };
    if !aligned(entries, align_of::<usize>()) {
        return HalfrayStatus::Misaligned;
    }
    // SAFETY: non-NULL, aligned, writable (contract).
    unsafe { entries.write(l.bvh.stack_depth()) };
    HalfrayStatus::Ok
}

/// The checked inputs of a query: the loaded tree, the ray and the traversal stack, which
/// must overlap neither the handle nor its buffer (the query writes the stack while it reads
/// them). The answer is written after the last read of all three.
///
/// # Safety
///
/// As [`halfray_closest_hit`]'s `bvh`, `ray`, `stack` and `stack_entries`.
unsafe fn query_inputs<'a>(
    bvh: *const HalfrayBvh,
    ray: *const HalfrayRay,
    stack: *mut HalfrayStackEntry,
    stack_entries: usize,
) -> Result<(&'a Loaded, Ray, &'a mut [StackEntry]), HalfrayStatus> {
    // SAFETY: a readable handle (contract).
    let l = unsafe { loaded(bvh) }?;
    let (s, n) = (
        stack as usize,
        stack_entries.saturating_mul(size_of::<HalfrayStackEntry>()),
    );
    if !(disjoint(bvh as usize, size_of::<HalfrayBvh>(), s, n)
        && disjoint(l.buffer, l.buffer_len, s, n))
    {
        return Err(HalfrayStatus::Overlap);
    }
    if ray.is_null() {
        return Err(HalfrayStatus::Null);
    }
    if !aligned(ray, align_of::<HalfrayRay>()) {
        return Err(HalfrayStatus::Misaligned);
    }
    // SAFETY: non-NULL, aligned, readable (contract); any bits are valid `f32`s.
    let r = unsafe { ray.read() };
    let ray = Ray {
        origin: Vec3::from_array(r.origin),
        direction: Vec3::from_array(r.direction),
        t_min: r.t_min,
        t_max: r.t_max,
    };
    if !ray.is_valid() {
        return Err(HalfrayStatus::InvalidRay);
    }
    // SAFETY: `stack_entries` writable entries of `StackEntry`'s size and alignment
    // (asserted above) at `stack`, used by nothing else during the query (contract), and
    // outside the handle and the buffer (checked above).
    let stack = unsafe { filled(stack.cast::<StackEntry>(), stack_entries, StackEntry::EMPTY) }?;
    Ok((l, ray, stack))
}

/// The closest hit of `*ray` in `*bvh`, with the watertight test (no ray through a shared
/// edge or vertex passes between triangles; of equal `t`, the smaller triangle index), on
/// the caller's traversal stack `stack` of `stack_entries` entries (contents ignored). The
/// answer is bit for bit the one halfray-core gives on any target.
///
/// Returns `HALFRAY_STATUS_OK` with `*hit` the hit, or `primitive` = `HALFRAY_NO_HIT` for a
/// miss; `NULL` when `bvh`, `ray` or `hit` is NULL, or `stack` is NULL with a non-zero
/// `stack_entries`; `MISALIGNED`; `NOT_LOADED`; `OVERLAP` when the stack overlaps the handle
/// or its baked buffer (checked first: a NULL `stack` whose `stack_entries` reach the handle's
/// or the buffer's address is reported as `OVERLAP`, not `NULL`); `INVALID_RAY` (NaN or infinite origin or
/// direction, zero direction, NaN bounds, `t_min` = +infinity, `t_min` > `t_max`);
/// `STACK_TOO_SMALL` when this ray needed more entries. `*hit` is written only on success.
///
/// # Safety
///
/// `bvh`, unless NULL, points to a `HalfrayBvh` whose buffer is still in place; `ray`, unless
/// NULL, to a readable `HalfrayRay`; `stack`, unless NULL, to `stack_entries` writable
/// entries; `hit`, unless NULL, to a writable `HalfrayHit`; the stack and `*hit` used by no
/// other call meanwhile, the handle written by none (queries only read it: several may run
/// on one handle at once, each with its own stack). The stack must not overlap the handle or its buffer (checked: `OVERLAP`); `*hit`
/// is written last, and should not overlap them either (the answer would replace them).
#[no_mangle]
pub unsafe extern "C" fn halfray_closest_hit(
    bvh: *const HalfrayBvh,
    ray: *const HalfrayRay,
    stack: *mut HalfrayStackEntry,
    stack_entries: usize,
    hit: *mut HalfrayHit,
) -> HalfrayStatus {
    if hit.is_null() {
        return HalfrayStatus::Null;
    }
    if !aligned(hit, align_of::<HalfrayHit>()) {
        return HalfrayStatus::Misaligned;
    }
    // SAFETY: the contract of this function.
    let (l, ray, stack) = match unsafe { query_inputs(bvh, ray, stack, stack_entries) } {
        Ok(v) => v,
        Err(e) => return e,
    };
    let answer = match l.bvh.closest_hit(
        &ray,
        &mut Triangles::new(&l.mesh, &WatertightF32Exact),
        &mut Query::new().stack(stack),
    ) {
        Ok(a) => a,
        // The one error of a query on the caller's stack.
        Err(_) => return HalfrayStatus::StackTooSmall,
    };
    let out = match answer {
        Some((primitive, h)) => hit_record(primitive, &h),
        None => HalfrayHit {
            primitive: HALFRAY_NO_HIT,
            t: 0.0,
            b1: 0.0,
            b2: 0.0,
            ng: [0.0; 3],
            front_face: false,
        },
    };
    // SAFETY: non-NULL, aligned, writable (contract).
    unsafe { hit.write(out) };
    HalfrayStatus::Ok
}

/// The C record of a hit.
fn hit_record(primitive: u32, h: &TriangleHit) -> HalfrayHit {
    HalfrayHit {
        primitive,
        t: h.t,
        b1: h.b1,
        b2: h.b2,
        ng: h.ng.to_array(),
        front_face: h.front_face,
    }
}

/// Whether `*ray` hits anything in `*bvh` (shadow and occlusion rays): traversal stops at the
/// first triangle hit in (`t_min`, `t_max`]. Hit or miss always agrees with
/// `halfray_closest_hit`; inputs and stack as there.
///
/// Returns `HALFRAY_STATUS_OK` with `*occluded` set; `NULL` when `bvh`, `ray` or `occluded`
/// is NULL, or `stack` is NULL with a non-zero `stack_entries`; `MISALIGNED`; `NOT_LOADED`;
/// `OVERLAP` (as `halfray_closest_hit`); `INVALID_RAY`; `STACK_TOO_SMALL`.
/// `*occluded` is written only on success.
///
/// # Safety
///
/// As `halfray_closest_hit`, with `occluded`, unless NULL, pointing to a writable `bool`.
#[no_mangle]
pub unsafe extern "C" fn halfray_any_hit(
    bvh: *const HalfrayBvh,
    ray: *const HalfrayRay,
    stack: *mut HalfrayStackEntry,
    stack_entries: usize,
    occluded: *mut bool,
) -> HalfrayStatus {
    if occluded.is_null() {
        return HalfrayStatus::Null;
    }
    // SAFETY: the contract of this function.
    let (l, ray, stack) = match unsafe { query_inputs(bvh, ray, stack, stack_entries) } {
        Ok(v) => v,
        Err(e) => return e,
    };
    match l.bvh.any_hit(
        &ray,
        &mut Triangles::new(&l.mesh, &WatertightF32Exact),
        &mut Query::new().stack(stack),
    ) {
        Ok(a) => {
            // SAFETY: non-NULL and writable (contract); `bool` has alignment 1.
            unsafe { occluded.write(a.is_some()) };
            HalfrayStatus::Ok
        }
        Err(_) => HalfrayStatus::StackTooSmall,
    }
}

/// A function that can panic (an index out of bounds), built only with the `panic-probe`
/// feature: `scripts/test-ffi.sh` links a C program that calls it and expects the link to fail
/// on the panic handler's undefined symbol, so that the guard is known to work.
#[cfg(feature = "panic-probe")]
#[no_mangle]
pub extern "C" fn halfray_ffi_panic_probe(i: usize) -> u8 {
    [7u8][i]
}

// Never defined anywhere: a program that links the panic handler (because some reachable
// code of this library could panic) fails to link, naming this symbol.
#[cfg(not(test))]
extern "C" {
    fn halfray_ffi_error_a_panic_path_is_linked() -> !;
}

#[cfg(not(test))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never runs: the symbol is undefined, so a program that can reach this does not
    // link.
    unsafe { halfray_ffi_error_a_panic_path_is_linked() }
}
