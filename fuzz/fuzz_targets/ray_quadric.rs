//! Fuzz target `ray_quadric`: the property checks are `halfray_fuzz::quadric::ray_quadric` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::quadric::ray_quadric(data));
