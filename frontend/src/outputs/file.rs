//! One output file, checked before the work and written after it.
//!
//! [`OutputFile::reserve`] checks the location (the folder exists, is a folder, takes a new
//! file: a temporary file is created there and removed at once; the path is not a directory,
//! not read-only, not hard-linked), so every output a command will write is known to be
//! writable before the command starts working. Nothing is left in the folder while the
//! command works: the temporary file that will become the output is created only when
//! writing starts. [`OutputFile::write`] then fills it:
//!
//! * a new or regular file gets a temporary file in its folder, synced, given the replaced
//!   file's permissions, its extended attributes (its ACL, `user.*`, `security.*`:
//!   [`super::xattr`]; one that cannot be copied is an error, when reserved) and its owner
//!   and group where this process may (`keep_owner`), and renamed over it: readers see the
//!   old bytes or the new ones, never a mix, and a failure at any point leaves the old file
//!   untouched and no temporary file;
//! * a symlink is followed (to the end of its chain) and its target replaced as above, in
//!   the target's folder: the link stays a link;
//! * a character or block device, FIFO or socket is opened and written in place: it stays
//!   what it was (`-o /dev/null` works; a FIFO gets the stream);
//! * a path naming one of this process's descriptors (`-`, `/dev/stdout`, `/dev/stderr`,
//!   `/dev/fd/N`, `/proc/self/fd/N`, see [`super::target::stream_fd`]) is written through that
//!   descriptor: stdout and stderr through the process's own handles (so `>> log` appends
//!   after what was printed before), other descriptors opened for appending. Never resolved
//!   to the file behind them and replaced.
//!
//! A read-only file (no write bit set), one this process's user may not write, or one with
//! several hard links is refused unless `force`; with `force` it is replaced, keeping its mode
//! (and, for a hard link, splitting it: only this name gets the new bytes). A file no rename
//! can replace (immutable, or another user's in a sticky folder, [`super::replace`]) is
//! refused. So is standard input (`/dev/stdin`) and a descriptor that is not open.
//!
//! Several outputs of one command are written all or nothing by [`write_together`].

use super::identity::{FileId, file_id};
use super::target::{CHARACTER_DEVICE, Target, resolve};
use super::temp::TempFile;
use super::xattr::Attributes;
use crate::error::{Error, Result};
use std::fs::Permissions;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// How an output reaches its file.
#[derive(Debug)]
enum Route {
    /// Through a temporary file in `dir`, renamed over `target`.
    Replace {
        target: PathBuf,
        dir: PathBuf,
        permissions: Option<Permissions>,
        /// The replaced file's owner and group (`uid`, `gid`), given to the replacement
        /// where this process may ([`keep_owner`]).
        owner: Option<(u32, u32)>,
        /// The replaced file's extended attributes, given to the replacement (`None` for a
        /// new file, which keeps what its folder gives it: a default ACL).
        attributes: Option<Attributes>,
    },
    /// Written in place (device, FIFO, socket); `char_device` for a character device.
    InPlace { target: PathBuf, char_device: bool },
    /// Written through this process's descriptor `fd`.
    Stream { fd: u32 },
}

/// An output whose location was checked; see the module docs.
#[derive(Debug)]
pub struct OutputFile {
    dest: PathBuf,
    id: Option<FileId>,
    route: Route,
}

fn refuse(dest: &Path, kind: io::ErrorKind, message: String) -> Error {
    Error::io(dest, io::Error::new(kind, message))
}

/// `true` when `path` can only name a folder: it ends in a separator, or its last component
/// is `.` or `..` (which [`Path::components`] would fold away or climb).
fn names_a_folder(path: &Path) -> bool {
    let text = path.as_os_str().as_encoded_bytes();
    let last = text
        .rsplit(|&b| std::path::is_separator(char::from(b)))
        .next()
        .unwrap_or_default();
    matches!(last, b"" | b"." | b"..")
}

/// The folder holding `path` (`.` for a bare name).
pub(crate) fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

#[cfg(unix)]
fn mode_text(p: &Permissions) -> String {
    format!(
        " (mode {:04o})",
        std::os::unix::fs::PermissionsExt::mode(p) & 0o7777
    )
}

#[cfg(not(unix))]
fn mode_text(_: &Permissions) -> String {
    String::new()
}

