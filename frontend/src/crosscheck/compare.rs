//! The Embree side of the cross-check (feature `embree`): every mesh of the run, each set's
//! rays through both sides, the single-thread timed passes, then every ray classified on all
//! worker threads.

use super::corpus::{ResultLog, RunMeshes, run_inputs};
use super::judge::{self, Answer, Verdict};
use super::report::{DetailKind, Disagreement, MeshResult, Report, RunConfig, SetReport};
use super::sets::{self, Adjacency, SET_NAMES, SetRay};
use super::{CrosscheckArgs, finish};
use crate::accel::MeshAccel;
use crate::embree::{EmbreeDevice, EmbreeMesh, EmbreeScene, takes_ray};
use crate::error::{Error, Result};
use crate::obj::read_obj;
use crate::outputs::{Named, file_id, reserve_outputs};
use crate::raysets::named::watertight_hits;
use crate::timing::{TIMED_PASSES, spread_positions};
use halfray_core::Ray;
use halfray_core::triangle::TriangleVariant;
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// The two sides of one mesh, halfray's BVH and Embree's robust and default scenes, and the
/// `f64` reference that judges them (over the same mesh, without the BVH).
struct Sides<'a> {
    accel: &'a MeshAccel,
    reference: &'a judge::Reference<'a>,
    robust: &'a EmbreeScene,
    fast: &'a EmbreeScene,
    variant: TriangleVariant,
}

impl Sides<'_> {
    fn halfray(&self, r: &Ray) -> Option<Answer> {
        Answer::of_hit(self.accel.closest_variant(self.variant, r))
    }

    /// [`Sides::halfray`] of every ray of `rays`, by the batch query (the same answers).
    fn halfray_batch(&self, rays: &[Ray]) -> Vec<Option<Answer>> {
        let hits = self.accel.closest_variant_batch(self.variant, rays);
        hits.into_iter().map(Answer::of_hit).collect()
    }
}

/// Bytes one ray of a set holds at the set's peak: the generated ray, its shard's copy and
/// its outcome, and, when timed, its ray in the batch and the three sides' answers. Counts
/// inline sizes only: a ray's disagreement details exist only for the few rays that differ.
const BYTES_PER_SET_RAY: u64 = (size_of::<SetRay>()
    + size_of::<(usize, SetRay)>()
    + size_of::<Outcome>()
    + size_of::<Ray>()
    + 3 * size_of::<Option<Answer>>()) as u64;

/// Bytes one pixel of the depth image holds: its camera ray, both sides' depths, three RGB
/// pixels of the side-by-side image and, at most, as many again in the encoded PNG.
const BYTES_PER_DEPTH_PIXEL: u64 = (size_of::<Ray>() + 2 * size_of::<Option<f32>>() + 2 * 9) as u64;

/// The size options, checked before any work: at least one ray a set and one timed ray (a
/// check of no ray passes vacuously), `--rays` rays of one set and the `--depth-size`² image
/// each within [`crate::limits::check_memory`]'s budget, and a depth image at least one pixel
/// wide.
fn check_sizes(args: &CrosscheckArgs) -> Result<()> {
    for (name, n) in [("--rays", args.rays), ("--timing-rays", args.timing_rays)] {
        if n == 0 {
            return Err(Error::Usage(format!(
                "{name} must be at least 1 (a check of no ray checks nothing)"
            )));
        }
    }
    let rays = args.rays as u64;
    crate::limits::check_memory(
        &format!("--rays {rays} (one set's rays held at once)"),
        rays.checked_mul(BYTES_PER_SET_RAY),
    )?;
    if args.depth_image.is_some() {
        let size = args.depth_size as u64;
        if size == 0 {
            return Err(Error::Usage("--depth-size must be at least 1".into()));
        }
        crate::limits::check_memory(
            &format!("--depth-size {size}"),
            size.checked_mul(size)
                .and_then(|p| p.checked_mul(BYTES_PER_DEPTH_PIXEL)),
        )?;
    }
    Ok(())
}

