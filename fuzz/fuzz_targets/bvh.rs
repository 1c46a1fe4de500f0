//! Fuzz target `bvh`: the property checks are `halfray_fuzz::bvh::bvh` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::bvh::bvh(data));
