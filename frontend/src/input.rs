//! Reading an input file whole, bounded: every file a command reads in one piece (scene, OBJ,
//! mesh list, cross-check part) comes through [`read_bytes`] or [`read_text`].
//!
//! A regular file is read when it holds at most [`MAX_INPUT_BYTES`]; a FIFO, socket or pipe
//! (`<(…)`, `/dev/stdin` from a pipe) is read up to that many bytes and refused beyond; a
//! character or block device (`/dev/zero`, `/dev/urandom`, a disk) and a directory are
//! refused before reading anything.

use crate::error::{Error, Location, Result};
use crate::limits::MAX_INPUT_BYTES;
use std::io::{self, Read};
use std::path::Path;

fn refuse(path: &Path, kind: io::ErrorKind, message: String) -> Error {
    Error::io(path, io::Error::new(kind, message))
}

/// `path` opened for reading: a directory or a character or block device is refused before it
/// is opened, and so is a regular file of more than [`MAX_INPUT_BYTES`] (see the module docs).
/// Every error names `path`.
///
/// # Errors
///
/// [`Error::Io`] as listed, or the operating system's error opening `path`.
pub fn open(path: &Path) -> Result<std::fs::File> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let ft = meta.file_type();
    if ft.is_dir() {
        return Err(refuse(
            path,
            io::ErrorKind::IsADirectory,
            "is a directory, not a file".into(),
        ));
    }
    if let Some(kind) = device_kind(&ft) {
        return Err(refuse(
            path,
            io::ErrorKind::InvalidInput,
            format!("is a {kind}, not a regular file"),
        ));
    }
    if ft.is_file() && meta.len() > MAX_INPUT_BYTES {
        return Err(too_big(path));
    }
    std::fs::File::open(path).map_err(|e| Error::io(path, e))
}

fn too_big(path: &Path) -> Error {
    refuse(
        path,
        io::ErrorKind::FileTooLarge,
        format!(
            "holds more than {} MiB, the input limit (limits::MAX_INPUT_BYTES)",
            MAX_INPUT_BYTES >> 20
        ),
    )
}

/// The bytes of `path` (see the module docs), opened by [`open`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let file = open(path)?;
    // A regular file's length sizes the buffer: read through `take`, the file gives no size
    // hint, and the buffer doubled past it (a 1 GiB file asked for 2 GiB).
    let size = file
        .metadata()
        .ok()
        .filter(std::fs::Metadata::is_file)
        .map(|m| m.len());
    read_at_most(file, MAX_INPUT_BYTES, size)
        .map_err(|e| Error::io(path, e))?
        .ok_or_else(|| too_big(path))
}

/// Everything `reader` yields when that is at most `limit` bytes; `None` when it yields more
/// (then `limit + 1` bytes were read and the rest never: a stream that never ends stops
/// there). `size`, when known, is the expected length: the buffer starts that large (plus
/// the byte that shows the end), never above `limit + 1`.
fn read_at_most(reader: impl Read, limit: u64, size: Option<u64>) -> io::Result<Option<Vec<u8>>> {
    let capacity = size.map_or(0, |n| n.min(limit).saturating_add(1));
    let mut bytes = Vec::with_capacity(usize::try_from(capacity).unwrap_or(0));
    reader.take(limit + 1).read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= limit).then_some(bytes))
}

/// The UTF-8 byte-order mark, skipped at the start of a text file.
pub const BOM: &[u8] = b"\xEF\xBB\xBF";

/// The text of `path` ([`read_bytes`]) after a leading [`BOM`], which some editors write; bytes
/// that are not UTF-8 are an input error at the line and column (in characters) of the first
/// bad byte. `what` says what the text should be, for that message (`"a scene (TOML)"`).
pub fn read_text(path: &Path, what: &str) -> Result<String> {
    let mut bytes = read_bytes(path)?;
    if bytes.starts_with(BOM) {
        bytes.drain(..BOM.len());
    }
    utf8(path, bytes, what)
}