/// Runs every requested set on every mesh (see [`finish`] for the exit status).
pub fn run(args: &CrosscheckArgs) -> Result<()> {
    check_sizes(args)?;
    let run = RunMeshes::read(&args.meshes, args.mesh_list.as_deref(), "cross-check")?;
    run.refuse_repeated("checked")?;
    crate::cli_values::refuse_repeated_sets(&args.sets)?;
    let RunMeshes {
        paths: meshes,
        named_at,
    } = run;
    let config = RunConfig {
        intersector: args.intersector.0.name().into(),
        seed: args.seed,
        rays: args.rays,
        ray_sets: if args.sets.is_empty() {
            SET_NAMES.iter().map(|s| s.to_string()).collect()
        } else {
            args.sets.clone()
        },
        shard: args.shard,
    };
    // Outputs are checked before any work, and none may be an input.
    let inputs = run_inputs(&meshes, args.mesh_list.as_deref());
    let mut outputs = Vec::new();
    outputs.extend(args.json.iter().map(|p| Named::new("--json", p)));
    outputs.extend(
        args.depth_image
            .iter()
            .map(|p| Named::new("--depth-image", p)),
    );
    let mut reserved = reserve_outputs(&outputs, &inputs, args.force)?.into_iter();
    if let Some(p) = &args.depth_image {
        crate::png::check_png_name(Named::new("--depth-image", p))?;
    }
    let json_out = args.json.as_ref().and_then(|_| reserved.next());
    let depth_out = args.depth_image.as_ref().and_then(|_| reserved.next());
    // The depth image of the first mesh checked, written with the report at the end.
    let mut depth_png: Option<Vec<u8>> = None;
    if let Some(log) = &args.jsonl {
        refuse_log_clash(log, &inputs, &outputs)?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.map_or(0, usize::from))
        .build()
        .map_err(Error::Threads)?;
    let device = EmbreeDevice::new()?;
    // Opened (created) only once the run can start: a run refused for want of Embree or
    // threads leaves no empty log behind.
    let mut log = args
        .jsonl
        .as_ref()
        .map(|p| ResultLog::open(p, args.resume, &config))
        .transpose()?;
    let start = Instant::now();
    let mut results = Vec::with_capacity(meshes.len());
    // Rays this process checked (not those of meshes a resumed log already holds): the
    // throughput's numerator.
    let mut checked_rays = 0.0f64;
    for (path, named_at) in meshes.iter().zip(&named_at) {
        let shown = path.display().to_string();
        if let Some(done) = log.as_ref().and_then(|l| l.done(path)) {
            crate::note!(
                "crosscheck {}: already in the results log, skipped (--resume)",
                crate::text::escaped(&shown)
            );
            results.push(done.clone());
            continue;
        }
        let want_depth = depth_out.is_some() && depth_png.is_none();
        let checked = pool.install(|| check_mesh(&device, path, &config, args, want_depth));
        let checked = checked.map(|(rows, png)| {
            depth_png = depth_png.take().or(png);
            checked_rays += rows.iter().map(|r| r.rays as f64).sum::<f64>();
            rows
        });
        // A failed mesh a list named is reported with the list's line.
        let error = checked.as_ref().err().map(|e| match named_at {
            Some(at) => format!("{e} (named at {at})"),
            None => e.to_string(),
        });
        if let Some(e) = &error {
            crate::note!(
                "crosscheck {}: {} (counted as failed; the run goes on)",
                crate::text::escaped(&shown),
                crate::text::escaped(e)
            );
        }
        let result = MeshResult {
            path: shown.clone(),
            config: config.clone(),
            error,
            sets: checked.unwrap_or_default(),
        };
        if let Some(log) = &mut log {
            log.append(&result)?;
        }
        results.push(result);
    }
    let depth = match (depth_out, depth_png) {
        (Some(out), Some(png)) => Some((out, png)),
        (Some(_), None) => {
            crate::note!(
                "crosscheck: no mesh was checked in this run, so no depth image was written"
            );
            None
        }
        (None, _) => None,
    };
    let wall = start.elapsed().as_secs_f64();
    let mut report = Report::new(config, pool.current_num_threads(), wall, &results);
    report.rays_per_second = if wall > 0.0 { checked_rays / wall } else { 0.0 };
    finish(&report, json_out, depth, args.max_mismatch)
}

