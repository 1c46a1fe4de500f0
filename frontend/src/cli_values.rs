//! Command-line values shared by several subcommands, as clap `ValueEnum`s so that clap
//! checks them and generates their help from the core's own list.

use clap::ValueEnum;
use clap::builder::PossibleValue;
use halfray_core::triangle::TriangleVariant;

/// A triangle intersector by its core name (`--intersector`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Intersector(pub TriangleVariant);

/// Every intersector the core has, in its order.
const ALL: [Intersector; TriangleVariant::ALL.len()] = {
    let mut out = [Intersector(TriangleVariant::Watertight); TriangleVariant::ALL.len()];
    let mut i = 0;
    while i < out.len() {
        out[i] = Intersector(TriangleVariant::ALL[i]);
        i += 1;
    }
    out
};

impl ValueEnum for Intersector {
    fn value_variants<'a>() -> &'a [Self] {
        &ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()))
    }
}

impl Default for Intersector {
    fn default() -> Self {
        Self(TriangleVariant::Watertight)
    }
}

impl std::fmt::Display for Intersector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.name())
    }
}

/// A finite `f32` option value (clap `value_parser`): a number `f32` cannot hold (`1e39`) is
/// refused as written, with `f32`'s range, rather than read as infinity and reported as `inf`;
/// so is a non-zero number that rounds to zero (`1e-46`), rather than read and reported as
/// `0`; NaN and infinities are refused too.
///
/// # Errors
///
/// The message clap shows after the option's name.
pub fn finite_f32(s: &str) -> Result<f32, String> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    let y = x as f32;
    if !x.is_finite() {
        return Err(format!("`{s}` is not a finite number"));
    }
    if !y.is_finite() {
        return Err(format!("`{s}` is beyond the largest `f32` (±3.4e38)"));
    }
    if y == 0.0 && x != 0.0 {
        return Err(format!(
            "`{s}` is nearer zero than the smallest `f32` (±1.4e-45) and would be read as 0"
        ));
    }
    Ok(y)
}

/// Refuses a `--sets` list that names a set twice: it would be traced, counted and reported
/// twice (and a cross-check's mismatches summed twice against `--max-mismatch`). A usage error
/// naming the first set repeated.
pub fn refuse_repeated_sets<T: PartialEq + std::fmt::Display>(sets: &[T]) -> crate::Result<()> {
    match sets
        .iter()
        .enumerate()
        .find(|&(i, s)| sets[..i].contains(s))
    {
        Some((_, s)) => Err(crate::Error::Usage(format!(
            "--sets names `{s}` twice: each set is traced once"
        ))),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Finite `f32` values parse to themselves; a finite number beyond `f32` is refused as
    /// written (not echoed as `inf`), as are NaN, infinities and text.
    #[test]
    fn finite_f32_takes_what_f32_holds() {
        assert_eq!(finite_f32("0.5"), Ok(0.5));
        assert_eq!(finite_f32(" -3e38 "), Ok(-3e38));
        assert_eq!(finite_f32("1.4e-45"), Ok(f32::from_bits(1)));
        assert_eq!(finite_f32("-0"), Ok(-0.0));
        for (bad, why) in [
            ("1e-50", "`1e-50` is nearer zero than the smallest `f32`"),
            ("-1e-46", "`-1e-46` is nearer zero"),
            ("1e39", "`1e39` is beyond the largest `f32`"),
            ("-4e38", "`-4e38` is beyond the largest `f32`"),
            ("nan", "not a finite number"),
            ("-inf", "not a finite number"),
            ("1e999", "not a finite number"),
            ("abc", "`abc` is not a number"),
        ] {
            let e = finite_f32(bad).unwrap_err();
            assert!(e.contains(why), "{bad}: {e}");
        }
    }

    #[test]
    fn every_core_intersector_is_a_value_and_parses_back() {
        assert_eq!(
            Intersector::value_variants().len(),
            TriangleVariant::ALL.len()
        );
        for v in TriangleVariant::ALL {
            assert_eq!(Intersector::from_str(v.name(), false), Ok(Intersector(v)));
        }
        assert!(Intersector::from_str("mollertrumbore", false).is_err());
    }
}
