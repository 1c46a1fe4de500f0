//! Prints, for each machine, the lines its images print under QEMU
//! (`mcu: <machine> <queries> queries hash <hex> hits <n> leaks <n>` for `mcu-firmware`, the
//! same after `mcu-query:` for `mcu-query`, without its stack figure), computed on the host
//! with the same `mcu-check` code and buffers of the same sizes. With `MCU_C_RAYS` set, also
//! writes the Cortex-M4F query image's rays to that file and prints the line the C firmware
//! (examples/mcu-c) must print for them (`mcu-c:` and the query image's figures).

use halfray_core::Vec3;
use halfray_core::bvh::{BvhNode, node_capacity};
use halfray_core::halfedge::{EdgeRec, FaceRec, VertexRec, build_scratch_len};
use halfray_core::mesh::TriangleMesh;
use halfray_core::ray::Ray;
use mcu_check::{
    Config, Fnv, HalfedgeStorage, M3, M4F, RayStorage, edge_count, halfedge_checks, ray_checks,
    triangle_count, vertex_count,
};

/// What each image includes from `halfray bake` (paths set by scripts/test-mcu.sh).
#[allow(dead_code)]
mod baked_m4f {
    include!(env!("MCU_BAKED_M4F"));
}
#[allow(dead_code)]
mod baked_m3 {
    include!(env!("MCU_BAKED_M3"));
}

/// A baked mesh and BVH: positions, triangles, nodes, indices.
type Baked = (
    &'static [Vec3],
    &'static [[u32; 3]],
    &'static [BvhNode],
    &'static [u32],
);

fn line(machine: &str, c: Config, baked: Baked) -> Result<String, mcu_check::CheckError> {
    let mut hash = Fnv::new();
    let (nv, nt) = (vertex_count(c.grid), triangle_count(c.grid));
    let r = ray_checks(
        c.grid,
        c.rays_per_set,
        RayStorage {
            positions: &mut vec![Vec3::ZERO; nv],
            triangles: &mut vec![[0; 3]; nt],
            nodes: &mut vec![BvhNode::EMPTY; node_capacity(nt)],
            indices: &mut vec![0; nt],
        },
        &mut hash,
    )?;
    let (positions, triangles, nodes, indices) = baked;
    let mesh = TriangleMesh::new(positions, triangles);
    let f = mcu_check::baked_checks(
        nodes,
        indices,
        &mesh,
        &mut vec![0; halfray_core::bvh::load_scratch_len(triangles.len())],
        c.rays_per_set,
        &mut hash,
    )?;
    let (hv, he, hf) = (
        vertex_count(c.halfedge_grid),
        edge_count(c.halfedge_grid),
        triangle_count(c.halfedge_grid),
    );
    let h = halfedge_checks(
        c.halfedge_grid,
        HalfedgeStorage {
            positions: &mut vec![Vec3::ZERO; hv],
            triangles: &mut vec![[0; 3]; hf],
            mesh: (
                &mut vec![VertexRec::EMPTY; hv],
                &mut vec![EdgeRec::EMPTY; he],
                &mut vec![FaceRec::EMPTY; hf],
            ),
            fine: (
                &mut vec![VertexRec::EMPTY; hv + he],
                &mut vec![EdgeRec::EMPTY; 2 * he + 3 * hf],
                &mut vec![FaceRec::EMPTY; 4 * hf],
            ),
            scratch: &mut vec![0; build_scratch_len(hf)],
            out_positions: &mut vec![Vec3::ZERO; hv + he],
            out_triangles: &mut vec![[0; 3]; 4 * hf],
        },
        &mut hash,
    )?;
    let s = r.plus(f).plus(h);
    Ok(format!(
        "mcu: {machine} {} queries hash {:016x} hits {} leaks {}",
        s.queries,
        hash.value(),
        s.hits,
        s.leaks
    ))
}