/// Refuses a results log that is an input or another output (by file identity).
fn refuse_log_clash(log: &Path, inputs: &[Named<'_>], outputs: &[Named<'_>]) -> Result<()> {
    let Ok(id) = file_id(log) else {
        return Ok(()); // Not created yet: it cannot be any existing file.
    };
    for other in inputs.iter().chain(outputs) {
        if file_id(other.path).is_ok_and(|o| o == id) {
            return Err(Error::Usage(format!(
                "--jsonl `{}` is the {} `{}`",
                crate::text::path(log),
                other.name,
                crate::text::path(other.path)
            )));
        }
    }
    Ok(())
}

/// One mesh's rows, and its depth image (PNG bytes) when `want_depth`.
fn check_mesh(
    device: &EmbreeDevice,
    path: &Path,
    config: &RunConfig,
    args: &CrosscheckArgs,
    want_depth: bool,
) -> Result<(Vec<SetReport>, Option<Vec<u8>>)> {
    let mesh = read_obj(path)?;
    let name = crate::text::file_name(path);
    let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let in_file = |e: Error| Error::InFile {
        path: path.to_path_buf(),
        source: Box::new(e),
    };
    // Checked and laid out once; each scene keeps its own share of the buffers.
    let embree_mesh =
        EmbreeMesh::new(&positions, &mesh.triangles).map_err(|e| in_file(e.into()))?;
    let robust =
        EmbreeScene::from_mesh(device, &embree_mesh, true).map_err(|e| in_file(e.into()))?;
    let fast =
        EmbreeScene::from_mesh(device, &embree_mesh, false).map_err(|e| in_file(e.into()))?;
    let adj = Adjacency::new(&mesh);
    let accel = MeshAccel::new(mesh).map_err(in_file)?;
    let reference = judge::Reference::new(&accel.mesh);
    let sides = Sides {
        accel: &accel,
        reference: &reference,
        robust: &robust,
        fast: &fast,
        variant: args.intersector.0,
    };
    let seed = sets::mesh_seed(config.seed, &name);
    let hits = watertight_hits(accel.bvh(), &accel.mesh);
    let mut rows = Vec::with_capacity(config.ray_sets.len());
    for set in &config.ray_sets {
        let rays =
            sets::generate(set, &accel.mesh, &adj, config.rays, seed, &hits).unwrap_or_default();
        let generated = config.shard.select(rays);
        let shard_rays = generated.len();
        let rays: Vec<(usize, SetRay)> = generated
            .into_iter()
            .filter(|(_, r)| takes_ray(&r.ray))
            .collect();
        let mut row = compare_set(&sides, &rays, args.timing_rays);
        row.mesh = name.clone();
        row.path = path.display().to_string();
        row.name = set.clone();
        row.rays_outside_embree = shard_rays - rays.len();
        let shown = crate::text::escaped(&name);
        let dropped = match row.rays_outside_embree {
            0 => String::new(),
            n => format!(" ({n} more generated, not traced: outside Embree's range)"),
        };
        crate::note!(
            "crosscheck {shown} {set}: {} rays{dropped}, {} genuine, {} leaks halfray, {} leaks embree",
            row.rays,
            row.genuine_mismatches,
            row.leaks_halfray,
            row.leaks_embree
        );
        if row.rays == 0 {
            crate::note!(
                "warning: crosscheck {shown} {set}: no ray left to check ({} generated, {} of them outside Embree's range)",
                shard_rays,
                row.rays_outside_embree
            );
        }
        rows.push(row);
    }
    let png = want_depth
        .then(|| super::depth::depth_diff_png(&accel, &robust, args.intersector.0, args.depth_size))
        .transpose()?;
    Ok((rows, png))
}

