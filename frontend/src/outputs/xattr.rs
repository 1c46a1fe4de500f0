//! A replaced file's extended attributes, given to its replacement: its POSIX ACL
//! (`system.posix_acl_access`), `user.*` and `security.*` attributes, every one this process
//! can list. Without them, a file with an ACL would lose its named users' access and its
//! owning group would get the ACL mask as its plain group bits (`group::r--` with mask `rw-`
//! becomes `rw-`).
//!
//! Linux only (`listxattr`, `getxattr`, `fsetxattr`); elsewhere a file has no attributes
//! here and none are copied.

use std::ffi::{CStr, CString};
use std::fs::File;
use std::io;
use std::path::Path;

/// The name of the access ACL's attribute.
pub const ACCESS_ACL: &CStr = c"system.posix_acl_access";

/// A file's extended attributes, names and values, as read by [`Attributes::of`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Attributes {
    entries: Vec<(CString, Vec<u8>)>,
}

impl Attributes {
    /// The attributes of the file `path` names (symlinks followed). A file system without
    /// extended attributes has none.
    ///
    /// # Errors
    /// When the list or a value cannot be read (other than the file system not supporting
    /// them, or an attribute removed in between).
    pub fn of(path: &Path) -> io::Result<Self> {
        sys::read(path).map(|entries| Self { entries })
    }

    /// Gives `file` these attributes, each value that differs from what `file` has (so that a
    /// label the file already carries, `security.selinux`, is not set again), and removes
    /// from it an access ACL these lack (inherited from its folder's default ACL). Call it
    /// again after writing the bytes: the kernel removes some attributes on a write
    /// (`security.capability`), which the second call puts back.
    ///
    /// # Errors
    /// The first attribute that cannot be set, named in the message.
    pub fn copy_to(&self, file: &File) -> io::Result<()> {
        for (name, value) in &self.entries {
            if sys::value_of(file, name)?.as_deref() != Some(value.as_slice()) {
                sys::set(file, name, value).map_err(|e| failed("copy", name, &e))?;
            }
        }
        if !self.entries.iter().any(|(n, _)| n.as_c_str() == ACCESS_ACL)
            && sys::value_of(file, ACCESS_ACL)?.is_some()
        {
            sys::remove(file, ACCESS_ACL).map_err(|e| failed("remove", ACCESS_ACL, &e))?;
        }
        Ok(())
    }
}

fn failed(what: &str, name: &CStr, e: &io::Error) -> io::Error {
    io::Error::new(
        e.kind(),
        format!(
            "cannot {what} extended attribute `{}` on its replacement: {e}",
            name.to_string_lossy()
        ),
    )
}

#[cfg(target_os = "linux")]
mod sys {
    use std::ffi::{CStr, CString};
    use std::fs::File;
    use std::io;
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::io::AsRawFd;
    use std::path::Path;

    /// Most tries at reading a list or a value whose size changed in between (`ERANGE`).
    const MAX_READ_TRIES: u32 = 8;

    fn last_error() -> io::Error {
        io::Error::last_os_error()
    }

    /// Reads a buffer whose size the call `read(buf)` reports when `buf` is empty (the
    /// `listxattr`/`getxattr` convention), asking again when it grew in between (`ERANGE`).
    fn read_sized(mut read: impl FnMut(&mut [u8]) -> isize) -> io::Result<Vec<u8>> {
        for _ in 0..MAX_READ_TRIES {
            let Ok(size) = usize::try_from(read(&mut [])) else {
                return Err(last_error());
            };
            let mut buf = vec![0; size];
            match usize::try_from(read(&mut buf)) {
                Ok(len) if len <= buf.len() => {
                    buf.truncate(len);
                    return Ok(buf);
                }
                // Nothing at the size first asked (0) but something now: ask again.
                Ok(_) => {}
                Err(_) => {
                    let e = last_error();
                    if e.raw_os_error() != Some(libc::ERANGE) {
                        return Err(e);
                    }
                }
            }
        }
        Err(io::Error::other(
            "extended attributes kept changing while read",
        ))
    }

    /// `ENODATA` (no such attribute) and `ENOTSUP` (no attributes on this file system) mean
    /// there is nothing to read.
    fn absent(e: &io::Error) -> bool {
        matches!(e.raw_os_error(), Some(libc::ENODATA | libc::ENOTSUP))
    }

