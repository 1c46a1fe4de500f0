//! A `no_std`, no-allocator probe for `thumbv7em-none-eabihf` (Cortex-M4F/M7F): it links the
//! watertight triangle test, the binned-SAH builder and BVH closest-hit traversal over a small
//! static mesh (a closed cube of 12 triangles) stored in static arrays, so that the code size
//! and the stack use of the core can be measured on a real bare-metal target.
//!
//! There is no runtime crate: `_start` is the entry point (the linker's default), the build
//! storage lives on the stack, and the result is written to a volatile static so nothing is
//! optimised away. Build (the size and stack report: `docs/embedded.md`):
//!
//! ```text
//! cargo build --release --manifest-path examples/thumb-probe/Cargo.toml --target thumbv7em-none-eabihf
//! ```
#![no_std]
#![no_main]

use core::panic::PanicInfo;
use core::sync::atomic::{AtomicU32, Ordering};
use halfray_core::bvh::{BuildOptions, Bvh, BvhNode, node_capacity};
use halfray_core::mesh::TriangleMesh;
use halfray_core::prelude::*;
use halfray_core::query::{Query, Triangles};
use halfray_core::solids::{CUBE_TRIANGLES, CUBE_VERTICES};
use halfray_core::triangle::Watertight;
use halfray_core::{Ray, Vec3};

/// The cube `[-1, 1]³` ([`CUBE_VERTICES`]), in a static as flash data.
static POSITIONS: [Vec3; 8] = CUBE_VERTICES;

/// Its 12 triangles, counter-clockwise seen from outside ([`CUBE_TRIANGLES`]).
static TRIANGLES: [[u32; 3]; 12] = CUBE_TRIANGLES;

const PRIMS: usize = TRIANGLES.len();

/// Where the probe reports: the hit triangle, and the hit distance's bits.
static RESULT: AtomicU32 = AtomicU32::new(0);
static RESULT_T: AtomicU32 = AtomicU32::new(0);

type ProbeBvh<'a> = Bvh<&'a mut [BvhNode], &'a mut [u32]>;

/// Entry point. Builds the BVH into stack storage, casts one ray at the cube, then idles.
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    let mesh = TriangleMesh::new(&POSITIONS, &TRIANGLES);
    let mut nodes = [BvhNode::EMPTY; node_capacity(PRIMS)];
    let mut indices = [0u32; PRIMS];
    let Some(bvh) = build(&mesh, &mut nodes, &mut indices) else {
        idle(u32::MAX)
    };
    // Read the ray from a volatile source so the traversal is not constant-folded.
    let z = f32::from_bits(RESULT_T.load(Ordering::Relaxed)) + 5.0;
    let ray = Ray::new(Vec3::new(0.25, 0.5, z), Vec3::new(0.0, 0.0, -1.0));
    match closest(&bvh, &mesh, &ray) {
        Some((prim, t)) => {
            RESULT_T.store(t.to_bits(), Ordering::Relaxed);
            idle(prim)
        }
        None => idle(u32::MAX - 1),
    }
}

/// The build, kept out of line so its stack frame is reported on its own.
#[inline(never)]
fn build<'a>(
    mesh: &TriangleMesh<'_>,
    nodes: &'a mut [BvhNode],
    indices: &'a mut [u32],
) -> Option<ProbeBvh<'a>> {
    Bvh::build(mesh, nodes, indices, &BuildOptions::default()).ok()
}

/// Closest-hit traversal with the watertight test, kept out of line so that its stack frame
/// (fixed 64-entry traversal stack included) is reported on its own.
#[inline(never)]
fn closest(bvh: &ProbeBvh<'_>, mesh: &TriangleMesh<'_>, ray: &Ray) -> Option<(u32, f32)> {
    bvh.closest_hit(
        ray,
        &mut Triangles::new(mesh, &Watertight),
        &mut Query::new(),
    )
    .map(|(prim, hit)| (prim, hit.t))
}

fn idle(code: u32) -> ! {
    RESULT.store(code, Ordering::Relaxed);
    loop {
        core::hint::spin_loop();
    }
}

#[panic_handler]
fn panic(_: &PanicInfo) -> ! {
    idle(0xDEAD)
}
