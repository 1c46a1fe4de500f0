//! Atomic output files in one call: [`OutputFile::reserve`] then [`OutputFile::write`] (see
//! [`crate::outputs::file`] for what happens to symlinks, devices, FIFOs, read-only and
//! hard-linked files, and on failure). Commands that have several outputs reserve them all
//! before working with [`crate::outputs::reserve_outputs`] instead.

use crate::error::Result;
use crate::outputs::OutputFile;
use std::io::Write;
use std::path::Path;

/// Writes `dest` atomically with the bytes produced by `fill` (read-only and hard-linked
/// files are refused).
pub fn write_atomic(
    dest: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    OutputFile::reserve(dest, false)?.write(fill)
}

/// Writes `bytes` to `dest` atomically.
pub fn write_bytes_atomic(dest: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(dest, |w| w.write_all(bytes))
}