/// Times `pass` once on the calling thread: its result and seconds.
fn timed<T>(pass: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let out = pass();
    (out, start.elapsed().as_secs_f64())
}

/// What one ray contributes to its set's row.
#[derive(Default)]
struct Outcome {
    /// `None`: a leak on one side only (counted as such, not judged again).
    verdict: Option<Verdict>,
    leak_ray: bool,
    leaks: [bool; 3],
    any_hit: bool,
    /// Either side's any-hit answer contradicts its own closest hit (the ray counts once).
    any_vs_closest: bool,
    details: Vec<Disagreement>,
}

/// Classifies one ray (index `index` in its set) from the three sides' closest hits.
fn classify(
    sides: &Sides<'_>,
    index: usize,
    r: &SetRay,
    h: Option<Answer>,
    e: Option<Answer>,
    f: Option<Answer>,
) -> Outcome {
    let mut out = Outcome::default();
    let record = |out: &mut Outcome, kind| {
        out.details
            .push(Disagreement::new(index, kind, &r.ray, h, e));
    };
    if let Some(target) = &r.target {
        out.leak_ray = true;
        let lh = judge::is_leak(&r.ray, h.as_ref(), target.t);
        let le = judge::is_leak(&r.ray, e.as_ref(), target.t);
        out.leaks = [lh, le, judge::is_leak(&r.ray, f.as_ref(), target.t)];
        if lh {
            record(&mut out, DetailKind::LeakHalfray);
            if std::env::var_os("HALFRAY_CROSSCHECK_DEBUG").is_some() {
                crate::note!(
                    "halfray leak: ray {:?} incident {:?} ours {h:?} embree {e:?}",
                    r.ray,
                    target.incident
                );
            }
        }
        if lh != le {
            // A leak is its own category; counted above, not judged again.
            return out;
        }
    }
    let verdict = if h == e {
        Verdict::Agree
    } else {
        judge::judge(&sides.accel.mesh, &r.ray, h, e, |ray| {
            sides.reference.closest(ray)
        })
    };
    if std::env::var_os("HALFRAY_CROSSCHECK_DEBUG").is_some()
        && !matches!(verdict, Verdict::Agree | Verdict::Tie)
    {
        crate::note!("{verdict:?}: ray {:?} ours {h:?} embree {e:?}", r.ray);
    }
    match verdict {
        Verdict::Genuine => record(&mut out, DetailKind::Genuine),
        Verdict::EmbreeWrong => record(&mut out, DetailKind::EmbreeWrong),
        _ => {}
    }
    // Any hit over the same interval. Where the closest hits agree (or tie), the any-hit
    // answers must agree too.
    let any_h = sides.accel.any_variant(sides.variant, &r.ray);
    let any_e = sides.robust.occluded_ray(&r.ray);
    out.any_hit = matches!(verdict, Verdict::Agree | Verdict::Tie) && any_h != any_e;
    out.any_vs_closest = any_h != h.is_some() || any_e != e.is_some();
    if out.any_hit {
        record(&mut out, DetailKind::AnyHit);
    }
    if out.any_vs_closest {
        record(&mut out, DetailKind::AnyVsClosest);
    }
    out.verdict = Some(verdict);
    out
}

/// One side's timed pass over the sampled rays: its answer to each, in order.
type TimedPass<'a> = &'a dyn Fn() -> Vec<Option<Answer>>;

