//! Fuzz target `ray_triangle`: the property checks are `halfray_fuzz::ray_triangle` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::ray_triangle(data));
