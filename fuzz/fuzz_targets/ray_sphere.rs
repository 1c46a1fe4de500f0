//! Fuzz target `ray_sphere`: the property checks are `halfray_fuzz::sphere::ray_sphere` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::sphere::ray_sphere(data));