/// The line the `mcu-query` image prints (without its stack figure): [`mcu_check::query_checks`]
/// with the `f64`-free watertight test on the baked BVH. Each ray is also pushed to `rays`.
fn query_line(
    machine: &str,
    c: Config,
    baked: Baked,
    rays: &mut Vec<Ray>,
) -> Result<String, mcu_check::CheckError> {
    let mut hash = Fnv::new();
    let (positions, triangles, nodes, indices) = baked;
    let mesh = TriangleMesh::new(positions, triangles);
    let mut scratch = vec![0; halfray_core::bvh::load_scratch_len(triangles.len())];
    let bvh = halfray_core::bvh::Bvh::from_parts(nodes, indices, &mesh, &mut scratch)
        .map_err(|_| mcu_check::CheckError::Build)?;
    if bvh.stack_depth() > mcu_check::QUERY_STACK {
        return Err(mcu_check::CheckError::Build);
    }
    let isect = halfray_core::triangle::WatertightF32Exact;
    let mut stack = [halfray_core::query::StackEntry::EMPTY; mcu_check::QUERY_STACK];
    let s = mcu_check::query_checks(&bvh, &mesh, 3 * c.rays_per_set, &mut hash, |ray| {
        rays.push(*ray);
        let closest = mcu_check::closest_in(&isect, &bvh, &mesh, &mut stack, ray).ok()?;
        let any = mcu_check::any_in(&isect, &bvh, &mesh, &mut stack, ray).ok()?;
        Some((closest, any))
    });
    Ok(format!(
        "mcu-query: {machine} {} queries hash {:016x} hits {} leaks {}",
        s.queries,
        hash.value(),
        s.hits,
        s.leaks
    ))
}

/// Writes `rays` as halfray-ffi's `HalfrayRay` records: origin, direction, `t_min`, `t_max`,
/// eight little-endian `f32`s each.
fn write_rays(path: &std::path::Path, rays: &[Ray]) -> std::io::Result<()> {
    let mut b = Vec::with_capacity(32 * rays.len());
    for r in rays {
        let fields = [r.origin.to_array(), r.direction.to_array()];
        for x in fields.as_flattened().iter().chain([&r.t_min, &r.t_max]) {
            b.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    std::fs::write(path, b)
}

fn main() -> std::process::ExitCode {
    let mut ok = true;
    let m4f: Baked = (
        &baked_m4f::POSITIONS,
        &baked_m4f::TRIANGLES,
        &baked_m4f::NODES,
        &baked_m4f::INDICES,
    );
    let m3: Baked = (
        &baked_m3::POSITIONS,
        &baked_m3::TRIANGLES,
        &baked_m3::NODES,
        &baked_m3::INDICES,
    );
    for (machine, config, baked) in [("mps2-an386", M4F, m4f), ("lm3s6965evb", M3, m3)] {
        let mut rays = Vec::new();
        let query = query_line(machine, config, baked, &mut rays);
        // The C firmware (examples/mcu-c) answers the M4F query image's rays through
        // halfray-ffi: written for it, its line is the query image's.
        let c_line = match (machine, &query, std::env::var_os("MCU_C_RAYS")) {
            ("mps2-an386", Ok(q), Some(path)) => Some(
                write_rays(std::path::Path::new(&path), &rays)
                    .map(|()| q.replacen("mcu-query:", "mcu-c:", 1))
                    .map_err(|e| {
                        eprintln!("mcu-host: writing {}: {e}", path.display());
                        mcu_check::CheckError::Storage
                    }),
            ),
            _ => None,
        };
        for l in [line(machine, config, baked), query]
            .into_iter()
            .chain(c_line)
        {
            match l {
                Ok(l) => println!("{l}"),
                Err(e) => {
                    eprintln!("mcu-host: {machine}: {e:?}");
                    ok = false;
                }
            }
        }
    }
    if ok {
        std::process::ExitCode::SUCCESS
    } else {
        std::process::ExitCode::FAILURE
    }
}
