//! Fuzz target `halfedge_ops`: the property checks are `halfray_fuzz::halfedge::halfedge_ops` in `fuzz/src/lib.rs`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| halfray_fuzz::halfedge::halfedge_ops(data));
