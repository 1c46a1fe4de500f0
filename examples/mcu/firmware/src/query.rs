//! The `mcu-query` image: only what a firmware needs to answer ray queries on a BVH baked on
//! the host (`halfray bake`) — `Bvh::from_parts` (the loader's checks) and closest- and any-hit
//! traversal with [`WatertightF32Exact`], the watertight test without `f64` — plus the lean
//! ray loop of [`mcu_check::query_checks`] and a result hash. No formatting machinery (the
//! numbers are printed by hand) and no panic path is linked: `scripts/test-mcu.sh` reports
//! this image's `.text` as the query path's size.
//!
//! Prints `mcu-query: <machine> <queries> queries hash <hex> hits <n> leaks <n> stack <bytes>
//! traversal <bytes>` by semihosting, where `stack` is the deepest stack the queries used below
//! the point where they are called (after loading: the loader's scratch is the caller's,
//! needed only then), measured by painting the stack below the stack pointer before the
//! queries and scanning it after, and `traversal` the traversal stack the image gives them
//! ([`QUERY_STACK`] entries, at least the baked tree's `Bvh::stack_depth`, which `mcu-host`
//! checks; a query that needed more would refuse). Exits QEMU with 0, or 1 when the baked
//! data is refused, a query refused or a ray leaked.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hio;
use halfray_core::bvh::Bvh;
use halfray_core::mesh::TriangleMesh;
use halfray_core::query::StackEntry;
use halfray_core::triangle::WatertightF32Exact;
use mcu_check::{Fnv, QUERY_STACK};

mod exit;

/// The mesh and BVH baked by `halfray bake` (path in `MCU_BAKED`).
mod baked {
    include!(env!("MCU_BAKED"));
}

#[cfg(target_abi = "eabihf")]
const MACHINE: &str = "mps2-an386";
#[cfg(not(target_abi = "eabihf"))]
const MACHINE: &str = "lm3s6965evb";

/// Rays: as many as each set of the `mcu-check` image on this machine, times three.
#[cfg(target_abi = "eabihf")]
const RAYS: usize = 3 * mcu_check::M4F.rays_per_set;
#[cfg(not(target_abi = "eabihf"))]
const RAYS: usize = 3 * mcu_check::M3.rays_per_set;

/// Bytes painted below the stack pointer before the queries: more than they may use.
const PAINT_BYTES: usize = 8 * 1024;
/// The paint pattern.
const PAINT: u32 = 0xDEAD_BEEF;

/// The queries, out of line so that their whole stack lies below the painting's start. Returns
/// the summary and the lowest stack pointer at which a query was called (the stack pointer
/// inside the closure that calls them: every query's frames lie below it).
#[inline(never)]
fn queries(
    bvh: &Bvh<&[halfray_core::bvh::BvhNode], &[u32]>,
    mesh: &TriangleMesh<'_>,
    hash: &mut Fnv,
) -> (mcu_check::Summary, usize) {
    // The traversal stack: the caller's memory, sized for the baked tree (checked in `main`).
    let mut stack = [StackEntry::EMPTY; QUERY_STACK];
    let mut call_sp = usize::MAX;
    let summary = mcu_check::query_checks(bvh, mesh, RAYS, hash, |ray| {
        call_sp = call_sp.min(cortex_m::register::msp::read() as usize);
        let closest =
            mcu_check::closest_in(&WatertightF32Exact, bvh, mesh, &mut stack, ray).ok()?;
        let any = mcu_check::any_in(&WatertightF32Exact, bvh, mesh, &mut stack, ray).ok()?;
        Some((closest, any))
    });
    (summary, call_sp)
}

unsafe extern "C" {
    /// cortex-m-rt's `link.x`: the lowest address the stack may reach, the first byte after
    /// the statics (`.data`, `.bss`, `.uninit`), aligned to 4.
    static _stack_end: u8;
}

/// Runs `f` with the `PAINT_BYTES` below the stack pointer painted (fewer where the statics
/// end closer), and returns its result and the lowest address whose word no longer holds the
/// paint (the deepest stack used).
#[inline(never)]
fn with_painted_stack<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let top = cortex_m::register::msp::read() as usize;
    let bottom = (top - PAINT_BYTES).max(&raw const _stack_end as usize);
    // SAFETY: `[bottom, top)` is RAM between the end of the statics (`_stack_end`) and the
    // stack pointer: unused stack, which nothing live occupies until `f` runs (on the 64 KiB
    // `lm3s6965evb` too: `bottom` never goes below `_stack_end`; `top − PAINT_BYTES` does
    // not wrap, RAM starting at `0x2000_0000`); volatile writes of aligned words (`top` is
    // 8-byte aligned by the AAPCS, `_stack_end` 4-byte aligned by `link.x`).
    for a in (bottom..top).step_by(4) {
        unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
    }
    let r = f();
    // SAFETY: reads of the same aligned words, which stay RAM.
    let lowest = (bottom..top)
        .step_by(4)
        .find(|&a| unsafe { core::ptr::read_volatile(a as *const u32) } != PAINT)
        .unwrap_or(top);
    (r, lowest)
}

/// Writes `v` in decimal.
fn decimal(out: &mut hio::HostStream, mut v: u32) {
    let mut buf = [0u8; 10];
    let mut i = buf.len();
    loop {
        i -= 1;
        buf[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 || i == 0 {
            break;
        }
    }
    let _ = out.write_all(buf.get(i..).unwrap_or(&[]));
}

/// Writes `v` as 16 hex digits.
fn hex(out: &mut hio::HostStream, v: u64) {
    let mut buf = [0u8; 16];
    for (k, b) in buf.iter_mut().enumerate() {
        *b = b"0123456789abcdef"[((v >> (60 - 4 * k)) & 15) as usize];
    }
    let _ = out.write_all(&buf);
}

#[entry]
fn main() -> ! {
    let mesh = TriangleMesh::new(&baked::POSITIONS, &baked::TRIANGLES);
    let mut scratch = [0u32; baked::LOAD_SCRATCH_WORDS];
    let loaded = Bvh::from_parts(&baked::NODES[..], &baked::INDICES[..], &mesh, &mut scratch);
    let mut hash = Fnv::new();
    // The baked tree's depth is checked against the traversal stack on the host (`mcu-host`);
    // here a query that needed more would refuse, which counts as a failure.
    let result = loaded.ok().map(|bvh| {
        let ((s, call_sp), lowest) = with_painted_stack(|| queries(&bvh, &mesh, &mut hash));
        (s, call_sp.saturating_sub(lowest))
    });
    let ok = result.is_some_and(|(s, _)| s.leaks == 0);
    if let (Ok(mut out), Some((s, stack))) = (hio::hstdout(), result) {
        let _ = out.write_all(b"mcu-query: ");
        let _ = out.write_all(MACHINE.as_bytes());
        let _ = out.write_all(b" ");
        decimal(&mut out, s.queries);
        let _ = out.write_all(b" queries hash ");
        hex(&mut out, hash.value());
        let _ = out.write_all(b" hits ");
        decimal(&mut out, s.hits);
        let _ = out.write_all(b" leaks ");
        decimal(&mut out, s.leaks);
        let _ = out.write_all(b" stack ");
        decimal(&mut out, stack as u32);
        let _ = out.write_all(b" traversal ");
        decimal(
            &mut out,
            core::mem::size_of::<[StackEntry; QUERY_STACK]>() as u32,
        );
        let _ = out.write_all(b"\n");
    }
    exit::exit(ok)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    exit::exit(false)
}
