//! Fuzz target `ray_quadric`: the property checks are `halfray_fuzz_props::quadric::ray_quadric` in the `halfray-fuzz-props` crate (`tests/fuzz-props`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz_props::quadric::ray_quadric(data));
