//! Fuzz target `kdtree`: the property checks are `halfray_fuzz_props::kdtree` in the `halfray-fuzz-props` crate (`tests/fuzz-props`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz_props::kdtree::kdtree(data));
