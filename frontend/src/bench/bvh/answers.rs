//! The answers `bench bvh` times, checked: every side's hit count on every timed pass
//! ([`Timed::hits`]), and Embree's answers on a sample judged (closest hits against an `f64`
//! reference, occlusions against the watertight test), so that a side answering wrongly (an
//! Embree call that returns at once, answers "occluded" at once or any hit for the nearest, a
//! batch call that fails) fails the run instead of being timed as fast.

use super::BvhReport;
use crate::crosscheck::judge::{self, Verdict};
use crate::error::{Error, Result};
use crate::timing::Timed;
use halfray_core::Ray;

/// Largest difference allowed between an Embree side's hit count and halfray's on one set, as
/// a fraction of the set's rays (rounded down to whole rays: a set under 100 rays allows none).
///
/// Embree's default and robust modes are not watertight, and its default mode's traversal is
/// not conservative, so either may answer a few rays otherwise than halfray's watertight query.
/// The worst cases measured: on rays aimed exactly at shared edges and vertices (the
/// cross-check's `edges` and `vertices` sets, docs/accuracy.md) Embree robust lets 0.37 % of
/// the transversal ones through (Embree default 6.5 %, but no set `bench bvh` times is aimed
/// there); on the sets it times, with this check at zero tolerance, Embree default's
/// `rtcOccluded1` misses 0.21–0.30 % of the generated `far` sphere's shadow rays (coordinates
/// about 2.5·10⁴; `--width` 64 to 1024, robust none), and every other difference on the ten
/// shared meshes and the six generated ones (`--width 512 --rays 500000`, `--width 384 --rays
/// 300000`) is at most 6 rays in 300 000. 1 % is over three times the largest, and small
/// beside what a wrong side gives: a call that answers "miss" at once is off by the set's whole
/// hit rate, which only a set hitting under 1 % of its rays (the cube's `ao`) would not show.
///
/// Each Embree call's count on every timed pass is held to its mode's single-ray call on the
/// first pass ([`Expected::embree`]), and what that call answers is judged on a sample
/// ([`judged_failures`], [`judged_any_failures`], which allow the same share of wrong rays),
/// whatever `--intersector` times: a variant that loses hits (`moller-trumbore`, whose ε loses
/// small triangles) is measured, not taken for Embree's error. A shadow or ambient-occlusion
/// ray that Embree finds occluded by the face it leaves (its rounding cannot tell the origin
/// from that face when the spawn offset is below it: a face in a coordinate plane, whose
/// offset is a subnormal) is judged undecided, not wrong.
pub const EMBREE_HIT_COUNT_TOLERANCE: f64 = 0.01;

/// Rays of a closest-hit set whose answers are judged, untimed ([`judged_failures`]): spread
/// evenly over the set (every ray of a smaller one).
pub const JUDGED_RAYS: usize = 4096;

/// The failures of the closest-hit sides `sides` (each a name and its answer on the judged
/// rays `rays`, [`JUDGED_RAYS`]) against the watertight test's answers `watertight` on the
/// same rays, judged as `crosscheck` judges a disagreement ([`judge::judge`]: a tie at a
/// shared edge, a difference within the `f64` reference's own uncertainty, or one side
/// contradicting the reference over every triangle of `mesh`): one message per side
/// that contradicts the reference ([`Verdict::EmbreeWrong`]) on more of the rays than
/// [`EMBREE_HIT_COUNT_TOLERANCE`] allows, naming the mesh, the set, the side and the count.
/// Hit counts alone ([`count_failures`]) pass a side that answers any hit instead of the
/// nearest, or a hit without its `t`.
#[must_use]
pub fn judged_failures(
    (mesh_name, set): (&str, &str),
    mesh: &crate::obj::ObjMesh,
    (rays, watertight): (&[Ray], &[Option<judge::Answer>]),
    sides: &[(String, Vec<Option<judge::Answer>>)],
) -> Vec<String> {
    let reference = judge::Reference::new(mesh);
    judged(
        (mesh_name, set),
        (rays, watertight),
        sides,
        |ray, w, e: &Option<judge::Answer>| {
            judge::judge(mesh, ray, w, *e, |r| reference.closest(r)) == Verdict::EmbreeWrong
        },
    )
}

