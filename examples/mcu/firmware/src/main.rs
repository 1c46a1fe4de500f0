//! The `mcu-check` image: runs the checks of this machine's [`mcu_check::Config`] with every
//! buffer on the stack (no heap, no `static mut`), prints
//! `mcu: <machine> <queries> queries hash <hex> hits <n> leaks <n>` by semihosting and exits
//! QEMU with status 0, or 1 on an error, a leak or a panic.
#![no_std]
#![no_main]
// The bench image (feature `bench`) runs only `bench::run`.
#![cfg_attr(feature = "bench", allow(dead_code, unused_imports))]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use halfray_core::Vec3;
use halfray_core::bvh::{BvhNode, node_capacity};
use halfray_core::halfedge::{EdgeRec, FaceRec, VertexRec, build_scratch_len};
use halfray_core::mesh::TriangleMesh;
use mcu_check::{
    CheckError, Config, Fnv, HalfedgeStorage, RayStorage, Summary, baked_checks, edge_count,
    halfedge_checks, ray_checks, triangle_count, vertex_count,
};

mod exit;

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
    #[cfg(feature = "bench")]
    bench::run();
    #[cfg(not(feature = "bench"))]
    checks()
}

/// The checks: prints the result line and exits QEMU.
#[cfg(not(feature = "bench"))]
fn checks() -> ! {
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
    exit::exit(ok)
}

/// Instructions per closest-hit query, per triangle variant, on the baked BVH.
///
/// Under `-icount shift=0` QEMU advances virtual time by 1 ns per instruction, and SysTick
/// (core clock) counts that virtual time; the instructions per tick are calibrated with
/// `cortex_m::asm::delay(n)`, which runs exactly `2·(n + 1)` instructions. Prints
/// `mcu-bench: MACHINE VARIANT INSTRUCTIONS_PER_QUERY HITS` per variant, then exits.
#[cfg(feature = "bench")]
mod bench {
    use super::{CONFIG, MACHINE, baked, hprintln};
    use cortex_m::peripheral::SYST;
    use cortex_m::peripheral::syst::SystClkSource;
    use halfray_core::bvh::Bvh;
    use halfray_core::mesh::TriangleMesh;
    use halfray_core::prelude::*;
    use halfray_core::query::{Query, Triangles};
    use halfray_core::triangle::{
        Cramer, F64Reference, MollerTrumbore, TriangleIntersector, Watertight, WatertightF32,
        WatertightF32Exact,
    };
    use halfray_core::{Ray, Vec3};

    const RAYS: usize = CONFIG.rays_per_set;
    const CALIBRATION_LOOPS: u32 = 200_000;

    /// SysTick ticks `f` takes (the counter counts down, 24 bits).
    fn ticks(f: impl FnOnce()) -> u32 {
        let a = SYST::get_current();
        f();
        let b = SYST::get_current();
        a.wrapping_sub(b) & 0x00FF_FFFF
    }

    fn per_query<I: TriangleIntersector>(
        name: &str,
        isect: &I,
        bvh: &Bvh<&[halfray_core::bvh::BvhNode], &[u32]>,
        mesh: &TriangleMesh<'_>,
        rays: &[Ray],
        per_tick: f32,
    ) {
        let mut hits = 0u32;
        let t = ticks(|| {
            for r in rays {
                hits += core::hint::black_box(bvh.closest_hit(
                    r,
                    &mut Triangles::new(mesh, isect),
                    &mut Query::new(),
                ))
                .is_some() as u32;
            }
        });
        let insns = t as f32 * per_tick / rays.len() as f32;
        hprintln!("mcu-bench: {} {} {} {}", MACHINE, name, insns as u32, hits);
    }

    pub fn run() -> ! {
        let Some(mut p) = cortex_m::Peripherals::take() else {
            crate::exit::exit(false);
        };
        p.SYST.set_clock_source(SystClkSource::Core);
        p.SYST.set_reload(0x00FF_FFFF);
        p.SYST.clear_current();
        p.SYST.enable_counter();
        let cal = ticks(|| cortex_m::asm::delay(CALIBRATION_LOOPS));
        let per_tick = (2 * (CALIBRATION_LOOPS + 1)) as f32 / cal.max(1) as f32;
        let mesh = TriangleMesh::new(&baked::POSITIONS, &baked::TRIANGLES);
        let mut scratch = [0u32; baked::LOAD_SCRATCH_WORDS];
        let Ok(bvh) = Bvh::from_parts(&baked::NODES[..], &baked::INDICES[..], &mesh, &mut scratch)
        else {
            crate::exit::exit(false);
        };
        // A pinhole camera framing the mesh's box from outside, as in `baked_checks`.
        let b = bvh.bounds();
        let (center, size) = ((b.min + b.max) * 0.5, b.max - b.min);
        let reach = size.x.max(size.y).max(size.z);
        let eye = center + Vec3::new(0.3, -0.4, 1.0) * (1.5 * reach);
        let mut rays = [Ray::new(eye, Vec3::Z); RAYS];
        let side = (1..=RAYS).take_while(|s| s * s <= RAYS).last().unwrap_or(1);
        for (k, r) in rays.iter_mut().enumerate() {
            let (x, y) = ((k % side) as f32, ((k / side) % side) as f32);
            let u = ((x + 0.5) / side as f32 - 0.5) * reach;
            let v = ((y + 0.5) / side as f32 - 0.5) * reach;
            *r = Ray::new(eye, center + Vec3::new(u, v, 0.0) - eye);
        }
        hprintln!(
            "mcu-bench: {} calibration {} instructions per tick",
            MACHINE,
            per_tick
        );
        per_query("watertight", &Watertight, &bvh, &mesh, &rays, per_tick);
        per_query(
            "watertight-f32",
            &WatertightF32,
            &bvh,
            &mesh,
            &rays,
            per_tick,
        );
        per_query(
            "watertight-f32-exact",
            &WatertightF32Exact,
            &bvh,
            &mesh,
            &rays,
            per_tick,
        );
        per_query(
            "moller-trumbore",
            &MollerTrumbore::CLASSIC,
            &bvh,
            &mesh,
            &rays,
            per_tick,
        );
        per_query(
            "moller-trumbore-noeps",
            &MollerTrumbore::NO_EPSILON,
            &bvh,
            &mesh,
            &rays,
            per_tick,
        );
        per_query("cramer", &Cramer, &bvh, &mesh, &rays, per_tick);
        per_query("f64-reference", &F64Reference, &bvh, &mesh, &rays, per_tick);
        crate::exit::exit(true)
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("mcu: {} panic: {}", MACHINE, info);
    exit::exit(false)
}
