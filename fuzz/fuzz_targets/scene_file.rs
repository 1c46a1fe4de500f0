//! Fuzz target `scene_file`: the property checks are `halfray_fuzz::scene::scene_file` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::scene::scene_file(data));
