//! Fuzz target `planted` (test-only): panics on exactly one input, the planted seed
//! `corpus/planted-crash`, and accepts every other. CI's cluster stage fuzzes it next to real
//! targets and checks that the merge job reports that input as a finding of this target.
#![no_main]

/// The one crashing input (the content of `corpus/planted-crash`).
const PLANTED: &[u8] = b"halfray planted finding\n";

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    assert!(data != PLANTED, "the planted crashing input");
});
