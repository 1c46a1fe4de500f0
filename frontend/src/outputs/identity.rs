//! File identity: whether two paths name the same file, whatever their spelling (`./a`,
//! `dir/../a`, a symlink, a hard link).

use super::target::{Target, resolve};
use std::collections::HashMap;
use std::ffi::OsString;
use std::io;
use std::path::{Path, PathBuf};

/// What makes a file itself.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum FileId {
    /// An existing file: its device and inode.
    #[cfg(unix)]
    Inode {
        /// Device number.
        dev: u64,
        /// Inode number.
        ino: u64,
    },
    /// An existing file: its canonical path (where there are no inode numbers).
    #[cfg(not(unix))]
    Canonical(PathBuf),
    /// A file not created yet: its canonical folder and its name.
    New {
        /// Canonical folder.
        dir: PathBuf,
        /// File name.
        name: OsString,
    },
}

/// The identity of the file `path` names, symlinks followed. A missing file is identified
/// by its folder's canonical path and its name; an error when that folder does not exist.
pub fn file_id(path: &Path) -> io::Result<FileId> {
    match resolve(path)? {
        Target::Missing { path } => {
            let name = path
                .file_name()
                .ok_or_else(|| io::Error::other("the path names no file"))?
                .to_os_string();
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            Ok(FileId::New {
                dir: std::fs::canonicalize(dir)?,
                name,
            })
        }
        // The open file behind the descriptor (`/dev/fd/N` is this process's own table).
        Target::Stream { fd, .. } => existing_id(Path::new(&format!("/dev/fd/{fd}"))),
        target => existing_id(target.path()),
    }
}

/// The first two positions (earlier, later) whose identities are equal; `None` identities
/// (files that could not be identified) match nothing.
pub fn first_repeat<'a>(
    ids: impl IntoIterator<Item = Option<&'a FileId>>,
) -> Option<(usize, usize)> {
    let mut seen: HashMap<&FileId, usize> = HashMap::new();
    for (k, id) in ids.into_iter().enumerate() {
        let Some(id) = id else { continue };
        if let Some(&j) = seen.get(id) {
            return Some((j, k));
        }
        seen.insert(id, k);
    }
    None
}

#[cfg(unix)]
fn existing_id(path: &Path) -> io::Result<FileId> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::metadata(path)?;
    Ok(FileId::Inode {
        dev: meta.dev(),
        ino: meta.ino(),
    })
}

#[cfg(not(unix))]
fn existing_id(path: &Path) -> io::Result<FileId> {
    Ok(FileId::Canonical(std::fs::canonicalize(path)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_repeat_is_the_earliest_later_position_and_none_matches_nothing() {
        let id = |n: &str| FileId::New {
            dir: PathBuf::from("/d"),
            name: n.into(),
        };
        let (a, b, c) = (id("a"), id("b"), id("c"));
        assert_eq!(first_repeat([Some(&a), Some(&b), Some(&c)]), None);
        assert_eq!(first_repeat([None, Some(&a), None, Some(&b)]), None);
        assert_eq!(
            first_repeat([Some(&a), Some(&b), Some(&b), Some(&a)]),
            Some((1, 2))
        );
        assert_eq!(
            first_repeat([Some(&c), None, Some(&a), Some(&c)]),
            Some((0, 3))
        );
    }

    #[cfg(unix)]
    #[test]
    fn same_file_under_different_spellings() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.txt");
        std::fs::write(&a, b"x").unwrap();
        let hard = dir.path().join("hard.txt");
        std::fs::hard_link(&a, &hard).unwrap();
        let sym = dir.path().join("sym.txt");
        std::os::unix::fs::symlink(&a, &sym).unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        let dotted = dir.path().join("sub/../a.txt");
        let id = file_id(&a).unwrap();
        for other in [&hard, &sym, &dotted] {
            assert_eq!(file_id(other).unwrap(), id, "{}", other.display());
        }
        let b = dir.path().join("b.txt");
        std::fs::write(&b, b"x").unwrap();
        assert_ne!(file_id(&b).unwrap(), id);
        // Not yet existing: folder + name.
        let n1 = file_id(&dir.path().join("new.png")).unwrap();
        let n2 = file_id(&dir.path().join("sub/../new.png")).unwrap();
        assert_eq!(n1, n2);
        assert_ne!(n1, file_id(&dir.path().join("other.png")).unwrap());
        assert!(file_id(&dir.path().join("nodir/x.png")).is_err());
    }
}
