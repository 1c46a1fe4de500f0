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

#[cfg(test)]
mod tests {
    use super::*;

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
