//! The Embree side of the cross-check (feature `embree`).

use super::judge::{self, Answer, Verdict};
use super::sets::{self, Adjacency, SET_NAMES, SetRay};
use super::{CrosscheckArgs, SetReport, markdown};
use crate::accel::MeshAccel;
use crate::atomic::write_bytes_atomic;
use crate::embree::{EmbreeDevice, EmbreeScene, ray_is_valid};
use crate::error::{Error, Result};
use crate::obj::read_obj;
use halfray_core::Ray;
use halfray_core::triangle::TriangleVariant;
use std::time::Instant;

fn embree_answer(scene: &EmbreeScene, r: &Ray) -> Option<Answer> {
    scene.intersect_ray(r).map(|h| Answer {
        prim: h.prim_id,
        t: h.t,
        u: h.u,
        v: h.v,
    })
}

/// Runs every requested set on every mesh, prints the table, writes JSON, and fails with
/// [`Error::Mismatch`] past `--max-mismatch` genuine mismatches or on any watertight leak.
pub fn run(args: &CrosscheckArgs) -> Result<()> {
    let variant = args.intersector.0;
    let set_names: Vec<String> = if args.sets.is_empty() {
        SET_NAMES.iter().map(|s| s.to_string()).collect()
    } else {
        args.sets.clone()
    };
    // clap accepts only names of `SET_NAMES` (`CrosscheckArgs::sets`).
    let device = EmbreeDevice::new()?;
    let mut rows = Vec::new();
    for (mi, path) in args.meshes.iter().enumerate() {
        let mesh = read_obj(path)?;
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into(),
        );
        let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
        let robust = EmbreeScene::new(&device, &positions, &mesh.triangles, true)?;
        let fast = EmbreeScene::new(&device, &positions, &mesh.triangles, false)?;
        let adj = Adjacency::new(&mesh);
        let accel = MeshAccel::new(mesh)?;
        for set in &set_names {
            let rays = sets::generate(
                set,
                &accel.mesh,
                &adj,
                args.rays,
                args.seed.wrapping_add(mi as u64),
            )
            .unwrap_or_default();
            let rays: Vec<SetRay> = rays
                .into_iter()
                .filter(|r| {
                    ray_is_valid(
                        r.ray.origin.to_array(),
                        r.ray.direction.to_array(),
                        r.ray.t_min,
                        r.ray.t_max,
                    )
                })
                .collect();
            let mut row = compare_set(&accel, &robust, &fast, variant, &rays);
            row.mesh = name.clone();
            row.name = set.clone();
            eprintln!(
                "crosscheck {name} {set}: {} rays, {} genuine, {} leaks halfray, {} leaks embree",
                row.rays, row.genuine_mismatches, row.leaks_halfray, row.leaks_embree
            );
            rows.push(row);
        }
        if mi == 0
            && let Some(out) = &args.depth_image
        {
            super::depth::write_depth_diff(out, &accel, &robust, variant, args.depth_size)?;
        }
    }
    print!("{}", markdown(&rows));
    let total_h: f64 = rows
        .iter()
        .map(|r| r.rays as f64 / r.mrays_halfray.max(1e-12))
        .sum();
    let total_e: f64 = rows
        .iter()
        .map(|r| r.rays as f64 / r.mrays_embree.max(1e-12))
        .sum();
    if total_h > 0.0 {
        println!(
            "\nthroughput ratio halfray / Embree robust (time-weighted over all sets): {:.2}",
            total_e / total_h
        );
    }
    if let Some(path) = &args.json {
        let json = serde_json::json!({ "intersector": variant.name(), "sets": rows });
        let bytes = serde_json::to_vec_pretty(&json).map_err(|e| Error::Other(e.to_string()))?;
        write_bytes_atomic(path, &bytes)?;
    }
    let genuine: usize = rows.iter().map(|r| r.genuine_mismatches).sum();
    let leaks: usize = rows.iter().map(|r| r.leaks_halfray).sum();
    if genuine > args.max_mismatch {
        return Err(Error::Mismatch(format!(
            "{genuine} genuine mismatches (allowed: {})",
            args.max_mismatch
        )));
    }
    if variant.is_watertight() && leaks > 0 {
        return Err(Error::Mismatch(format!(
            "{leaks} leaks through the watertight intersector"
        )));
    }
    Ok(())
}