/// One set's row: the single-thread timed passes over `timing_rays` (at least 1, [`check_sizes`]) rays spread
/// evenly over the set ([`spread_positions`], the same rays for every side, so that a camera's
/// empty first rows do not stand for the whole image), then every ray classified on the worker
/// threads. Each side is timed [`TIMED_PASSES`] times, the sides taking turns pass by pass,
/// and its fastest pass is reported (as `bench bvh` does: on a shared machine a slow pass
/// measures the neighbours, and turns give every side the same warm-up). halfray traces the
/// sampled rays as one batch ([`MeshAccel::closest_variant_batch`], the same answers as one by
/// one), Embree one `rtcIntersect1` call a ray.
fn compare_set(sides: &Sides<'_>, rays: &[(usize, SetRay)], timing_rays: usize) -> SetReport {
    let positions = spread_positions(rays.len(), timing_rays);
    let sample = || positions.iter().map(|&j| &rays[j].1.ray);
    let batch: Vec<Ray> = sample().copied().collect();
    // halfray, Embree robust, Embree default.
    let passes: [TimedPass<'_>; 3] = [
        &|| sides.halfray_batch(&batch),
        &|| {
            sample()
                .map(|r| Answer::of_embree(sides.robust, r))
                .collect()
        },
        &|| sample().map(|r| Answer::of_embree(sides.fast, r)).collect(),
    ];
    let mut secs = [f64::INFINITY; 3];
    let mut answers: [Vec<Option<Answer>>; 3] = Default::default();
    for _ in 0..TIMED_PASSES {
        for ((pass, out), best) in passes.iter().zip(&mut answers).zip(&mut secs) {
            let s;
            (*out, s) = timed(pass);
            *best = best.min(s);
        }
    }
    let [ours, emb, emb_fast] = answers;
    let [secs_h, secs_e, secs_f] = secs;
    let outcomes: Vec<Outcome> = rays
        .par_iter()
        .enumerate()
        .map(|(j, (index, r))| {
            let (h, e, f) = if let Ok(k) = positions.binary_search(&j) {
                (ours[k], emb[k], emb_fast[k])
            } else {
                (
                    sides.halfray(&r.ray),
                    Answer::of_embree(sides.robust, &r.ray),
                    Answer::of_embree(sides.fast, &r.ray),
                )
            };
            classify(sides, *index, r, h, e, f)
        })
        .collect();
    let mut row = SetReport {
        rays: rays.len(),
        timed_rays: ours.len(),
        secs_halfray: secs_h,
        secs_embree: secs_e,
        secs_embree_default: secs_f,
        ..SetReport::default()
    };
    row.update_throughput();
    for o in outcomes {
        row.leak_rays += o.leak_ray as usize;
        row.leaks_halfray += o.leaks[0] as usize;
        row.leaks_embree += o.leaks[1] as usize;
        row.leaks_embree_default += o.leaks[2] as usize;
        match o.verdict {
            None => {}
            Some(Verdict::Agree) => row.agree += 1,
            Some(Verdict::Tie) => row.ties += 1,
            Some(Verdict::WithinTolerance) => row.within_tolerance += 1,
            Some(Verdict::EmbreeWrong) => row.embree_wrong += 1,
            Some(Verdict::Genuine) => row.genuine_mismatches += 1,
        }
        row.any_hit_disagreements += o.any_hit as usize;
        row.any_vs_closest_inconsistent += o.any_vs_closest as usize;
        row.disagreements.extend(o.details);
    }
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// How far Embree's `t` of an exact crossing may lie from it, in ulps of `t`: its kernels
    /// differ by ISA (the robust AVX2 kernel returns `0.5 − 2⁻²⁵` for the crossing `0.5` that
    /// the AVX-512 one returns exactly); a few ulps cover the reciprocal-based division.
    const EMBREE_KERNEL_T_ULPS: f32 = 4.0;

    /// Calls `f` with the sides of a cross-check over `accel`: Embree's robust and fast scenes
    /// of `accel.mesh` (its positions as they are now, which may differ from those its tree
    /// was built over), the reference over the same mesh, and the watertight test.
    fn with_sides<R>(accel: &MeshAccel, f: impl FnOnce(&Sides<'_>) -> R) -> R {
        let positions: Vec<[f32; 3]> = accel.mesh.positions.iter().map(|p| p.to_array()).collect();
        let device = EmbreeDevice::new().unwrap();
        let robust = EmbreeScene::new(&device, &positions, &accel.mesh.triangles, true).unwrap();
        let fast = EmbreeScene::new(&device, &positions, &accel.mesh.triangles, false).unwrap();
        let reference = judge::Reference::new(&accel.mesh);
        f(&Sides {
            accel,
            reference: &reference,
            robust: &robust,
            fast: &fast,
            variant: TriangleVariant::Watertight,
        })
    }

    /// A ray straight down onto the interior of a unit quad hits it on every side; given
    /// closest answers of "miss" for both halfray and Embree, both sides' any-hit answers
    /// contradict their closest hits: one ray, counted once.
    #[test]
    fn a_ray_inconsistent_on_both_sides_counts_once() {
        let accel = MeshAccel::new(super::super::judge::tests::quad()).unwrap();
        let r = SetRay {
            ray: Ray::new(Vec3::new(0.7, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0)),
            target: None,
        };
        with_sides(&accel, |sides| {
            let hit = sides.halfray(&r.ray);
            assert!(hit.is_some());
            // Both sides inconsistent, one side inconsistent, neither.
            for (h, e, want) in [(None, None, 1), (None, hit, 1), (hit, hit, 0)] {
                let o = classify(sides, 0, &r, h, e, e);
                assert_eq!(o.any_vs_closest as usize, want, "{h:?} {e:?}");
            }
        });
    }

    /// A traversal that skips a triangle: halfray's BVH is built over a mesh whose triangle 2
    /// lies 100 units along `x` (among 16 others there, so that the tree keeps it in another
    /// leaf than the quad's), then the triangle is moved over the quad
    /// ([`judge::tests::two_floors`]), where the tree's boxes do not reach. A ray straight down
    /// meets it first in Embree, yet halfray hits the quad below: a genuine mismatch, which a
    /// reference walking halfray's tree would have missed too and judged within tolerance.
    #[test]
    fn a_triangle_halfray_s_tree_skips_is_a_genuine_mismatch() {
        let mut moved = super::super::judge::tests::two_floors();
        // The far cluster: eight unit quads at x = 100, 102, …, 114.
        for k in 0..8 {
            let base = moved.positions.len() as u32;
            let x = 100.0 + 2.0 * k as f32;
            moved.positions.extend([
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
                Vec3::new(x + 1.0, 1.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
            ]);
            moved.triangles.push([base, base + 1, base + 2]);
            moved.triangles.push([base, base + 2, base + 3]);
        }
        let mut built = moved.clone();
        for p in &mut built.positions[4..7] {
            p.x += 100.0;
        }
        let mut accel = MeshAccel::new(built).unwrap();
        accel.mesh = moved;
        let r = SetRay {
            ray: Ray::new(Vec3::new(0.7, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0)),
            target: None,
        };
        with_sides(&accel, |sides| {
            let h = sides.halfray(&r.ray);
            let e = Answer::of_embree(sides.robust, &r.ray);
            assert_eq!(h.map(|a| (a.prim, a.t)), Some((0, 1.0)));
            // Embree's `t` of the plane z = 0.5 is 0.5 on its AVX-512 kernels and one ulp
            // below on its AVX2 ones (Zen 3): its kernels round differently.
            let e = e.expect("Embree robust hits the moved triangle");
            assert_eq!(e.prim, 2);
            assert!(
                (e.t - 0.5).abs() <= EMBREE_KERNEL_T_ULPS * f32::EPSILON * 0.5,
                "{e:?}"
            );
            let o = classify(sides, 0, &r, h, Some(e), Some(e));
            assert_eq!(o.verdict, Some(Verdict::Genuine));
        });
    }
}