impl OutputFile {
    /// Checks that `dest` can be written (see the module docs). `force` allows replacing
    /// read-only, other users' and hard-linked files.
    pub fn reserve(dest: &Path, force: bool) -> Result<Self> {
        let target = resolve(dest).map_err(|e| Error::io(dest, e))?;
        let route = match target {
            Target::Directory { .. } => {
                return Err(refuse(
                    dest,
                    io::ErrorKind::IsADirectory,
                    "is a directory, not a file".into(),
                ));
            }
            Target::Stream { fd, .. } => {
                if fd == 0 {
                    return Err(refuse(
                        dest,
                        io::ErrorKind::InvalidInput,
                        "is standard input, not an output".into(),
                    ));
                }
                // Stdout and stderr exist (Rust's runtime opens `/dev/null` for a closed
                // one); another descriptor must be open now, not found closed after the work.
                if fd > 2 {
                    std::fs::metadata(format!("/dev/fd/{fd}")).map_err(|e| {
                        refuse(dest, e.kind(), format!("descriptor {fd} is not open ({e})"))
                    })?;
                }
                if fd == 1 {
                    crate::console::stdout_carries_output();
                }
                Route::Stream { fd }
            }
            Target::Special { path, kind } => Route::InPlace {
                target: path,
                char_device: kind == CHARACTER_DEVICE,
            },
            Target::Missing { path } => {
                if names_a_folder(&path) {
                    // `out.png/` or `new/.`: no file can be created under that name (the
                    // rename at the end would fail, after the work and after other outputs).
                    return Err(refuse(
                        dest,
                        io::ErrorKind::NotADirectory,
                        "ends in a folder separator (or `.`, `..`): names a folder, not a file"
                            .into(),
                    ));
                }
                let dir = folder_of(&path);
                match std::fs::metadata(dir) {
                    Ok(m) if m.is_dir() => {}
                    Ok(_) => {
                        return Err(refuse(
                            dest,
                            io::ErrorKind::NotADirectory,
                            format!("`{}` is not a folder", crate::text::path(dir)),
                        ));
                    }
                    Err(e) if e.kind() == io::ErrorKind::NotFound => {
                        return Err(refuse(
                            dest,
                            io::ErrorKind::NotFound,
                            format!("folder `{}` does not exist", crate::text::path(dir)),
                        ));
                    }
                    Err(e) => return Err(Error::io(dir, e)),
                }
                drop(temp_in(dest, dir)?);
                Route::Replace {
                    dir: dir.to_path_buf(),
                    target: path,
                    permissions: None,
                    owner: None,
                    attributes: None,
                }
            }
            Target::Regular {
                path,
                permissions,
                links,
            } => {
                if permissions.readonly() && !force {
                    return Err(refuse(
                        dest,
                        io::ErrorKind::PermissionDenied,
                        format!(
                            "is read-only{}; pass --force to replace it",
                            mode_text(&permissions)
                        ),
                    ));
                }
                if links > 1 && !force {
                    return Err(refuse(
                        dest,
                        io::ErrorKind::AlreadyExists,
                        format!(
                            "has {links} hard links; replacing it would split them (pass --force to replace this name only)"
                        ),
                    ));
                }
                let dir = folder_of(&path).to_path_buf();
                let meta = std::fs::metadata(&path);
                let barrier = match (&meta, std::fs::metadata(&dir)) {
                    (Ok(file), Ok(folder)) => super::replace::barrier(&path, file, &folder),
                    _ => None,
                };
                if let Some(b) = barrier.filter(|b| !(force && b.forced_past())) {
                    return Err(refuse(
                        dest,
                        io::ErrorKind::PermissionDenied,
                        b.message().into(),
                    ));
                }
                let attributes = Attributes::of(&path).map_err(|e| {
                    refuse(
                        dest,
                        e.kind(),
                        format!("cannot read its extended attributes: {e}"),
                    )
                })?;
                // Tried on the temporary file made to check the folder: an attribute this
                // process cannot copy (`security.capability` without the capability) is
                // refused now, before the work.
                let mut probe = temp_in(dest, &dir)?;
                probe
                    .file()
                    .and_then(|file| attributes.copy_to(file))
                    .map_err(|e| Error::io(dest, e))?;
                drop(probe);
                Route::Replace {
                    dir,
                    target: path,
                    permissions: Some(permissions),
                    owner: meta.ok().as_ref().and_then(owner_of),
                    attributes: Some(attributes),
                }
            }
        };
        Ok(Self {
            id: file_id(dest).ok(),
            dest: dest.to_path_buf(),
            route,
        })
    }

