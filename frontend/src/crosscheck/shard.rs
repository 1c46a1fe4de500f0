//! `--shard K/N`: a deterministic 1/N of every ray set, chosen by ray index.
//!
//! Shard `K` of `N` (`0 ≤ K < N`, zero-based like a Slurm array index or a Kubernetes
//! `JOB_COMPLETION_INDEX`) takes the rays whose index in the generated set is `≡ K (mod N)`.
//! The sets are generated in full on every shard from the same seed before the selection, so
//! the shards of one `N` partition the unsharded run ray for ray: every ray is in exactly one
//! shard, with the same index, whatever `N` is.

use std::fmt;
use std::str::FromStr;

/// One shard of a run: `index` of `count`. Read back from JSON through the same check as
/// `--shard` (`index < count`): `{"index": 0, "count": 0}` or `7/1` is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "ShardFields")]
pub struct Shard {
    /// Zero-based shard index, `< count`.
    pub index: usize,
    /// Number of shards, `≥ 1`.
    pub count: usize,
}

/// A shard as written, before [`Shard::new`] checks it.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ShardFields {
    index: usize,
    count: usize,
}

impl TryFrom<ShardFields> for Shard {
    type Error = String;

    fn try_from(f: ShardFields) -> Result<Self, String> {
        Self::new(f.index, f.count).ok_or_else(|| {
            format!(
                "shard {}/{}: the index must be below the count (shards are 0/N .. N-1/N, N ≥ 1)",
                f.index, f.count
            )
        })
    }
}

impl Shard {
    /// The whole run (shard 0 of 1).
    pub const WHOLE: Self = Self { index: 0, count: 1 };

    /// Shard `index` of `count`; `None` unless `index < count`.
    pub fn new(index: usize, count: usize) -> Option<Self> {
        (index < count).then_some(Self { index, count })
    }

    /// `true` when the ray at `ray_index` (its index in the generated set) is in this shard.
    pub fn contains(&self, ray_index: usize) -> bool {
        ray_index % self.count == self.index
    }

    /// This shard's items with their indices in `items`, in order.
    pub fn select<T>(&self, items: Vec<T>) -> Vec<(usize, T)> {
        items
            .into_iter()
            .enumerate()
            .filter(|(i, _)| self.contains(*i))
            .collect()
    }
}

impl Default for Shard {
    fn default() -> Self {
        Self::WHOLE
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// Parses `K/N` with `0 ≤ K < N`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}` is not K/N (for example 0/4)"))?;
        let parse = |x: &str, what: &str| {
            x.trim().parse::<usize>().map_err(|e| match e.kind() {
                std::num::IntErrorKind::PosOverflow => {
                    format!("`{s}`: {what} `{x}` is too large (at most {})", usize::MAX)
                }
                _ => format!("`{s}`: {what} `{x}` is not a non-negative integer"),
            })
        };
        let (k, n) = (parse(k, "K")?, parse(n, "N")?);
        Self::new(k, n).ok_or_else(|| match n {
            0 => format!("`{s}`: N must be at least 1 (one shard: 0/1)"),
            _ => format!(
                "`{s}`: K must be in 0..N (shards are zero-based: 0/{n} .. {}/{n})",
                n - 1
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_rays_exactly() {
        let len = 1000;
        for n in [1, 2, 3, 7] {
            // How many shards hold each ray index: exactly one, with the index unchanged.
            let mut seen = vec![0usize; len];
            let mut total = 0;
            for k in 0..n {
                let shard = Shard::new(k, n).unwrap();
                let items: Vec<usize> = (0..len).map(|i| i * 10).collect();
                for (i, item) in shard.select(items) {
                    assert_eq!(item, i * 10, "shard {shard} keeps each ray's index");
                    seen[i] += 1;
                    total += 1;
                }
            }
            assert_eq!(total, len, "N = {n}: shard sizes sum to the set size");
            assert!(
                seen.iter().all(|&c| c == 1),
                "N = {n}: a ray twice or missing"
            );
        }
    }

    #[test]
    fn shard_sizes_differ_by_at_most_one() {
        for n in [2, 3, 7] {
            let sizes: Vec<usize> = (0..n)
                .map(|k| Shard::new(k, n).unwrap().select(vec![(); 100]).len())
                .collect();
            let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            assert!(hi - lo <= 1, "N = {n}: {sizes:?}");
        }
    }

    #[test]
    fn parses_k_of_n_and_refuses_the_rest() {
        assert_eq!("0/1".parse(), Ok(Shard::WHOLE));
        assert_eq!("3/4".parse(), Ok(Shard { index: 3, count: 4 }));
        assert_eq!(" 2 / 7 ".parse(), Ok(Shard { index: 2, count: 7 }));
        for bad in ["4/4", "1/0", "0/0", "-1/4", "1", "a/2", "1/b", ""] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert!(e.contains(&format!("`{bad}`")), "{bad}: {e}");
        }
        assert_eq!(Shard::new(2, 5).unwrap().to_string(), "2/5");
        // The message names the shards there are: none of `0/0 .. 0/0` for N = 0.
        for (bad, want) in [
            ("0/0", "N must be at least 1"),
            ("1/0", "N must be at least 1"),
            ("4/4", "0/4 .. 3/4"),
            // A number, but beyond 64 bits: said so, not "not a non-negative integer".
            (
                "0/18446744073709551616",
                "N `18446744073709551616` is too large (at most 18446744073709551615)",
            ),
            ("-1/4", "K `-1` is not a non-negative integer"),
        ] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert!(e.contains(want), "{bad}: {e}");
        }
    }
}
