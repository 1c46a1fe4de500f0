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

/// One side's figures from [`interleaved`] or [`interleaved_batches`].
#[derive(Debug, Clone, PartialEq)]
pub struct Timed {
    /// Best-of-[`TIMED_PASSES`] throughput, Mrays/s; 0 for no rays.
    pub mrays: f64,
    /// The side's hit count on each pass, in pass order: the same on every pass for a side
    /// whose answers are deterministic, so that a caller can check the answers it timed.
    pub hits: [usize; TIMED_PASSES],
}

/// Best-of-[`TIMED_PASSES`] throughputs (Mrays/s) of each of `fs` over `rays`, the passes taken
/// round-robin (pass 1 of every function, then pass 2, …), so that a slow spell of a shared
/// machine falls on every side rather than on whichever ran then, with each side's hit count
/// on every pass ([`Timed`]). Each function answers hit or miss. An empty `rays` gives 0
/// Mrays/s and 0 hits for every side.
pub fn interleaved(rays: &[Ray], fs: &[&dyn Fn(&Ray) -> bool]) -> Vec<Timed> {
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
/// API): each function answers the number of hits in `rays`, which is that side's count for
/// the pass ([`Timed::hits`]).
pub fn interleaved_batches(rays: &[Ray], fs: &[BatchSide<'_>]) -> Vec<Timed> {
    let mut best = vec![f64::INFINITY; fs.len()];
    let mut hits = vec![[0; TIMED_PASSES]; fs.len()];
    for pass in 0..TIMED_PASSES {
        for ((f, b), h) in fs.iter().zip(best.iter_mut()).zip(hits.iter_mut()) {
            let t0 = Instant::now();
            h[pass] = f(std::hint::black_box(rays));
            *b = b.min(t0.elapsed().as_secs_f64());
        }
    }
    best.iter()
        .zip(hits)
        .map(|(&s, hits)| Timed {
            mrays: mrays_per_second(rays.len() as u64, s),
            hits,
        })
        .collect()
}

/// The positions of `n` rays spread evenly over a set of `len`: `⌊i·len/n⌋` for
/// `i < min(n, len)`, strictly increasing; every position when `n ≥ len`, none when `n` or
/// `len` is 0. The rays a timed pass or an untimed check takes from a larger set, so that a
/// camera's empty first rows do not stand for the whole image.
#[must_use]
pub fn spread_positions(len: usize, n: usize) -> Vec<usize> {
    let n = n.min(len);
    (0..n)
        .map(|i| (i as u128 * len as u128 / n as u128) as usize)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use halfray_core::Vec3;

    /// Worked by hand: 4 of 10 rays are 0, 2, 5, 7 (`⌊10i/4⌋`); 1500 of 2000 are 1500
    /// distinct positions, not every second ray (1000); a set no larger than `n` is timed
    /// whole; nothing of an empty set.
    #[test]
    fn the_timed_rays_are_n_evenly_spaced_positions() {
        assert_eq!(spread_positions(10, 4), [0, 2, 5, 7]);
        assert_eq!(spread_positions(10, 1), [0]);
        assert_eq!(spread_positions(3, 5), [0, 1, 2]);
        assert_eq!(spread_positions(4, 4), [0, 1, 2, 3]);
        assert!(spread_positions(0, 5).is_empty());
        let p = spread_positions(2000, 1500);
        assert_eq!(p.len(), 1500);
        assert!(p.windows(2).all(|w| w[0] < w[1]) && p[1499] < 2000);
        // ⌊4i/3⌋: 0, 1, 2, 4, 5, 6, 8, … (every position but 3, 7, 11, …).
        assert_eq!(&p[..7], [0, 1, 2, 4, 5, 6, 8]);
    }

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
        assert!(m.iter().all(|x| x.mrays > 0.0));
        assert_eq!([calls[0].get(), calls[1].get()], [10 * TIMED_PASSES; 2]);
        assert_eq!(
            interleaved(&[], &[&a]),
            vec![Timed {
                mrays: 0.0,
                hits: [0; TIMED_PASSES]
            }]
        );
    }

    /// Each side's count on each pass is what it answered on that pass, in pass order: a
    /// side whose answers change between passes shows it.
    #[test]
    fn each_side_s_hit_count_is_kept_per_pass() {
        let rays = vec![Ray::new(Vec3::ZERO, Vec3::X); 10];
        let every_other = std::cell::Cell::new(false);
        let a = |_: &Ray| {
            every_other.set(!every_other.get());
            every_other.get()
        };
        let none = |_: &Ray| false;
        let m = interleaved(&rays, &[&a, &none]);
        assert_eq!(m[0].hits, [5; TIMED_PASSES]);
        assert_eq!(m[1].hits, [0; TIMED_PASSES]);
        let pass = std::cell::Cell::new(0);
        let growing = |rays: &[Ray]| {
            pass.set(pass.get() + 1);
            rays.len() + pass.get()
        };
        let m = interleaved_batches(&rays, &[&growing]);
        assert_eq!(m[0].hits, std::array::from_fn(|k| 11 + k));
    }
}
