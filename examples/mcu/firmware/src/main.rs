//! The `mcu-check` image: runs the checks of this machine's [`mcu_check::Config`] with every
//! buffer on the stack (no heap, no `static mut`), prints
//! `mcu: <machine> <queries> queries hash <hex> hits <n> leaks <n>` by semihosting and exits
//! QEMU with status 0, or 1 on an error, a leak or a panic.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use halfray_core::Vec3;
use halfray_core::bvh::{BvhNode, TriangleMesh, node_capacity};
use halfray_core::halfedge::{EdgeRec, FaceRec, VertexRec, build_scratch_len};
use mcu_check::{
    CheckError, Config, Fnv, HalfedgeStorage, RayStorage, Summary, baked_checks, edge_count,
    halfedge_checks, ray_checks, triangle_count, vertex_count,
};

/// The mesh and BVH baked by `halfray bake` (path in `MCU_BAKED`, set by scripts/test-mcu.sh):
/// `static` arrays in flash.
mod baked {
    include!(env!("MCU_BAKED"));
}

#[cfg(target_abi = "eabihf")]
const MACHINE: &str = "mps2-an386";
#[cfg(target_abi = "eabihf")]
const CONFIG: Config = mcu_check::M4F;
#[cfg(not(target_abi = "eabihf"))]
const MACHINE: &str = "lm3s6965evb";
#[cfg(not(target_abi = "eabihf"))]
const CONFIG: Config = mcu_check::M3;

const NV: usize = vertex_count(CONFIG.grid);
const NT: usize = triangle_count(CONFIG.grid);
const HV: usize = vertex_count(CONFIG.halfedge_grid);
const HE: usize = edge_count(CONFIG.halfedge_grid);
const HF: usize = triangle_count(CONFIG.halfedge_grid);

#[inline(never)]
fn rays(hash: &mut Fnv) -> Result<Summary, CheckError> {
    let mut positions = [Vec3::ZERO; NV];
    let mut triangles = [[0u32; 3]; NT];
    let mut nodes = [BvhNode::EMPTY; node_capacity(NT)];
    let mut indices = [0u32; NT];
    ray_checks(
        CONFIG.grid,
        CONFIG.rays_per_set,
        RayStorage {
            positions: &mut positions,
            triangles: &mut triangles,
            nodes: &mut nodes,
            indices: &mut indices,
        },
        hash,
    )
}

#[inline(never)]
fn flash(hash: &mut Fnv) -> Result<Summary, CheckError> {
    let mesh = TriangleMesh::new(&baked::POSITIONS, &baked::TRIANGLES);
    let mut scratch = [0u32; baked::LOAD_SCRATCH_WORDS];
    baked_checks(
        &baked::NODES,
        &baked::INDICES,
        &mesh,
        &mut scratch,
        CONFIG.rays_per_set,
        hash,
    )
}

#[inline(never)]
fn halfedge(hash: &mut Fnv) -> Result<Summary, CheckError> {
    let mut positions = [Vec3::ZERO; HV];
    let mut triangles = [[0u32; 3]; HF];
    let mut v = [VertexRec::EMPTY; HV];
    let mut e = [EdgeRec::EMPTY; HE];
    let mut f = [FaceRec::EMPTY; HF];
    let mut v2 = [VertexRec::EMPTY; HV + HE];
    let mut e2 = [EdgeRec::EMPTY; 2 * HE + 3 * HF];
    let mut f2 = [FaceRec::EMPTY; 4 * HF];
    let mut scratch = [0u32; build_scratch_len(HF)];
    let mut out_positions = [Vec3::ZERO; HV + HE];
    let mut out_triangles = [[0u32; 3]; 4 * HF];
    halfedge_checks(
        CONFIG.halfedge_grid,
        HalfedgeStorage {
            positions: &mut positions,
            triangles: &mut triangles,
            mesh: (&mut v, &mut e, &mut f),
            fine: (&mut v2, &mut e2, &mut f2),
            scratch: &mut scratch,
            out_positions: &mut out_positions,
            out_triangles: &mut out_triangles,
        },
        hash,
    )
}

#[entry]
fn main() -> ! {
    let mut hash = Fnv::new();
    let result = rays(&mut hash)
        .and_then(|r| flash(&mut hash).map(|f| r.plus(f)))
        .and_then(|r| halfedge(&mut hash).map(|h| r.plus(h)));
    let ok = match result {
        Ok(s) => {
            hprintln!(
                "mcu: {} {} queries hash {:016x} hits {} leaks {}",
                MACHINE,
                s.queries,
                hash.value(),
                s.hits,
                s.leaks
            );
            s.leaks == 0
        }
        Err(e) => {
            hprintln!("mcu: {} error {:?}", MACHINE, e);
            false
        }
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("mcu: {} panic: {}", MACHINE, info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
