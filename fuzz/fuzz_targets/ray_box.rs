//! Fuzz target `ray_box`: the property checks are `halfray_fuzz::ray_box` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::ray_box(data));