/// An Embree side's any-hit answer to one judged ray: whether it occludes the ray and, where
/// that differs from the watertight test's answer, its nearest hit (`rtcIntersect1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Occlusion {
    /// `rtcOccluded1`'s answer.
    pub occluded: bool,
    /// `rtcIntersect1`'s answer where `occluded` differs from the watertight test's, else
    /// `None`.
    pub nearest: Option<judge::Answer>,
}

/// The failures of the any-hit sides `sides` (each a name and its [`Occlusion`]s of the judged
/// rays `rays`, [`JUDGED_RAYS`]) against the watertight test's closest hits `watertight` on
/// the same rays: where a side's occlusion differs, its nearest hit is judged against the
/// watertight test's as [`judged_failures`] judges them (the face a ray leaves, which its
/// rounding cannot tell from the origin, is at the interval's start: undecided), and an
/// occlusion without a nearest hit, or a nearest hit without an occlusion, is wrong. One
/// message per side wrong on more of the rays than [`EMBREE_HIT_COUNT_TOLERANCE`] allows. A
/// call answering "occluded" (or "not") at once fails here.
#[must_use]
pub fn judged_any_failures(
    (mesh_name, set): (&str, &str),
    mesh: &crate::obj::ObjMesh,
    (rays, watertight): (&[Ray], &[Option<judge::Answer>]),
    sides: &[(String, Vec<Occlusion>)],
) -> Vec<String> {
    let reference = judge::Reference::new(mesh);
    judged(
        (mesh_name, set),
        (rays, watertight),
        sides,
        |ray, w, e: &Occlusion| {
            e.occluded != w.is_some()
                && (e.occluded != e.nearest.is_some()
                    || judge::judge(mesh, ray, w, e.nearest, |r| reference.closest(r))
                        == Verdict::EmbreeWrong)
        },
    )
}

/// The failures of the Embree sides `sides` (each a name and its answers to the judged rays
/// `rays`; `watertight`: the watertight test's closest hits of them): one message per side
/// answering `wrong` on more of the rays than [`EMBREE_HIT_COUNT_TOLERANCE`] allows (or not
/// answering every ray), naming the mesh, the set, the side and the count.
fn judged<A>(
    (mesh_name, set): (&str, &str),
    (rays, watertight): (&[Ray], &[Option<judge::Answer>]),
    sides: &[(String, Vec<A>)],
    wrong: impl Fn(&Ray, Option<judge::Answer>, &A) -> bool,
) -> Vec<String> {
    let allowed = allowed_difference(rays.len(), true);
    sides
        .iter()
        .filter_map(|(name, answers)| {
            let n = rays
                .iter()
                .zip(watertight)
                .zip(answers)
                .filter(|((ray, w), e)| wrong(ray, **w, e))
                .count();
            (n > allowed || answers.len() != rays.len()).then(|| {
                format!(
                    "{mesh_name} set {set}: {name} answered {n} of {} judged rays wrongly against the f64 reference, where the watertight test did not (allowed {allowed}: {} % of the rays)",
                    rays.len(),
                    100.0 * EMBREE_HIT_COUNT_TOLERANCE
                )
            })
        })
        .collect()
}

/// The hit counts a set's sides are checked against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Expected {
    /// halfray's sides' count: halfray's closest-hit query with the run's `--intersector`,
    /// which they answer exactly.
    pub halfray: usize,
    /// Embree's sides' count, within [`EMBREE_HIT_COUNT_TOLERANCE`]: the same mode's
    /// single-ray call on its first timed pass (its answers judged apart, [`judged_failures`],
    /// [`judged_any_failures`]: a mesh at the edge of `f32`'s resolution has more rays within
    /// the reference's uncertainty than the tolerance, so the watertight count is no bound).
    pub embree: usize,
    /// Where `embree` comes from, named in a failure's message.
    pub embree_from: &'static str,
}

impl Expected {
    /// Both counts `n` (unit tests).
    #[must_use]
    pub fn same(n: usize) -> Self {
        Self {
            halfray: n,
            embree: n,
            embree_from: "the count",
        }
    }
}