    /// The path as given.
    pub fn path(&self) -> &Path {
        &self.dest
    }

    /// The identity of the file it will write (`None` when it cannot be determined).
    pub fn id(&self) -> Option<&FileId> {
        self.id.as_ref()
    }

    /// The identity two outputs of one command must not share ([`super::reserve_outputs`]):
    /// [`Self::id`], but `None` for a character device written in place (`/dev/null`, a
    /// terminal), which takes each output's bytes in turn as the shell's `>/dev/null
    /// 2>/dev/null` does: no rename replaces it, no descriptor is shared.
    pub fn repeat_id(&self) -> Option<&FileId> {
        match self.route {
            Route::InPlace {
                char_device: true, ..
            } => None,
            _ => self.id(),
        }
    }

    /// Writes the bytes `fill` produces (see the module docs). On error nothing at the
    /// destination changed (except for devices, FIFOs and descriptors, which get what was
    /// written) and no temporary file is left.
    pub fn write(self, fill: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
        match self.stage(fill)? {
            Staged::Temp { temp, target, dest } => {
                temp.persist(&target).map_err(|e| Error::io(&dest, e))
            }
            Staged::Written => Ok(()),
        }
    }

    /// A regular file's bytes in a synced temporary file, not yet renamed; everything else
    /// written.
    fn stage(self, fill: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<Staged> {
        let dest = self.dest;
        match self.route {
            Route::Replace {
                target,
                dir,
                permissions,
                owner,
                attributes,
            } => {
                let mut temp = temp_in(&dest, &dir)?;
                let result = (|| {
                    let file = temp.file()?;
                    // The owner before the mode: a change of owner clears the set-user-ID
                    // and set-group-ID bits the mode may then set.
                    if let Some(owner) = owner {
                        keep_owner(file, owner);
                    }
                    // Before the bytes: a private file's new contents are never readable
                    // by others, not even in the temporary file. Then the attributes: an
                    // ACL's mask is the mode's group bits, its other entries are not in
                    // the mode.
                    if let Some(p) = permissions {
                        file.set_permissions(p)?;
                    }
                    if let Some(a) = &attributes {
                        a.copy_to(file)?;
                    }
                    let mut w = io::BufWriter::new(&mut *file);
                    fill(&mut w)?;
                    w.flush()?;
                    drop(w);
                    // Again: a write removes some attributes (`security.capability`).
                    if let Some(a) = &attributes {
                        a.copy_to(file)?;
                    }
                    file.sync_all()
                })();
                result.map_err(|e| Error::io(&dest, e))?;
                Ok(Staged::Temp { temp, target, dest })
            }
            Route::InPlace { target, .. } => {
                let result = (|| {
                    let file = std::fs::OpenOptions::new().write(true).open(&target)?;
                    let mut w = io::BufWriter::new(file);
                    fill(&mut w)?;
                    w.flush()
                })();
                result.map_err(|e| Error::io(&dest, e))?;
                Ok(Staged::Written)
            }
            Route::Stream { fd } => {
                write_stream(fd, fill).map_err(|e| match e.kind() {
                    io::ErrorKind::BrokenPipe => Error::BrokenPipe,
                    _ => Error::io(crate::console::output_name(&dest), e),
                })?;
                Ok(Staged::Written)
            }
        }
    }
}

/// The owner and group of a file's metadata (`None` where the platform has none).
#[cfg(unix)]
#[allow(clippy::unnecessary_wraps)]
fn owner_of(m: &std::fs::Metadata) -> Option<(u32, u32)> {
    use std::os::unix::fs::MetadataExt;
    Some((m.uid(), m.gid()))
}

#[cfg(not(unix))]
fn owner_of(_: &std::fs::Metadata) -> Option<(u32, u32)> {
    None
}

/// Gives `file` (a replacement, not yet renamed) the owner and group `(uid, gid)` of the file
/// it replaces, as far as this process may: root both (a root-run command replacing a user's
/// file leaves it theirs), another user the group where it is one of theirs. Where the system
/// refuses, the replacement keeps this process's user and group, as any save by rename does.
#[cfg(unix)]
fn keep_owner(file: &std::fs::File, (uid, gid): (u32, u32)) {
    use std::os::unix::fs::{MetadataExt, fchown};
    let Ok(m) = file.metadata() else {
        return;
    };
    if (m.uid(), m.gid()) != (uid, gid) && fchown(file, Some(uid), Some(gid)).is_err() {
        let _ = fchown(file, None, Some(gid));
    }
}

#[cfg(not(unix))]
fn keep_owner(_: &std::fs::File, _: (u32, u32)) {}

/// An output half way: see [`OutputFile::stage`].
enum Staged {
    Temp {
        temp: TempFile,
        target: PathBuf,
        dest: PathBuf,
    },
    Written,
}

/// Writes to descriptor `fd`: stdout and stderr through the process's handles (locked, so
/// the bytes land after what was printed and before what is printed next), any other
/// descriptor opened for appending through `/dev/fd/N`.
fn write_stream(fd: u32, fill: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    match fd {
        1 => {
            let mut out = io::stdout().lock();
            let mut w = io::BufWriter::new(&mut out);
            fill(&mut w)?;
            w.flush()?;
            drop(w);
            out.flush()
        }
        2 => {
            let mut w = io::BufWriter::new(io::stderr().lock());
            fill(&mut w)?;
            w.flush()
        }
        _ => {
            let file = std::fs::OpenOptions::new()
                .append(true)
                .open(format!("/dev/fd/{fd}"))?;
            let mut w = io::BufWriter::new(file);
            fill(&mut w)?;
            w.flush()
        }
    }
}

/// Writes several outputs all or nothing: every regular file's bytes go to a synced
/// temporary file first, then devices, FIFOs and descriptors are written, and only when all
/// of that succeeded are the temporary files renamed over their targets, in order. On an
/// error before the renames no regular output changed and no temporary file is left; a
/// device or descriptor written before the failing one keeps what it got. (A rename failing
/// after others succeeded is the one partial outcome: each output was reserved only if a
/// rename can replace it ([`super::replace::barrier`]: permission, the immutable and
/// append-only attributes, a mount point, a sticky folder), so it takes a change to the file
/// system in between.)
pub fn write_together(outputs: Vec<(OutputFile, Vec<u8>)>) -> Result<()> {
    let (files, streams): (Vec<_>, Vec<_>) = outputs
        .into_iter()
        .partition(|(o, _)| matches!(o.route, Route::Replace { .. }));
    let mut staged = Vec::with_capacity(files.len());
    for (out, bytes) in files {
        staged.push(out.stage(|w| w.write_all(&bytes))?);
    }
    for (out, bytes) in streams {
        out.stage(|w| w.write_all(&bytes))?;
    }
    for s in staged {
        if let Staged::Temp { temp, target, dest } = s {
            temp.persist(&target).map_err(|e| Error::io(&dest, e))?;
        }
    }
    Ok(())
}

fn temp_in(dest: &Path, dir: &Path) -> Result<TempFile> {
    TempFile::create_in(dir).map_err(|e| {
        refuse(
            dest,
            e.kind(),
            format!(
                "cannot create a file in folder `{}`: {e}",
                crate::text::path(dir)
            ),
        )
    })
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::{FileTypeExt, PermissionsExt};

    fn write(dest: &Path, force: bool, bytes: &[u8]) -> Result<()> {
        OutputFile::reserve(dest, force)?.write(|w| w.write_all(bytes))
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn mode(p: &Path) -> u32 {
        std::fs::metadata(p).unwrap().permissions().mode() & 0o7777
    }

    #[test]
    fn failed_write_leaves_destination_and_folder_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("out.txt");
        std::fs::write(&dest, b"old").unwrap();
        let out = OutputFile::reserve(&dest, false).unwrap();
        assert_eq!(
            names(dir.path()),
            ["out.txt"],
            "reserved: no temporary file while the command works"
        );
        let err = out.write(|w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read(&dest).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["out.txt"], "temporary file removed");
        // Reserved but never written (the work failed): also no trace.
        drop(OutputFile::reserve(&dest, false).unwrap());
        assert_eq!(names(dir.path()), ["out.txt"]);
    }

    #[test]
    fn outputs_written_together_are_all_or_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.json");
        std::fs::write(&a, b"old").unwrap();
        let b = dir.path().join("b.png");
        let full = Path::new("/dev/full");
        // The device fails: neither regular file changes, nothing is left in the folder.
        let outs = vec![
            (OutputFile::reserve(&a, false).unwrap(), b"new".to_vec()),
            (OutputFile::reserve(full, false).unwrap(), b"x".to_vec()),
            (OutputFile::reserve(&b, false).unwrap(), b"png".to_vec()),
        ];
        assert!(write_together(outs).is_err());
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["a.json"]);
        let outs = vec![
            (OutputFile::reserve(&a, false).unwrap(), b"new".to_vec()),
            (OutputFile::reserve(&b, false).unwrap(), b"png".to_vec()),
        ];
        write_together(outs).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"new");
        assert_eq!(std::fs::read(&b).unwrap(), b"png");
    }

    #[test]
    fn symlinks_are_written_through_and_stay_links() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("real")).unwrap();
        let target = dir.path().join("real/t.txt");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink("real/t.txt", &link).unwrap();
        write(&link, false, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(names(&dir.path().join("real")), ["t.txt"]);
        // A dangling link gets its target created.
        let dangling = dir.path().join("dangling.txt");
        std::os::unix::fs::symlink("real/created.txt", &dangling).unwrap();
        write(&dangling, false, b"made").unwrap();
        assert!(std::fs::symlink_metadata(&dangling).unwrap().is_symlink());
        assert_eq!(
            std::fs::read(dir.path().join("real/created.txt")).unwrap(),
            b"made"
        );
    }

    #[test]
    fn devices_and_fifos_are_written_in_place() {
        let dir = tempfile::tempdir().unwrap();
        // A link to /dev/null: written through, /dev/null stays a character device.
        let null = dir.path().join("null");
        std::os::unix::fs::symlink("/dev/null", &null).unwrap();
        write(&null, false, b"discarded").unwrap();
        assert!(
            std::fs::metadata("/dev/null")
                .unwrap()
                .file_type()
                .is_char_device()
        );
        assert_eq!(names(dir.path()), ["null"]);
        // A FIFO gets the stream and stays a FIFO.
        let fifo = dir.path().join("fifo");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo (coreutils) runs");
        assert!(status.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(fifo).unwrap())
        };
        write(&fifo, false, b"streamed").unwrap();
        assert_eq!(reader.join().unwrap(), b"streamed");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
        assert_eq!(names(dir.path()), ["fifo", "null"]);
    }

    /// A private file's replacement has the private mode from its first byte: the
    /// temporary file, looked at while its bytes are written, is already `0600`.
    #[test]
    fn a_private_file_is_never_readable_by_others_while_written() {
        let dir = tempfile::tempdir().unwrap();
        let private = dir.path().join("private.obj");
        std::fs::write(&private, b"old").unwrap();
        std::fs::set_permissions(&private, Permissions::from_mode(0o600)).unwrap();
        let mut seen = Vec::new();
        OutputFile::reserve(&private, false)
            .unwrap()
            .write(|w| {
                w.write_all(b"new")?;
                for name in names(dir.path()).iter().filter(|n| n.ends_with(".tmp")) {
                    seen.push(mode(&dir.path().join(name)));
                }
                Ok(())
            })
            .unwrap();
        assert_eq!(seen, [0o600]);
        assert_eq!(std::fs::read(&private).unwrap(), b"new");
    }

    /// Standard input and a descriptor that is not open are refused when reserved (before
    /// the work), not found wrong after it.
    #[test]
    fn standard_input_and_closed_descriptors_are_not_outputs() {
        let e = OutputFile::reserve(Path::new("/dev/stdin"), true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("standard input"), "{e}");
        // A descriptor number far above any this test process opens.
        let e = OutputFile::reserve(Path::new("/dev/fd/4093"), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("descriptor 4093 is not open"), "{e}");
    }

    /// A replaced file keeps its owner and group where this process may set them: run as
    /// root (as CI is), a file of another user (`nobody`, uid 65534), set-group-ID bit
    /// included, stays theirs with its mode; the process's own file stays its own.
    #[test]
    fn owner_and_group_are_kept_where_the_process_may_set_them() {
        use std::os::unix::fs::{MetadataExt, chown};
        let dir = tempfile::tempdir().unwrap();
        let own = dir.path().join("own.txt");
        std::fs::write(&own, b"old").unwrap();
        let me = std::fs::metadata(&own).unwrap();
        write(&own, false, b"new").unwrap();
        let after = std::fs::metadata(&own).unwrap();
        assert_eq!((after.uid(), after.gid()), (me.uid(), me.gid()));
        let theirs = dir.path().join("theirs.txt");
        std::fs::write(&theirs, b"old").unwrap();
        if chown(&theirs, Some(65_534), Some(65_534)).is_err() {
            crate::skips::record_skip(
                "SKIPPED halfray outputs::file::tests::owner_and_group_are_kept_where_the_process_may_set_them: not root (no chown to another user)",
            );
            return;
        }
        std::fs::set_permissions(&theirs, Permissions::from_mode(0o2664)).unwrap();
        write(&theirs, false, b"new").unwrap();
        let after = std::fs::metadata(&theirs).unwrap();
        assert_eq!((after.uid(), after.gid()), (65_534, 65_534));
        assert_eq!(mode(&theirs), 0o2664);
        assert_eq!(std::fs::read(&theirs).unwrap(), b"new");
        assert_eq!(names(dir.path()), ["own.txt", "theirs.txt"]);
    }

    /// Sets extended attribute `name` of `path` to `value` (libc directly); whether it did.
    #[cfg(target_os = "linux")]
    fn set_xattr(path: &Path, name: &str, value: &[u8]) -> bool {
        use std::os::unix::ffi::OsStrExt;
        let p = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
        let n = std::ffi::CString::new(name).unwrap();
        // SAFETY: both strings are NUL-terminated and live across the call; `value` is
        // readable for its length.
        unsafe {
            libc::setxattr(
                p.as_ptr(),
                n.as_ptr(),
                value.as_ptr().cast(),
                value.len(),
                0,
            ) == 0
        }
    }

    /// The value of extended attribute `name` of `path` (libc directly), `None` when it has
    /// none.
    #[cfg(target_os = "linux")]
    fn get_xattr(path: &Path, name: &str) -> Option<Vec<u8>> {
        use std::os::unix::ffi::OsStrExt;
        let p = std::ffi::CString::new(path.as_os_str().as_bytes()).unwrap();
        let n = std::ffi::CString::new(name).unwrap();
        let mut buf = vec![0u8; 4096];
        // SAFETY: both strings are NUL-terminated and live across the call; `buf` is
        // writable for its length.
        let len =
            unsafe { libc::getxattr(p.as_ptr(), n.as_ptr(), buf.as_mut_ptr().cast(), buf.len()) };
        buf.truncate(usize::try_from(len).ok()?);
        Some(buf)
    }

    /// A POSIX ACL as the kernel's `system.posix_acl_*` value: version 2, then `(tag, perm,
    /// id)` entries (`acl_ea_entry` of `<linux/posix_acl_xattr.h>`).
    #[cfg(target_os = "linux")]
    fn acl(entries: &[(u16, u16, u32)]) -> Vec<u8> {
        let mut v = 2u32.to_le_bytes().to_vec();
        for &(tag, perm, id) in entries {
            v.extend(tag.to_le_bytes());
            v.extend(perm.to_le_bytes());
            v.extend(id.to_le_bytes());
        }
        v
    }

    /// A replaced file keeps its extended attributes: a `user.*` attribute, and an ACL
    /// (`user::rw-, user:65534:r--, group::r--, mask::rw-, other::---`) whose mask is the
    /// mode's group bits: the owning group stays `r--` (not the mask's `rw-` as a plain mode)
    /// and the named user keeps read access. A plain file in a folder whose default ACL
    /// a new file inherits is replaced without an ACL.
    #[cfg(target_os = "linux")]
    #[test]
    fn extended_attributes_and_the_acl_are_kept() {
        const ACL: &str = "system.posix_acl_access";
        const NONE: u32 = u32::MAX;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain.txt");
        std::fs::write(&plain, b"old").unwrap();
        let path = dir.path().join("shared.txt");
        std::fs::write(&path, b"old").unwrap();
        let access = acl(&[
            (0x01, 6, NONE),
            (0x02, 4, 65_534),
            (0x04, 4, NONE),
            (0x10, 6, NONE),
            (0x20, 0, NONE),
        ]);
        if !set_xattr(&path, "user.origin", b"scan 7") || !set_xattr(&path, ACL, &access) {
            crate::skips::record_skip(
                "SKIPPED halfray outputs::file::tests::extended_attributes_and_the_acl_are_kept: the temporary folder's file system takes no user attribute or ACL",
            );
            return;
        }
        let before = get_xattr(&path, ACL).expect("the ACL was set");
        assert_eq!(mode(&path) & 0o070, 0o060, "the mask as the group bits");
        write(&path, false, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(
            get_xattr(&path, "user.origin").as_deref(),
            Some(&b"scan 7"[..])
        );
        assert_eq!(get_xattr(&path, ACL), Some(before));
        assert_eq!(mode(&path) & 0o070, 0o060);
        // New files in the folder now get an ACL; the replaced plain file does not.
        assert!(set_xattr(dir.path(), "system.posix_acl_default", &access));
        let inherited = dir.path().join("inherited.txt");
        write(&inherited, false, b"new").unwrap();
        assert!(get_xattr(&inherited, ACL).is_some(), "a new file inherits");
        write(&plain, false, b"new").unwrap();
        assert_eq!(get_xattr(&plain, ACL), None);
        assert_eq!(
            names(dir.path()),
            ["inherited.txt", "plain.txt", "shared.txt"]
        );
    }

    #[test]
    fn mode_is_kept_and_read_only_or_hard_linked_files_need_force() {
        let dir = tempfile::tempdir().unwrap();
        let private = dir.path().join("private.txt");
        std::fs::write(&private, b"old").unwrap();
        std::fs::set_permissions(&private, Permissions::from_mode(0o600)).unwrap();
        write(&private, false, b"new").unwrap();
        assert_eq!(mode(&private), 0o600);
        assert_eq!(std::fs::read(&private).unwrap(), b"new");

        let ro = dir.path().join("ro.txt");
        std::fs::write(&ro, b"keep").unwrap();
        std::fs::set_permissions(&ro, Permissions::from_mode(0o444)).unwrap();
        let e = write(&ro, false, b"new").unwrap_err().to_string();
        assert!(
            e.contains("read-only (mode 0444)") && e.contains("--force"),
            "{e}"
        );
        assert_eq!(std::fs::read(&ro).unwrap(), b"keep");
        write(&ro, true, b"forced").unwrap();
        assert_eq!(std::fs::read(&ro).unwrap(), b"forced");
        assert_eq!(mode(&ro), 0o444);

        let a = dir.path().join("a.txt");
        let b = dir.path().join("b.txt");
        std::fs::write(&a, b"shared").unwrap();
        std::fs::hard_link(&a, &b).unwrap();
        let e = write(&a, false, b"new").unwrap_err().to_string();
        assert!(e.contains("2 hard links"), "{e}");
        assert_eq!(std::fs::read(&b).unwrap(), b"shared");
        write(&a, true, b"new").unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"new");
        assert_eq!(std::fs::read(&b).unwrap(), b"shared", "forced: link split");
        assert_eq!(
            names(dir.path()),
            ["a.txt", "b.txt", "private.txt", "ro.txt"]
        );
    }

    #[test]
    fn longest_valid_name_works_and_bad_locations_fail_at_reserve() {
        let dir = tempfile::tempdir().unwrap();
        let long = dir.path().join("x".repeat(254));
        write(&long, false, b"ok").unwrap();
        assert_eq!(std::fs::read(&long).unwrap(), b"ok");
        assert_eq!(names(dir.path()).len(), 1);

        let e = OutputFile::reserve(&dir.path().join("nodir/x.png"), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not exist"), "{e}");
        let e = OutputFile::reserve(&long.join("x.png"), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is not a folder"), "{e}");
        let e = OutputFile::reserve(dir.path(), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a directory"), "{e}");
    }

    /// A name that can only be a folder's (a trailing separator, a last `.` or `..`) is
    /// refused at reserve, whether something by that name exists as a file or nothing does:
    /// such a name passed the folder check (its parent is the folder) and failed only at the
    /// rename, after the work and after the outputs written before it.
    #[test]
    fn a_name_that_can_only_be_a_folder_fails_at_reserve() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("out.png");
        std::fs::write(&file, b"prior").unwrap();
        for name in [
            "out.png/",
            "new.json/",
            "new.json//",
            "new/.",
            "new/..",
            "out.png/.",
        ] {
            let dest = PathBuf::from(format!("{}/{name}", dir.path().display()));
            let e = OutputFile::reserve(&dest, true).unwrap_err().to_string();
            assert!(e.contains("names a folder"), "{name}: {e}");
        }
        assert_eq!(std::fs::read(&file).unwrap(), b"prior");
        assert_eq!(names(dir.path()), ["out.png"]);
        // Names that end like these but are files' names are still taken.
        for name in ["a.", "a..", ".a", "..a"] {
            write(&dir.path().join(name), false, b"ok").unwrap();
        }
        assert_eq!(names(dir.path()).len(), 5);
    }
}
