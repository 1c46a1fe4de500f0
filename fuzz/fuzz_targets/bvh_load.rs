//! Fuzz target `bvh_load`: the property checks are `halfray_fuzz::bvh_load::bvh_load` in
//! `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::bvh_load::bvh_load(data));