/// How far a side's count may be from the expected one on a set of `rays` rays: 0 for
/// halfray's own timed side (the same query as the count it is checked against), and
/// [`EMBREE_HIT_COUNT_TOLERANCE`] of the rays, rounded down, for an Embree side.
#[must_use]
pub fn allowed_difference(rays: usize, embree: bool) -> usize {
    if embree {
        (rays as f64 * EMBREE_HIT_COUNT_TOLERANCE) as usize
    } else {
        0
    }
}

/// One timed side of a set: its name in messages (`Embree robust rtcOccluded8`), its figures,
/// and whether it is an Embree side ([`allowed_difference`]).
pub struct Side<'a> {
    /// Named in a failure's message.
    pub name: String,
    /// Its throughput and hit counts.
    pub timed: &'a Timed,
    /// An Embree side (allowed [`EMBREE_HIT_COUNT_TOLERANCE`]), not halfray's.
    pub embree: bool,
}

/// A side's hit count to report: the pass's count farthest from `expected` (the first such
/// pass), which is every pass's count for a side whose answers do not change between passes.
#[must_use]
pub fn reported_hits(timed: &Timed, expected: usize) -> usize {
    timed
        .hits
        .iter()
        .copied()
        .reduce(|a, b| {
            if b.abs_diff(expected) > a.abs_diff(expected) {
                b
            } else {
                a
            }
        })
        .unwrap_or(0)
}

