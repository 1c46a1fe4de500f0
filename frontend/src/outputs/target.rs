//! What an output path points at, once symlinks are followed: the file the bytes must reach.

use std::fs::Permissions;
use std::io;
use std::path::{Path, PathBuf};

/// The [`Target::Special`] kind of a character device (`/dev/null`, a terminal).
pub const CHARACTER_DEVICE: &str = "character device";

/// Most symlinks followed from an output path to its target (Linux's own limit, `ELOOP`
/// beyond it: `MAXSYMLINKS` is 40).
pub const MAX_SYMLINK_HOPS: usize = 40;

/// The file an output path resolves to.
#[derive(Clone, Debug)]
pub enum Target {
    /// Nothing there yet: a new regular file will be created at `path` (the final target of
    /// the symlink chain, when the output path is a dangling symlink).
    Missing {
        /// Where the new file goes.
        path: PathBuf,
    },
    /// An existing regular file: replaced atomically by a file in the same folder, with the
    /// same permissions.
    Regular {
        /// The file (symlinks followed).
        path: PathBuf,
        /// Its permissions, given to the replacement.
        permissions: Permissions,
        /// Hard links to it (replacing a file with more than one splits them).
        links: u64,
    },
    /// A character or block device, FIFO or socket: written in place, never replaced.
    Special {
        /// The node (symlinks followed).
        path: PathBuf,
        /// `character device`, `block device`, `FIFO` or `socket`.
        kind: &'static str,
    },
    /// One of this process's open file descriptors named as a file (`-`, `/dev/stdout`,
    /// `/dev/fd/N`, `/proc/self/fd/N`, see [`stream_fd`]): written through the descriptor,
    /// never resolved to the file behind it and replaced.
    Stream {
        /// The path as named.
        path: PathBuf,
        /// The descriptor.
        fd: u32,
    },
    /// A directory: never an output.
    Directory {
        /// The directory.
        path: PathBuf,
    },
}

impl Target {
    /// The resolved path.
    pub fn path(&self) -> &Path {
        match self {
            Self::Missing { path }
            | Self::Regular { path, .. }
            | Self::Special { path, .. }
            | Self::Stream { path, .. }
            | Self::Directory { path } => path,
        }
    }
}

/// The descriptor a path names when it names one of this process's open files rather than a
/// file: `-` (stdout), `/dev/stdin`, `/dev/stdout`, `/dev/stderr` (0, 1, 2), `/dev/fd/N`,
/// `/proc/self/fd/N`, `/proc/thread-self/fd/N` and `/proc/<this pid>/fd/N`. Compared as
/// spelt (no `..` resolution); [`resolve`] checks every hop of a symlink chain.
pub fn stream_fd(path: &Path) -> Option<u32> {
    let s = path.to_str()?;
    match s {
        "-" | "/dev/stdout" => return Some(1),
        "/dev/stdin" => return Some(0),
        "/dev/stderr" => return Some(2),
        _ => {}
    }
    let pid = format!("/proc/{}/fd/", std::process::id());
    let n = [
        "/dev/fd/",
        "/proc/self/fd/",
        "/proc/thread-self/fd/",
        pid.as_str(),
    ]
    .iter()
    .find_map(|prefix| s.strip_prefix(prefix))?;
    if n.is_empty() || !n.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    n.parse().ok()
}

/// Follows `dest` through at most [`MAX_SYMLINK_HOPS`] symlinks (relative links are resolved
/// against the folder holding the link) and classifies what is at the end. A path that names
/// a descriptor ([`stream_fd`]), as given or at any hop, is a [`Target::Stream`].
pub fn resolve(dest: &Path) -> io::Result<Target> {
    let mut path = dest.to_path_buf();
    for _ in 0..=MAX_SYMLINK_HOPS {
        if let Some(fd) = stream_fd(&path) {
            return Ok(Target::Stream { path, fd });
        }
        let meta = match std::fs::symlink_metadata(&path) {
            Ok(m) => m,
            // A component that is a file (`file.txt/x`) is reported by the folder check.
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
                ) =>
            {
                return Ok(Target::Missing { path });
            }
            Err(e) => return Err(e),
        };
        let ft = meta.file_type();
        if ft.is_symlink() {
            let link = std::fs::read_link(&path)?;
            path = match path.parent() {
                Some(dir) if link.is_relative() => dir.join(link),
                _ => link,
            };
            continue;
        }
        if ft.is_dir() {
            return Ok(Target::Directory { path });
        }
        if ft.is_file() {
            return Ok(Target::Regular {
                permissions: meta.permissions(),
                links: link_count(&meta),
                path,
            });
        }
        return Ok(Target::Special {
            kind: special_kind(&ft),
            path,
        });
    }
    Err(io::Error::other(format!(
        "more than {MAX_SYMLINK_HOPS} symbolic links to follow"
    )))
}

#[cfg(unix)]
fn link_count(meta: &std::fs::Metadata) -> u64 {
    std::os::unix::fs::MetadataExt::nlink(meta)
}

#[cfg(not(unix))]
fn link_count(_: &std::fs::Metadata) -> u64 {
    1
}

#[cfg(unix)]
fn special_kind(ft: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_char_device() {
        CHARACTER_DEVICE
    } else if ft.is_block_device() {
        "block device"
    } else if ft.is_fifo() {
        "FIFO"
    } else {
        "socket"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "special file"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn follows_relative_and_dangling_symlinks() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.txt");
        std::fs::write(&real, b"x").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink("real.txt", &link).unwrap();
        match resolve(&link).unwrap() {
            Target::Regular { path, links, .. } => {
                assert_eq!(path, dir.path().join("real.txt"));
                assert_eq!(links, 1);
            }
            other => panic!("{other:?}"),
        }
        let dangling = dir.path().join("dangling");
        std::os::unix::fs::symlink("sub/new.txt", &dangling).unwrap();
        assert!(matches!(
            resolve(&dangling).unwrap(),
            Target::Missing { path } if path == dir.path().join("sub/new.txt")
        ));
        let a = dir.path().join("a");
        let b = dir.path().join("b");
        std::os::unix::fs::symlink("b", &a).unwrap();
        std::os::unix::fs::symlink("a", &b).unwrap();
        assert!(resolve(&a).is_err(), "a symlink loop is an error");
        // Descriptors, named directly or through a link, are streams, not the file behind.
        let out = dir.path().join("out");
        std::os::unix::fs::symlink("/dev/stdout", &out).unwrap();
        for (p, want) in [
            (Path::new("-"), 1),
            (Path::new("/dev/stderr"), 2),
            (Path::new("/proc/self/fd/7"), 7),
            (out.as_path(), 1),
        ] {
            assert!(
                matches!(resolve(p).unwrap(), Target::Stream { fd, .. } if fd == want),
                "{}",
                p.display()
            );
        }
        assert_eq!(stream_fd(Path::new("/dev/fd/x")), None);
        assert_eq!(stream_fd(Path::new("/dev/fd/")), None);
        assert!(matches!(
            resolve(Path::new("/dev/null")).unwrap(),
            Target::Special {
                kind: "character device",
                ..
            }
        ));
    }
}
