//! Fuzz target `ray_triangle`: the property checks are `halfray_fuzz_props::ray_triangle` in the `halfray-fuzz-props` crate (`tests/fuzz-props`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz_props::ray_triangle(data));
