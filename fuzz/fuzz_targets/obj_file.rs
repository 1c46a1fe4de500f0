//! Fuzz target `obj_file`: the property checks are `halfray_fuzz::obj_file` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::obj_file(data));