/// `bytes` as text, or the located error of [`read_text`].
pub fn utf8(path: &Path, bytes: Vec<u8>, what: &str) -> Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line_start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
        let column = 1 + String::from_utf8_lossy(&valid[line_start..])
            .chars()
            .count();
        let bad = e.as_bytes()[valid.len()];
        Error::input(
            Location::file(path).line(line).column(column),
            format!("byte 0x{bad:02x} is not UTF-8: expected {what}"),
        )
    })
}

#[cfg(unix)]
fn device_kind(ft: &std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_char_device() {
        Some("character device")
    } else if ft.is_block_device() {
        Some("block device")
    } else {
        None
    }
}

#[cfg(not(unix))]
fn device_kind(_: &std::fs::FileType) -> Option<&'static str> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_folders_are_refused_and_bad_utf8_is_located() {
        for (p, want) in [
            ("/dev/zero", "is a character device, not a regular file"),
            ("/dev/null", "is a character device, not a regular file"),
            ("/", "is a directory"),
        ] {
            let e = read_bytes(Path::new(p)).unwrap_err().to_string();
            assert!(e.contains(want), "{p}: {e}");
        }
        let e = utf8(
            Path::new("s.toml"),
            b"a = 1\nb = \"x\xffy\"\n".to_vec(),
            "TOML",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "s.toml:2:7: byte 0xff is not UTF-8: expected TOML");
    }

    /// The bound of a stream (a pipe, where no size is known before reading): a stream of
    /// exactly `limit` bytes is read whole, one byte more is refused, and an endless one
    /// (`io::repeat`) stops after `limit + 1` bytes.
    #[test]
    fn a_stream_is_read_up_to_the_limit_and_refused_beyond() {
        let data: Vec<u8> = (0..=255).collect();
        let limit = data.len() as u64;
        assert_eq!(
            read_at_most(&data[..], limit, None).unwrap(),
            Some(data.clone())
        );
        assert_eq!(read_at_most(&data[..], limit - 1, None).unwrap(), None);
        assert_eq!(read_at_most(&data[..0], 0, None).unwrap(), Some(Vec::new()));
        assert_eq!(read_at_most(io::repeat(7), 1000, None).unwrap(), None);
    }

    /// A known size sizes the buffer once: the bytes read are the same, and the buffer holds
    /// them with the one byte that shows the end to spare (read through `take`, a 1 GiB file
    /// grew a 2 GiB buffer); a size that is wrong (the file grew) still reads only to the limit.
    #[test]
    fn a_known_size_reads_into_one_buffer_of_that_size() {
        let data: Vec<u8> = (0..=255).cycle().take(100_000).collect();
        let bytes = read_at_most(&data[..], 1 << 20, Some(100_000))
            .unwrap()
            .unwrap();
        assert_eq!(bytes, data);
        assert_eq!(bytes.capacity(), 100_001);
        assert_eq!(read_at_most(&data[..], 1000, Some(10)).unwrap(), None);
        assert_eq!(
            read_at_most(io::repeat(7), 1000, Some(u64::MAX)).unwrap(),
            None
        );
    }

    /// A regular file is judged by its size before it is read: one byte over
    /// [`MAX_INPUT_BYTES`] is refused by [`open`] and [`read_bytes`] with a message naming the
    /// file and the limit, exactly the limit opens. Sparse files: no byte is written or read.
    #[test]
    fn a_regular_file_over_the_limit_is_refused_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        let sparse = |name: &str, len: u64| {
            let path = dir.path().join(name);
            std::fs::File::create(&path).unwrap().set_len(len).unwrap();
            path
        };
        let at = sparse("at-limit.obj", MAX_INPUT_BYTES);
        assert!(open(&at).is_ok());
        let over = sparse("over-limit.obj", MAX_INPUT_BYTES + 1);
        for e in [open(&over).unwrap_err(), read_bytes(&over).unwrap_err()] {
            let text = e.to_string();
            assert!(
                text.contains("over-limit.obj") && text.contains("holds more than 1024 MiB"),
                "{text}"
            );
        }
    }
}
