//! Whether this process may replace an existing regular file by renaming a new one over it,
//! decided when the output is reserved, before any work: a rename needs more than a writable
//! folder, and one that fails after others succeeded would leave outputs written together
//! half replaced ([`super::write_together`]).

use std::fs::Metadata;
use std::path::Path;

/// Why an existing file must not be replaced (or not without `--force`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Barrier {
    /// This process's user may not write the file (its mode and owner), though it may rename
    /// over it: replacing it needs `--force`, as a read-only file does.
    NotYours,
    /// The kernel refuses to change the file whatever the user (the immutable attribute,
    /// `chattr +i`): no rename replaces it.
    Unchangeable,
    /// The folder is sticky (`chmod +t`, as `/tmp`) and neither the file nor the folder
    /// belongs to this process's user (who is not root): the kernel refuses the rename.
    StickyFolder,
}

impl Barrier {
    /// Whether `--force` lets the output go ahead.
    pub fn forced_past(self) -> bool {
        self == Self::NotYours
    }

    /// What is wrong, after the path.
    pub fn message(self) -> &'static str {
        match self {
            Self::NotYours => "is not writable by you; pass --force to replace it",
            Self::Unchangeable => "is immutable (chattr +i): it cannot be replaced",
            Self::StickyFolder => {
                "is another user's file in a sticky folder (chmod +t): it cannot be replaced"
            }
        }
    }
}

/// The barrier to replacing the regular file `path` (`file` its metadata, symlinks followed)
/// in the folder whose metadata is `folder`, if any. Not caught: the append-only attribute
/// (`chattr +a`, which only an ioctl reports) and a file mounted over (`EBUSY`).
#[cfg(unix)]
pub fn barrier(path: &Path, file: &Metadata, folder: &Metadata) -> Option<Barrier> {
    use std::os::unix::ffi::OsStrExt;
    use std::os::unix::fs::MetadataExt;
    // SAFETY: `geteuid` takes no argument, touches no memory of ours and cannot fail.
    let euid = unsafe { libc::geteuid() };
    if sticky_refuses(folder.mode(), folder.uid(), file.uid(), euid) {
        return Some(Barrier::StickyFolder);
    }
    let c_path = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    // SAFETY: `c_path` is a NUL-terminated string that lives across the call, which only
    // reads it; `AT_FDCWD` resolves it as `std::fs` does. `AT_EACCESS` checks the effective
    // user, the one the rename and the write run as.
    let status = unsafe {
        libc::faccessat(
            libc::AT_FDCWD,
            c_path.as_ptr(),
            libc::W_OK,
            libc::AT_EACCESS,
        )
    };
    if status == 0 {
        return None;
    }
    match std::io::Error::last_os_error().raw_os_error() {
        Some(libc::EACCES) => Some(Barrier::NotYours),
        Some(libc::EPERM) => Some(Barrier::Unchangeable),
        // A busy executable (`ETXTBSY`) or a read-only file system: the rename decides, or
        // the temporary file's creation already failed.
        _ => None,
    }
}

/// No barrier is known off Unix.
#[cfg(not(unix))]
pub fn barrier(_: &Path, _: &Metadata, _: &Metadata) -> Option<Barrier> {
    None
}

/// Whether a sticky folder keeps user `euid` from renaming over a file: the folder has the
/// sticky bit (in `folder_mode`), the user is not root, and owns neither the file
/// (`file_uid`) nor the folder (`folder_uid`) — the rule of `rename(2)` (`EPERM`).
pub fn sticky_refuses(folder_mode: u32, folder_uid: u32, file_uid: u32, euid: u32) -> bool {
    const STICKY: u32 = 0o1000;
    folder_mode & STICKY != 0 && euid != 0 && file_uid != euid && folder_uid != euid
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sticky rule, case by case, as `rename(2)` states it (`EPERM`: "the directory
    /// containing oldpath has the sticky bit set and the caller's effective user ID is neither
    /// the user ID of the file to be deleted nor that of the directory containing it, and the
    /// process is not privileged").
    #[test]
    fn sticky_folder_refuses_only_other_users_files_in_other_users_folders() {
        let (me, other, root) = (1000, 1001, 0);
        // /tmp: sticky, root's.
        assert!(sticky_refuses(0o1777, root, other, me));
        assert!(!sticky_refuses(0o1777, root, me, me), "my own file");
        assert!(!sticky_refuses(0o1777, me, other, me), "my own folder");
        assert!(!sticky_refuses(0o1777, other, other, root), "root");
        assert!(!sticky_refuses(0o0777, root, other, me), "not sticky");
    }

    /// A file made immutable (`chattr +i`) is refused whatever the user; the same file
    /// without the attribute is not. Needs root and a file system with the attribute (ext4,
    /// xfs, btrfs): elsewhere the test says so on stderr and checks only the plain file.
    #[cfg(unix)]
    #[test]
    fn an_immutable_file_cannot_be_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frozen.obj");
        std::fs::write(&path, b"v 0 0 0\n").unwrap();
        let meta = |p: &Path| std::fs::metadata(p).unwrap();
        assert_eq!(barrier(&path, &meta(&path), &meta(dir.path())), None);
        let chattr = |flag: &str| {
            std::process::Command::new("chattr")
                .arg(flag)
                .arg(&path)
                .output()
                .is_ok_and(|o| o.status.success())
        };
        if !chattr("+i") {
            eprintln!("an_immutable_file_cannot_be_replaced: chattr +i refused here (not root?)");
            return;
        }
        let got = barrier(&path, &meta(&path), &meta(dir.path()));
        assert!(chattr("-i"), "chattr -i");
        assert_eq!(got, Some(Barrier::Unchangeable));
    }
}
