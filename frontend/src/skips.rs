//! A test's skip, recorded where CI prints it: tests that cannot run part of their checks on
//! the machine they run on (no AVX2, no `/dev/full`) say so here instead of passing silently.

use std::io::Write;

/// Writes `line` (`SKIPPED <crate> <test>: <why>`) to stderr and appends it to the file
/// `HALFRAY_SKIP_LOG` names, when set (`scripts/test-all.sh` prints that file after the tests,
/// so CI names every skipped test and why). A log that cannot be opened or written loses the
/// line there only; stderr still has it.
#[allow(clippy::print_stderr)]
pub fn record_skip(line: &str) {
    eprintln!("{line}");
    if let Some(path) = std::env::var_os("HALFRAY_SKIP_LOG")
        && let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
    {
        let _ = writeln!(f, "{line}");
    }
}