/// The failures of `sides` on the set `set` of `mesh` (`rays` rays, of which the sides should
/// hit `expected`): one message per side whose count on some pass differs from its expected
/// count by more than [`allowed_difference`], naming the mesh, the set, the side, the pass and
/// both counts. Empty when every side answers as it should.
#[must_use]
pub fn count_failures(
    mesh: &str,
    set: &str,
    rays: usize,
    expected: Expected,
    sides: &[Side<'_>],
) -> Vec<String> {
    let mut failures = Vec::new();
    for side in sides {
        let allowed = allowed_difference(rays, side.embree);
        let (expected, whose) = if side.embree {
            (expected.embree, expected.embree_from)
        } else {
            (expected.halfray, "halfray's closest-hit query")
        };
        let bad = side
            .timed
            .hits
            .iter()
            .enumerate()
            .find(|(_, h)| h.abs_diff(expected) > allowed);
        if let Some((pass, &got)) = bad {
            failures.push(format!(
                "{mesh} set {set}: {} hit {got} of {rays} rays on timed pass {}, {whose} {expected} (allowed difference {allowed}{})",
                side.name,
                pass + 1,
                if side.embree {
                    format!(": {} % of the rays", 100.0 * EMBREE_HIT_COUNT_TOLERANCE)
                } else {
                    String::new()
                }
            ));
        }
    }
    failures
}

/// The failure of `report`'s brute-force check, naming its mesh: any sample ray on which the
/// wide BVH, the binary BVH and brute force do not all agree
/// ([`BvhReport::brute_force_mismatches`], which must be 0 for the watertight test). Only the
/// watertight test promises a tree's answer equal to brute force's (`halfray_core::query`):
/// another `--intersector`'s mismatches are reported, not failed (`watertight-f32`'s `t` on a
/// grazing hit may lie beyond the tree's cull slack).
#[must_use]
pub fn brute_force_failure(report: &BvhReport) -> Option<String> {
    let m = report.brute_force_mismatches;
    let promised = report.intersector == halfray_core::triangle::TriangleVariant::Watertight.name();
    (m > 0 && promised).then(|| {
        format!(
            "{}: the wide BVH, the binary BVH and brute force disagree on {m} of {} sample rays (must be 0)",
            crate::text::escaped(&report.mesh),
            report.brute_force_rays
        )
    })
}

/// The run's status once its outputs are written: `Ok` when no check failed, else
/// [`Error::Mismatch`] (exit 3) listing every failure, one a line.
///
/// # Errors
///
/// As said, when `failures` is not empty.
pub fn verdict(failures: &[String]) -> Result<()> {
    if failures.is_empty() {
        return Ok(());
    }
    Err(Error::Mismatch(format!(
        "the answers timed failed {} check{} (the outputs are written; their figures time wrong answers):\n  {}",
        failures.len(),
        if failures.len() == 1 { "" } else { "s" },
        failures.join("\n  ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timing::TIMED_PASSES;

    /// A brute-force mismatch is a failure naming the mesh; none is none; any failure makes
    /// the run's status a mismatch (exit 3) listing every one.
    #[test]
    fn a_brute_force_mismatch_fails_the_run_with_exit_3() {
        let mut r = super::super::summary::tests::report("m.obj", &[]);
        assert_eq!(brute_force_failure(&r), None);
        (r.brute_force_mismatches, r.brute_force_rays) = (2, 100);
        let f = brute_force_failure(&r).unwrap();
        assert_eq!(
            f,
            "dir/m.obj: the wide BVH, the binary BVH and brute force disagree on 2 of 100 sample rays (must be 0)"
        );
        // Only the watertight test promises brute force's answers: another variant's
        // mismatches are reported in the JSON, not failed.
        let other = BvhReport {
            intersector: "watertight-f32".into(),
            ..r.clone()
        };
        assert_eq!(brute_force_failure(&other), None);
        assert!(verdict(&[]).is_ok());
        let e = verdict(&[f.clone(), "x set s: y".into()]).unwrap_err();
        assert_eq!(e.exit_code(), 3, "docs/bad-input.md: 3 mismatches");
        let msg = e.to_string();
        assert!(
            msg.starts_with("the answers timed failed 2 checks"),
            "{msg}"
        );
        assert!(msg.ends_with(&format!("\n  {f}\n  x set s: y")), "{msg}");
    }

    fn timed(hits: [usize; TIMED_PASSES]) -> Timed {
        Timed { mrays: 1.0, hits }
    }

    /// An Embree side that answers "miss" at once (0 hits where halfray hits 400 of 1000) fails
    /// with a message naming mesh, set and side; one within the tolerance passes; halfray's own
    /// side may not differ at all.
    #[test]
    fn a_side_whose_count_differs_fails_naming_mesh_set_and_side() {
        let right = timed([400; TIMED_PASSES]);
        let wrong = timed([0; TIMED_PASSES]);
        let ok = count_failures(
            "m.obj",
            "shadow",
            1000,
            Expected::same(400),
            &[
                Side {
                    name: "halfray".into(),
                    timed: &right,
                    embree: false,
                },
                Side {
                    name: "Embree default rtcOccluded1".into(),
                    timed: &right,
                    embree: true,
                },
            ],
        );
        assert!(ok.is_empty(), "{ok:?}");
        let failures = count_failures(
            "m.obj",
            "shadow",
            1000,
            Expected::same(400),
            &[Side {
                name: "Embree default rtcOccluded1".into(),
                timed: &wrong,
                embree: true,
            }],
        );
        assert_eq!(
            failures,
            [
                "m.obj set shadow: Embree default rtcOccluded1 hit 0 of 1000 rays on timed pass 1, the count 400 (allowed difference 10: 1 % of the rays)"
            ]
        );
        // 20 000 rays allow 200 rays' difference to Embree, none to halfray.
        let failures_off_by = |d: usize, embree: bool| {
            let t = timed([400 + d; TIMED_PASSES]);
            let side = Side {
                name: "side".into(),
                timed: &t,
                embree,
            };
            count_failures("m", "s", 20_000, Expected::same(400), &[side]).len()
        };
        assert_eq!(failures_off_by(200, true), 0);
        assert_eq!(failures_off_by(201, true), 1);
        assert_eq!(failures_off_by(1, false), 1);
    }

    /// A side answering another hit than the nearest (its hit count right), or a hit without
    /// its `t`, contradicts the `f64` reference and fails, naming mesh, set and side; the
    /// nearest hit with Embree's rounding of `t` passes; 1 % of the judged rays may be wrong.
    /// Two parallel unit squares at `z = 0` and `z = 1`, rays straight down from `z = 2`.
    #[test]
    fn a_side_answering_another_hit_than_the_nearest_fails_the_judged_check() {
        let mesh = crate::obj::parse_obj(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
             f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n",
            std::path::Path::new("squares.obj"),
        )
        .unwrap();
        let rays: Vec<Ray> = (0..200)
            .map(|i| {
                let (x, y) = (0.1 + 0.004 * i as f32, 0.3);
                Ray::new(halfray_core::Vec3::new(x, y, 2.0), -halfray_core::Vec3::Z)
            })
            .collect();
        // The nearest face is the top square's lower-right triangle (2: x > y) or its
        // upper-left one (3), at t = 1; the bottom square's at t = 2.
        let hit = |r: &Ray, t: f32, base: u32| {
            let prim = base + u32::from(r.origin.x <= r.origin.y);
            Some(judge::Answer {
                prim,
                t,
                u: 0.0,
                v: 0.0,
            })
        };
        let w: Vec<_> = rays.iter().map(|r| hit(r, 1.0, 2)).collect();
        let rounded: Vec<_> = rays.iter().map(|r| hit(r, 1.0 + 1e-7, 2)).collect();
        let farther: Vec<_> = rays.iter().map(|r| hit(r, 2.0, 0)).collect();
        let unwritten: Vec<_> = rays.iter().map(|r| hit(r, f32::INFINITY, 2)).collect();
        let mut two_off = w.clone();
        (two_off[0], two_off[1]) = (None, farther[1]);
        let mut three_off = two_off.clone();
        three_off[2] = None;
        let check = |answers: &Vec<Option<judge::Answer>>| {
            let sides = [("Embree robust rtcIntersect1".to_string(), answers.clone())];
            judged_failures(("m", "random"), &mesh, (&rays, &w), &sides)
        };
        assert!(check(&rounded).is_empty(), "{:?}", check(&rounded));
        assert!(check(&two_off).is_empty(), "{:?}", check(&two_off));
        assert_eq!(
            check(&three_off),
            [
                "m set random: Embree robust rtcIntersect1 answered 3 of 200 judged rays wrongly against the f64 reference, where the watertight test did not (allowed 2: 1 % of the rays)"
            ]
        );
        assert_eq!(check(&farther).len(), 1);
        assert_eq!(check(&unwritten).len(), 1);
    }

    /// A count wrong on one pass only is found, on that pass, and is the count reported.
    #[test]
    fn a_count_wrong_on_one_pass_is_found() {
        let mut hits = [7; TIMED_PASSES];
        hits[TIMED_PASSES - 1] = 3;
        let t = timed(hits);
        assert_eq!(reported_hits(&t, 7), 3);
        assert_eq!(reported_hits(&timed([7; TIMED_PASSES]), 7), 7);
        let failures = count_failures(
            "m",
            "random",
            10,
            Expected::same(7),
            &[Side {
                name: "halfray".into(),
                timed: &t,
                embree: false,
            }],
        );
        assert_eq!(failures.len(), 1);
        let want = format!("on timed pass {TIMED_PASSES},");
        assert!(failures[0].contains(&want), "{failures:?}");
    }

    /// With an intersector that loses hits, Embree is checked against the watertight count
    /// and halfray's side against its own: neither fails for the other's count.
    #[test]
    fn halfray_and_embree_sides_are_held_to_their_own_counts() {
        let lossy = timed([300; TIMED_PASSES]);
        let embree = timed([400; TIMED_PASSES]);
        let expected = Expected {
            halfray: 300,
            embree: 400,
            embree_from: "the watertight test's closest-hit query",
        };
        let sides = |h: &'static str, e: &'static str| {
            [
                Side {
                    name: h.into(),
                    timed: &lossy,
                    embree: false,
                },
                Side {
                    name: e.into(),
                    timed: &embree,
                    embree: true,
                },
            ]
        };
        assert!(count_failures("m", "s", 1000, expected, &sides("h", "e")).is_empty());
        let failures = count_failures("m", "s", 1000, Expected::same(300), &sides("h", "e"));
        assert_eq!(failures.len(), 1, "{failures:?}");
        assert!(failures[0].contains(": e hit 400"), "{failures:?}");
    }
}
