//! The worker threads: rayon's global pool, built by `main` with a bounded thread count
//! instead of lazily by rayon (which panics when `RAYON_NUM_THREADS` asks for more threads
//! than the system gives).

use crate::error::{Error, Result};

/// Most worker threads a run may ask for with `RAYON_NUM_THREADS`: 1024. More threads than
/// hardware threads only add scheduling and per-thread memory (each has a stack); 1024 is
/// above the hardware threads of any machine halfray targets and far below where thread
/// creation starts failing (the kernel's `threads-max`, per-user limits).
pub const MAX_WORKER_THREADS: usize = 1024;

/// The thread count `RAYON_NUM_THREADS` asks for: `None` when unset, empty or `0` (rayon's
/// own default then: one per hardware thread); a usage error when it is not a whole number
/// (rayon would ignore it silently) or above [`MAX_WORKER_THREADS`]. Surrounding spaces are
/// ignored.
pub fn requested_threads(value: Option<&str>) -> Result<Option<usize>> {
    let Some(digits) = value.map(str::trim).filter(|v| !v.is_empty()) else {
        return Ok(None);
    };
    if !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(Error::Usage(format!(
            "RAYON_NUM_THREADS={}: not a whole number of worker threads (unset it, or 0, for one per hardware thread)",
            crate::text::escaped(digits)
        )));
    }
    let n = digits.parse::<u128>().unwrap_or(u128::MAX);
    if n > MAX_WORKER_THREADS as u128 {
        return Err(Error::Usage(format!(
            "RAYON_NUM_THREADS={n}: at most {MAX_WORKER_THREADS} worker threads (workers::MAX_WORKER_THREADS)"
        )));
    }
    Ok((n > 0).then_some(n as usize))
}

/// Builds rayon's global pool from `RAYON_NUM_THREADS` ([`requested_threads`]). A thread the
/// system refuses to start is [`Error::Threads`], never a panic. Call once, from `main`,
/// before any parallel work.
pub fn install_global_pool() -> Result<()> {
    let value = std::env::var("RAYON_NUM_THREADS").ok();
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = requested_threads(value.as_deref())? {
        builder = builder.num_threads(n);
    }
    builder.build_global().map_err(Error::Threads)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_counts_are_bounded() {
        assert_eq!(requested_threads(None).unwrap(), None);
        assert_eq!(requested_threads(Some("0")).unwrap(), None);
        assert_eq!(requested_threads(Some("  ")).unwrap(), None);
        assert_eq!(requested_threads(Some(" 8 ")).unwrap(), Some(8));
        assert_eq!(
            requested_threads(Some("1024")).unwrap(),
            Some(MAX_WORKER_THREADS)
        );
        for big in [
            "1025",
            "100000",
            "999999999999999999999999999999999999999999",
        ] {
            let e = requested_threads(Some(big)).unwrap_err();
            assert_eq!(e.exit_code(), crate::error::EXIT_USAGE);
            assert!(e.to_string().contains("at most 1024"), "{e}");
        }
        for junk in ["x", "abc", "-1", "8 threads", "4.0"] {
            let e = requested_threads(Some(junk)).unwrap_err();
            assert_eq!(e.exit_code(), crate::error::EXIT_USAGE);
            assert!(e.to_string().contains("not a whole number"), "{e}");
        }
    }
}
