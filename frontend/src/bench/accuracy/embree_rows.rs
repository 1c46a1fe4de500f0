//! The `embree` and `embree-robust` rows of the accuracy benchmark (feature `embree`): the same
//! workloads through Embree 4's `rtcIntersect1` on scenes of the whole meshes.
//!
//! Embree has no per-triangle entry point, so `ns_per_test` is not reported, and every query
//! runs against a whole mesh: a leak is a miss or a hit beyond the aimed-at edge or vertex
//! (what [`crate::crosscheck::judge::is_leak`] decides), a false hit is the aimed-at triangle
//! itself reported as the closest hit, and `t` errors are taken where the closest hit is the
//! aimed-at triangle.

use super::VariantRow;
use super::triangles::{Accuracy, Workload};
use crate::crosscheck::judge::{is_leak, near_boundary};
use crate::embree::{EmbreeDevice, EmbreeMesh, EmbreeScene, ray_is_valid};
use crate::error::Result;
use crate::obj::ObjMesh;
use halfray_core::Ray;
use std::hint::black_box;
use std::time::Instant;

/// `m` checked and laid out for Embree, once per mesh: every scene of it shares the buffers.
fn embree_mesh(m: &ObjMesh) -> Result<EmbreeMesh> {
    let pos: Vec<[f32; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
    Ok(EmbreeMesh::new(&pos, &m.triangles)?)
}

/// The index of `m` in `distinct` (the same mesh or an equal one), pushed there if new.
fn index_of<'a>(distinct: &mut Vec<&'a ObjMesh>, m: &'a ObjMesh) -> usize {
    match distinct.iter().position(|&d| std::ptr::eq(d, m) || d == m) {
        Some(i) => i,
        None => {
            distinct.push(m);
            distinct.len() - 1
        }
    }
}

fn closest(s: &EmbreeScene, r: &Ray) -> Option<(u32, f32)> {
    if !ray_is_valid(
        r.origin.to_array(),
        r.direction.to_array(),
        r.t_min,
        r.t_max,
    ) {
        return None;
    }
    s.intersect_ray(r).map(|h| (h.prim_id, h.t))
}

/// Median Mrays/s of Embree closest-hit queries over `rays`.
fn mrays(s: &EmbreeScene, rays: &[Ray], reps: usize) -> f64 {
    crate::timing::median_of(reps, || {
        let start = Instant::now();
        let mut k = 0u32;
        for r in rays {
            k += closest(s, black_box(r)).is_some() as u32;
        }
        black_box(k);
        crate::timing::mrays_per_second(rays.len() as u64, start.elapsed().as_secs_f64())
    })
}

/// The two Embree rows. `throughput_sets` are the ray sets and meshes of the BVH columns, in
/// column order (`None` where a column is not measured). Each distinct mesh (of `meshes` and
/// the columns, equal ones once) is laid out for Embree once, and each row builds one scene of
/// it, which its accuracy figures and its throughput columns share.
pub fn rows(
    meshes: &[ObjMesh],
    w: &Workload,
    throughput_sets: &[Option<(&ObjMesh, Vec<Ray>)>; 4],
    reps: usize,
) -> Result<Vec<VariantRow>> {
    let device = EmbreeDevice::new()?;
    let mut distinct = Vec::new();
    let mesh_ix: Vec<usize> = meshes.iter().map(|m| index_of(&mut distinct, m)).collect();
    let column_ix = throughput_sets
        .each_ref()
        .map(|e| e.as_ref().map(|(m, _)| index_of(&mut distinct, m)));
    let laid_out: Vec<EmbreeMesh> = distinct
        .iter()
        .map(|m| embree_mesh(m))
        .collect::<Result<_>>()?;
    let mut out = Vec::new();
    for (name, robust) in [("embree", false), ("embree-robust", true)] {
        let built: Vec<EmbreeScene> = laid_out
            .iter()
            .map(|m| Ok(EmbreeScene::from_mesh(&device, m, robust)?))
            .collect::<Result<_>>()?;
        // The scene of `meshes[mi]`.
        let scenes: Vec<&EmbreeScene> = mesh_ix.iter().map(|&i| &built[i]).collect();
        let mut acc = Accuracy {
            leak_rays: w.leak_rays.len(),
            outside_rays: w.outside_rays.len(),
            ..Accuracy::default()
        };
        for ((ray, _), &mi) in w.leak_rays.iter().zip(&w.leak_mesh) {
            let hit = closest(scenes[mi], ray).map(|(prim, t)| crate::crosscheck::judge::Answer {
                prim,
                t,
                u: 0.0,
                v: 0.0,
            });
            acc.leaks += is_leak(ray, hit.as_ref(), 1.0) as usize;
        }
        for ((ray, _), &(mi, f)) in w.outside_rays.iter().zip(&w.outside_ids) {
            acc.false_hits += closest(scenes[mi], ray).is_some_and(|(p, _)| p == f) as usize;
        }
        for ((ray, tri), &(mi, f)) in w.pair_rays.iter().zip(&w.pair_ids) {
            let got = closest(scenes[mi], ray);
            let reference = super::triangles::oracle_t(ray, tri);
            if !near_boundary(ray, tri) {
                // Hit/miss of the aimed-at triangle, where it is not occluded by another one.
                let hits_it = got.is_some_and(|(p, _)| p == f);
                let other_first = got.is_some_and(|(p, _)| p != f);
                if !other_first {
                    acc.hit_miss_rays += 1;
                    acc.hit_miss_disagreements += (hits_it != reference.is_some()) as usize;
                }
            }
            if let (Some((p, t)), Some(tr)) = (got, reference)
                && p == f
            {
                acc.rel_t_errors.push(((t as f64 - tr) / tr).abs());
            }
        }
        acc.rel_t_errors.sort_by(f64::total_cmp);
        let mut cols = [None; 4];
        for ((col, entry), ix) in cols.iter_mut().zip(throughput_sets).zip(column_ix) {
            if let (Some((_, rays)), Some(i)) = (entry, ix) {
                *col = Some(mrays(&built[i], rays, reps));
            }
        }
        out.push(VariantRow::new(name, None, cols, &acc));
    }
    Ok(out)
}
