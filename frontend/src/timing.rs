//! Timing shared by `bench bvh`, `bench accuracy` and `crosscheck`: how many passes a
//! throughput figure is the best of, the round-robin passes that compare several sides on the
//! same rays, the median of timed passes, and rates per second and per million.

use halfray_core::Ray;
use std::time::Instant;

/// Timed passes per measurement; the best is reported, so that one preemption of a pass (a
/// few milliseconds for 100 000 camera rays) does not spoil a figure on a shared machine.
pub const TIMED_PASSES: usize = 5;

/// Throughput in millions of rays per second: `rays / secs / 10⁶`; 0 when `secs` is not
/// positive (nothing was timed). Every Mrays/s figure the tool prints is this.
#[must_use]
pub fn mrays_per_second(rays: u64, secs: f64) -> f64 {
    if secs > 0.0 {
        rays as f64 / secs / 1e6
    } else {
        0.0
    }
}

/// The upper median of `values`: the one at index `len / 2` once sorted by
/// [`f64::total_cmp`] (the larger of the two middle ones for an even count); 0 for no values.
#[must_use]
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(0.0)
}

/// The [`median`] of `reps` values of `pass`, called one after the other (each call one timed
/// pass, answering its figure); 0 when `reps` is 0.
pub fn median_of(reps: usize, mut pass: impl FnMut() -> f64) -> f64 {
    median((0..reps).map(|_| pass()).collect())
}

/// `count` per million of `of`: `count · 10⁶ / of`; 0 when `of` is 0 (nothing was tried).
#[must_use]
pub fn per_million(count: usize, of: usize) -> f64 {
    if of == 0 {
        0.0
    } else {
        count as f64 * 1.0e6 / of as f64
    }
}

/// A side timed on a whole set at once: answers the number of hits in the rays.
pub type BatchSide<'a> = &'a dyn Fn(&[Ray]) -> usize;

/// A [`BatchSide`] owned.
pub type OwnedBatchSide<'a> = Box<dyn Fn(&[Ray]) -> usize + 'a>;

/// Best-of-[`TIMED_PASSES`] throughputs (Mrays/s) of each of `fs` over `rays`, the passes taken
/// round-robin (pass 1 of every function, then pass 2, …), so that a slow spell of a shared
/// machine falls on every side rather than on whichever ran then. Each function answers hit or
/// miss; the answers are kept alive with [`std::hint::black_box`] and otherwise unused. An empty
/// `rays` gives 0 for every side.
pub fn interleaved(rays: &[Ray], fs: &[&dyn Fn(&Ray) -> bool]) -> Vec<f64> {
    let each: Vec<OwnedBatchSide<'_>> = fs
        .iter()
        .map(|f| {
            Box::new(move |rays: &[Ray]| rays.iter().filter(|r| f(std::hint::black_box(r))).count())
                as OwnedBatchSide<'_>
        })
        .collect();
    let sides: Vec<BatchSide<'_>> = each.iter().map(|f| f.as_ref()).collect();
    interleaved_batches(rays, &sides)
}

/// [`interleaved`] for sides that take the whole set at once (ray batches, Embree's packet
/// API): each function answers the number of hits in `rays`.
pub fn interleaved_batches(rays: &[Ray], fs: &[BatchSide<'_>]) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; fs.len()];
    for _ in 0..TIMED_PASSES {
        for (f, b) in fs.iter().zip(best.iter_mut()) {
            let t0 = Instant::now();
            let hits = f(std::hint::black_box(rays));
            std::hint::black_box(hits);
            *b = b.min(t0.elapsed().as_secs_f64());
        }
    }
    best.iter()
        .map(|&s| mrays_per_second(rays.len() as u64, s))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use halfray_core::Vec3;

    #[test]
    fn mrays_per_second_is_rays_over_seconds_in_millions() {
        assert_eq!(mrays_per_second(2_000_000, 0.5), 4.0);
        assert_eq!(mrays_per_second(3, 1.5e-6), 2.0);
        assert_eq!(mrays_per_second(0, 1.0), 0.0);
        assert_eq!(mrays_per_second(5, 0.0), 0.0);
    }

    #[test]
    fn the_median_is_the_upper_middle_value_and_0_for_none() {
        assert_eq!(median(vec![]), 0.0);
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), 3.0);
        let mut next = [5.0, 9.0, 7.0].into_iter();
        assert_eq!(median_of(3, || next.next().unwrap()), 7.0);
        assert_eq!(median_of(0, || unreachable!()), 0.0);
        assert_eq!(per_million(3, 4), 750_000.0);
        assert_eq!(per_million(3, 0), 0.0);
    }

    #[test]
    fn every_side_is_called_once_per_ray_and_pass() {
        let rays = vec![Ray::new(Vec3::ZERO, Vec3::X); 10];
        let calls = [std::cell::Cell::new(0), std::cell::Cell::new(0)];
        let a = |_: &Ray| {
            calls[0].set(calls[0].get() + 1);
            true
        };
        let b = |_: &Ray| {
            calls[1].set(calls[1].get() + 1);
            false
        };
        let m = interleaved(&rays, &[&a, &b]);
        assert_eq!(m.len(), 2);
        assert!(m.iter().all(|x| *x > 0.0));
        assert_eq!([calls[0].get(), calls[1].get()], [10 * TIMED_PASSES; 2]);
        assert_eq!(interleaved(&[], &[&a]), vec![0.0]);
    }
}