fn compare_set(
    accel: &MeshAccel,
    robust: &EmbreeScene,
    fast: &EmbreeScene,
    variant: TriangleVariant,
    rays: &[SetRay],
) -> SetReport {
    let mut row = SetReport {
        rays: rays.len(),
        ..SetReport::default()
    };
    // Timed passes, one thread each, same rays.
    let start = Instant::now();
    let ours: Vec<Option<Answer>> = rays
        .iter()
        .map(|r| {
            accel
                .closest_variant(variant, &r.ray)
                .map(|(prim, h)| Answer {
                    prim,
                    t: h.t,
                    u: h.b1,
                    v: h.b2,
                })
        })
        .collect();
    let secs_h = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let emb: Vec<Option<Answer>> = rays.iter().map(|r| embree_answer(robust, &r.ray)).collect();
    let secs_e = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let emb_fast: Vec<Option<Answer>> = rays.iter().map(|r| embree_answer(fast, &r.ray)).collect();
    let secs_f = start.elapsed().as_secs_f64();
    let mrays = |s: f64| {
        if s > 0.0 {
            rays.len() as f64 / s / 1.0e6
        } else {
            0.0
        }
    };
    row.mrays_halfray = mrays(secs_h);
    row.mrays_embree = mrays(secs_e);
    row.mrays_embree_default = mrays(secs_f);

    for (i, r) in rays.iter().enumerate() {
        let (h, e) = (ours[i], emb[i]);
        if let Some(target) = &r.target {
            row.leak_rays += 1;
            let lh = judge::is_leak(&r.ray, h.as_ref(), target.t);
            let le = judge::is_leak(&r.ray, e.as_ref(), target.t);
            row.leaks_halfray += lh as usize;
            row.leaks_embree += le as usize;
            row.leaks_embree_default +=
                judge::is_leak(&r.ray, emb_fast[i].as_ref(), target.t) as usize;
            if lh && std::env::var_os("HALFRAY_CROSSCHECK_DEBUG").is_some() {
                eprintln!(
                    "halfray leak: ray {:?} incident {:?} ours {h:?} embree {e:?}",
                    r.ray, target.incident
                );
            }
            if lh != le {
                // A leak is its own category; counted above, not judged again.
                continue;
            }
        }
        let verdict = if h == e {
            Verdict::Agree
        } else {
            let reference = accel
                .closest_variant(TriangleVariant::F64Reference, &r.ray)
                .map(|(prim, hit)| Answer {
                    prim,
                    t: hit.t,
                    u: hit.b1,
                    v: hit.b2,
                });
            judge::judge(&accel.mesh, &r.ray, h, e, reference)
        };
        if std::env::var_os("HALFRAY_CROSSCHECK_DEBUG").is_some()
            && !matches!(verdict, Verdict::Agree | Verdict::Tie)
        {
            eprintln!("{verdict:?}: ray {:?} ours {h:?} embree {e:?}", r.ray);
        }
        match verdict {
            Verdict::Agree => row.agree += 1,
            Verdict::Tie => row.ties += 1,
            Verdict::WithinTolerance => row.within_tolerance += 1,
            Verdict::EmbreeWrong => row.embree_wrong += 1,
            Verdict::Genuine => row.genuine_mismatches += 1,
        }
        // Any hit over the same interval.
        let any_h = accel.any_variant(variant, &r.ray);
        let any_e = robust.occluded_ray(&r.ray);
        // Where the closest hits agree (or tie), the any-hit answers must agree too.
        row.any_hit_disagreements +=
            (matches!(verdict, Verdict::Agree | Verdict::Tie) && any_h != any_e) as usize;
        row.any_vs_closest_inconsistent +=
            (any_h != h.is_some()) as usize + (any_e != e.is_some()) as usize;
    }
    row
}
