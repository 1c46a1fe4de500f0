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
    /// The file may only be appended to (`chattr +a`): the kernel refuses a rename over it
    /// (`EPERM`) whatever the user, though it lets anyone with write permission open it.
    AppendOnly,
    /// Another file system is mounted on the path (`mount --bind FILE PATH`): a rename over
    /// a mount point fails (`EBUSY`).
    MountPoint,
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
            Self::AppendOnly => "is append-only (chattr +a): it cannot be replaced",
            Self::MountPoint => "has a file mounted on it (mount --bind): it cannot be replaced",
            Self::StickyFolder => {
                "is another user's file in a sticky folder (chmod +t): it cannot be replaced"
            }
        }
    }
}

/// The barrier to replacing the regular file `path` (`file` its metadata, symlinks followed)
/// in the folder whose metadata is `folder`, if any. The append-only attribute and a mount
/// point are seen on Linux with glibc (`statx`); elsewhere only the permission, the immutable
/// attribute and the sticky rule are.
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
    if let Some(b) = attribute_barrier(&c_path) {
        return Some(b);
    }
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

/// The barrier the file's attributes (`statx`, symlinks followed as `path`'s metadata is)
/// put before a rename over it: append-only, immutable (also seen by `faccessat`, as
/// [`Barrier::Unchangeable`]) or a mount point. `None` where the call fails or the file system
/// does not report the attribute (its bit clear in `stx_attributes_mask`).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn attribute_barrier(c_path: &std::ffi::CStr) -> Option<Barrier> {
    let mut st = std::mem::MaybeUninit::<libc::statx>::zeroed();
    // SAFETY: `c_path` is NUL-terminated and lives across the call, which only reads it;
    // `st` points to a `statx` the call may fill (all-zero bytes are a valid `statx`, a
    // struct of integers). `AT_FDCWD` resolves the path as `std::fs` does.
    let status = unsafe {
        libc::statx(
            libc::AT_FDCWD,
            c_path.as_ptr(),
            0,
            libc::STATX_BASIC_STATS,
            st.as_mut_ptr(),
        )
    };
    if status != 0 {
        return None;
    }
    // SAFETY: zero-initialised above and filled by the successful call.
    let st = unsafe { st.assume_init() };
    let set = |flag: libc::c_int| {
        let flag = u64::from(flag.unsigned_abs());
        st.stx_attributes_mask & flag != 0 && st.stx_attributes & flag != 0
    };
    if set(libc::STATX_ATTR_IMMUTABLE) {
        Some(Barrier::Unchangeable)
    } else if set(libc::STATX_ATTR_APPEND) {
        Some(Barrier::AppendOnly)
    } else if set(libc::STATX_ATTR_MOUNT_ROOT) {
        Some(Barrier::MountPoint)
    } else {
        None
    }
}

/// Without `statx` the attributes are not looked at ([`barrier`]).
#[cfg(all(unix, not(all(target_os = "linux", target_env = "gnu"))))]
fn attribute_barrier(_: &std::ffi::CStr) -> Option<Barrier> {
    None
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

    /// Runs `chattr FLAG path`; whether it succeeded.
    fn chattr(flag: &str, path: &Path) -> bool {
        std::process::Command::new("chattr")
            .arg(flag)
            .arg(path)
            .output()
            .is_ok_and(|o| o.status.success())
    }

    fn barrier_of(path: &Path) -> Option<Barrier> {
        let meta = |p: &Path| std::fs::metadata(p).unwrap();
        barrier(
            path,
            &meta(path),
            &meta(super::super::file::folder_of(path)),
        )
    }

    /// A file with the attribute `chattr FLAG` gets barrier `want`, and so would the rename:
    /// it is refused with the errno `errno` (checked, so the barrier names the kernel's rule).
    /// The same file without the attribute has no barrier. Needs root and a file system with
    /// the attributes (ext4, xfs, btrfs): elsewhere the test records a skip and checks
    /// only the plain file.
    #[cfg(unix)]
    fn attribute_refuses(test: &str, flag: char, want: Barrier, errno: i32) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("kept.obj");
        std::fs::write(&path, b"v 0 0 0\n").unwrap();
        assert_eq!(barrier_of(&path), None);
        if !chattr(&format!("+{flag}"), &path) {
            crate::skips::record_skip(&format!(
                "SKIPPED halfray outputs::replace::tests::{test}: chattr +{flag} refused here (not root, or no attributes on this file system)"
            ));
            return;
        }
        let got = barrier_of(&path);
        let other = dir.path().join("new.obj");
        std::fs::write(&other, b"").unwrap();
        let renamed = std::fs::rename(&other, &path);
        assert!(chattr(&format!("-{flag}"), &path), "chattr -{flag}");
        assert_eq!(got, Some(want));
        assert_eq!(renamed.unwrap_err().raw_os_error(), Some(errno));
    }

    /// A file made immutable (`chattr +i`) is refused whatever the user.
    #[cfg(unix)]
    #[test]
    fn an_immutable_file_cannot_be_replaced() {
        attribute_refuses(
            "an_immutable_file_cannot_be_replaced",
            'i',
            Barrier::Unchangeable,
            libc::EPERM,
        );
    }

    /// An append-only file (`chattr +a`) is refused whatever the user: it is writable, so
    /// `faccessat` does not see it, but a rename over it fails.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn an_append_only_file_cannot_be_replaced() {
        attribute_refuses(
            "an_append_only_file_cannot_be_replaced",
            'a',
            Barrier::AppendOnly,
            libc::EPERM,
        );
    }

    /// A path with a file bind-mounted on it is refused: a rename over a mount point fails
    /// with `EBUSY`. Needs root and a mount namespace that allows `mount --bind`: elsewhere
    /// the test records a skip and checks only the plain file.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn a_mount_point_cannot_be_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let (path, source) = (dir.path().join("out.png"), dir.path().join("source"));
        std::fs::write(&path, b"under").unwrap();
        std::fs::write(&source, b"over").unwrap();
        assert_eq!(barrier_of(&path), None);
        let mount = std::process::Command::new("mount")
            .arg("--bind")
            .args([&source, &path])
            .output();
        if !mount.is_ok_and(|o| o.status.success()) {
            crate::skips::record_skip(
                "SKIPPED halfray outputs::replace::tests::a_mount_point_cannot_be_replaced: mount --bind refused here (not root?)",
            );
            return;
        }
        let got = barrier_of(&path);
        let renamed = std::fs::rename(&source, &path);
        let unmounted = std::process::Command::new("umount").arg(&path).status();
        assert!(unmounted.is_ok_and(|s| s.success()), "umount");
        assert_eq!(got, Some(Barrier::MountPoint));
        assert_eq!(renamed.unwrap_err().raw_os_error(), Some(libc::EBUSY));
        assert_eq!(barrier_of(&path), None, "the path once unmounted");
    }
}
