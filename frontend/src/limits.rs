//! Memory limits: sizes computed from input are estimated (with checked arithmetic) before
//! anything is allocated, and refused with a message naming the option and the estimate.

use crate::error::{Error, Result};

/// Most memory one command may plan to allocate for its main buffers: 4 GiB, the smallest
/// machine halfray is meant to run on (a larger request would abort there rather than fail
/// with a message).
pub const MEMORY_LIMIT_BYTES: u64 = 4 << 30;

/// Largest input file read whole (scene, OBJ, mesh list, cross-check part): 1 GiB, 30 times
/// the largest mesh of the shared corpus (the 33 MB dragon), far below the memory limit the
/// parsed data also needs room in. Also what stops a read from a pipe that never ends.
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Refuses `bytes` (`None`: the size computation overflowed) above [`MEMORY_LIMIT_BYTES`],
/// as a usage error naming `what` (the options that set the size and their values).
pub fn check_memory(what: &str, bytes: Option<u64>) -> Result<()> {
    check_memory_within(what, bytes, MEMORY_LIMIT_BYTES)
}

/// [`check_memory`] against `limit` bytes (the memory limit, or a smaller one in tests).
pub fn check_memory_within(what: &str, bytes: Option<u64>, limit: u64) -> Result<()> {
    const GIB: u64 = 1 << 30;
    match bytes {
        Some(b) if b <= limit => Ok(()),
        // A whole number of GiB (the memory limit) in GiB; another limit (a test's) in bytes.
        Some(b) if limit.is_multiple_of(GIB) => Err(Error::Usage(format!(
            "{what} needs about {:.1} GiB, more than the {} GiB limit",
            b as f64 / GIB as f64,
            limit / GIB
        ))),
        Some(b) => Err(Error::Usage(format!(
            "{what} needs {b} bytes, more than the {limit}-byte limit"
        ))),
        None => Err(Error::Usage(format!(
            "{what} is too large: its size does not fit in 64 bits"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_above_the_limit_or_overflowing_are_refused() {
        assert!(check_memory("x", Some(MEMORY_LIMIT_BYTES)).is_ok());
        let e = check_memory("--width 9 --height 9", Some(MEMORY_LIMIT_BYTES + 1))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("--width 9 --height 9 needs about 4.0 GiB"),
            "{e}"
        );
        let e = check_memory("--levels 40", None).unwrap_err().to_string();
        assert!(e.contains("does not fit"), "{e}");
    }
}