    fn none_when_absent(r: io::Result<Vec<u8>>) -> io::Result<Option<Vec<u8>>> {
        match r {
            Err(e) if absent(&e) => Ok(None),
            r => r.map(Some),
        }
    }

    pub(super) fn read(path: &Path) -> io::Result<Vec<(CString, Vec<u8>)>> {
        let c_path = CString::new(path.as_os_str().as_bytes())
            .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "NUL in the path"))?;
        // SAFETY: `c_path` is NUL-terminated and outlives the call; `buf` is a valid writable
        // buffer of `buf.len()` bytes (none for an empty one, which asks for the size).
        let names = none_when_absent(read_sized(|buf| unsafe {
            libc::listxattr(c_path.as_ptr(), buf.as_mut_ptr().cast(), buf.len())
        }))?
        .unwrap_or_default();
        let mut entries = Vec::new();
        for name in names.split(|&b| b == 0).filter(|n| !n.is_empty()) {
            let name = CString::new(name).expect("split at NUL");
            // SAFETY: as above; `name` is NUL-terminated and outlives the call.
            let value = none_when_absent(read_sized(|buf| unsafe {
                libc::getxattr(
                    c_path.as_ptr(),
                    name.as_ptr(),
                    buf.as_mut_ptr().cast(),
                    buf.len(),
                )
            }))?;
            // An attribute removed since it was listed is not copied.
            if let Some(value) = value {
                entries.push((name, value));
            }
        }
        Ok(entries)
    }

    /// The value of attribute `name` on `file`, `None` when it has none.
    pub(super) fn value_of(file: &File, name: &CStr) -> io::Result<Option<Vec<u8>>> {
        let fd = file.as_raw_fd();
        // SAFETY: `fd` is open for as long as `file` is borrowed; `name` is NUL-terminated;
        // `buf` is a valid writable buffer of `buf.len()` bytes.
        none_when_absent(read_sized(|buf| unsafe {
            libc::fgetxattr(fd, name.as_ptr(), buf.as_mut_ptr().cast(), buf.len())
        }))
    }

    pub(super) fn set(file: &File, name: &CStr, value: &[u8]) -> io::Result<()> {
        // SAFETY: the descriptor is open while `file` is borrowed; `name` is NUL-terminated;
        // `value` is readable for `value.len()` bytes. The call only reads them.
        let status = unsafe {
            libc::fsetxattr(
                file.as_raw_fd(),
                name.as_ptr(),
                value.as_ptr().cast(),
                value.len(),
                0,
            )
        };
        if status == 0 {
            Ok(())
        } else {
            Err(last_error())
        }
    }

    pub(super) fn remove(file: &File, name: &CStr) -> io::Result<()> {
        // SAFETY: the descriptor is open while `file` is borrowed; `name` is NUL-terminated.
        let status = unsafe { libc::fremovexattr(file.as_raw_fd(), name.as_ptr()) };
        if status == 0 {
            Ok(())
        } else {
            Err(last_error())
        }
    }
}

/// No extended attributes are read or written off Linux.
#[cfg(not(target_os = "linux"))]
mod sys {
    use std::ffi::{CStr, CString};
    use std::fs::File;
    use std::io;
    use std::path::Path;

    pub(super) fn read(_: &Path) -> io::Result<Vec<(CString, Vec<u8>)>> {
        Ok(Vec::new())
    }

    #[allow(clippy::unnecessary_wraps)]
    pub(super) fn value_of(_: &File, _: &CStr) -> io::Result<Option<Vec<u8>>> {
        Ok(None)
    }

    pub(super) fn set(_: &File, _: &CStr, _: &[u8]) -> io::Result<()> {
        Err(io::Error::from(io::ErrorKind::Unsupported))
    }

    pub(super) fn remove(_: &File, _: &CStr) -> io::Result<()> {
        Err(io::Error::from(io::ErrorKind::Unsupported))
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// An attribute the kernel will not set (a name in no namespace: `EOPNOTSUPP`) is an
    /// error naming it; the file is left without it.
    #[test]
    fn an_attribute_that_cannot_be_set_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let file = File::create(dir.path().join("f")).unwrap();
        let attributes = Attributes {
            entries: vec![(c"nonamespace.x".to_owned(), b"v".to_vec())],
        };
        let e = attributes.copy_to(&file).unwrap_err().to_string();
        assert!(
            e.contains("cannot copy extended attribute `nonamespace.x`"),
            "{e}"
        );
        assert_eq!(sys::value_of(&file, c"nonamespace.x").unwrap(), None);
    }
}
