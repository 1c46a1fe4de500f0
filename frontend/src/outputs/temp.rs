//! Temporary files next to an output, and their removal on every way out: drop (errors,
//! panics that unwind), and SIGINT/SIGTERM/SIGHUP once [`install_signal_cleanup`] ran.
//!
//! Names are `.halfray-<pid>-<n>.tmp`, at most [`MAX_TEMP_NAME_LEN`] bytes whatever the
//! output is called, so an output whose own name is at the file-system limit (255 bytes on
//! Linux) still gets a temporary file.
//!
//! What no handler can catch (SIGKILL, the OOM killer, an abort, SIGQUIT) leaves the file
//! behind; the name says which process made it, so the next temporary file created in that
//! folder removes it ([`remove_stale`]): a `.halfray-<pid>-<n>.tmp` whose process is gone (or
//! that bears this process's pid but is none of its live temporary files: a run before it
//! had the same pid, as every run in a container is pid 1) and which was last modified
//! [`STALE_TEMP_AGE`] ago or more.

use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Longest temporary file name, in bytes: `.halfray-` (9) + a `u32` pid (≤ 10) + `-` + a `u64`
/// counter (≤ 20) + `.tmp` (4).
pub const MAX_TEMP_NAME_LEN: usize = 9 + 10 + 1 + 20 + 4;

/// Names tried before giving up when they already exist (left by another process).
pub const MAX_TEMP_NAME_TRIES: u32 = 100;

/// How old a dead process's (or a previous run's) temporary file must be before
/// [`remove_stale`] removes it: one hour. A temporary file exists only while its output is
/// being written (seconds); the age guards a file of a process on another machine sharing
/// the folder (whose pid means nothing here) that is still being written.
pub const STALE_TEMP_AGE: std::time::Duration = std::time::Duration::from_secs(3600);

/// Temporary files that exist right now, removed by the signal handler.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static COUNTER: AtomicU64 = AtomicU64::new(0);

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while holding the lock leaves a list that is still valid.
    LIVE.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A temporary file, removed when dropped unless [`TempFile::persist`]ed.
#[derive(Debug)]
pub struct TempFile {
    path: PathBuf,
    file: Option<File>,
}

impl TempFile {
    /// Creates a new, empty temporary file in `dir` (never one that exists: `O_EXCL`).
    pub fn create_in(dir: &Path) -> io::Result<Self> {
        remove_stale(dir);
        let mut last = None;
        for _ in 0..MAX_TEMP_NAME_TRIES {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let name = format!(".halfray-{}-{n}.tmp", std::process::id());
            debug_assert!(name.len() <= MAX_TEMP_NAME_LEN);
            let path = dir.join(name);
            let mut registry = live();
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(file) => {
                    registry.push(path.clone());
                    return Ok(Self {
                        path,
                        file: Some(file),
                    });
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last = Some(e),
                Err(e) => return Err(e),
            }
        }
        Err(last.unwrap_or_else(|| io::Error::other("no free temporary file name")))
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The open file.
    pub fn file(&mut self) -> io::Result<&mut File> {
        self.file
            .as_mut()
            .ok_or_else(|| io::Error::other("temporary file already closed"))
    }

    /// Renames it to `dest` (same folder, so atomic) and forgets it.
    pub fn persist(mut self, dest: &Path) -> io::Result<()> {
        drop(self.file.take());
        let mut registry = live();
        std::fs::rename(&self.path, dest)?;
        registry.retain(|p| p != &self.path);
        self.path = PathBuf::new();
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.path.as_os_str().is_empty() {
            return;
        }
        drop(self.file.take());
        let mut registry = live();
        let _ = std::fs::remove_file(&self.path);
        registry.retain(|p| p != &self.path);
    }
}

/// The pid in a temporary file's name (`.halfray-<pid>-<n>.tmp`), `None` for other names.
fn temp_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(".halfray-")?.strip_suffix(".tmp")?;
    let (pid, n) = rest.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether process `pid` is known to be gone: only where `/proc` lists processes (Linux);
/// elsewhere nothing is known, and nothing is removed.
fn process_gone(pid: u32) -> bool {
    Path::new("/proc/self").exists() && !Path::new(&format!("/proc/{pid}")).exists()
}

/// Whether this process has a live temporary file named `name` (in any folder: the counter
/// in the name is unique within the process).
fn is_live(name: &std::ffi::OsStr) -> bool {
    live().iter().any(|p| p.file_name() == Some(name))
}

/// Removes from `dir` the temporary files of processes that are gone, and those with this
/// process's pid that are not its own (see the module docs). Best effort: errors are ignored
/// (another run may be removing the same file).
pub fn remove_stale(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let me = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_pid) else {
            continue;
        };
        let old = entry
            .metadata()
            .ok()
            .filter(|m| m.is_file())
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age >= STALE_TEMP_AGE);
        let orphan = if pid == me {
            !is_live(&name)
        } else {
            process_gone(pid)
        };
        if old && orphan {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Removes every live temporary file (what the signal handler does before exiting).
pub fn remove_live_temp_files() {
    for p in live().drain(..) {
        let _ = std::fs::remove_file(p);
    }
}

/// Starts a thread that, on SIGINT, SIGTERM or SIGHUP, removes the live temporary files and
/// exits with status 128 + the signal number (what a shell reports for a process the signal
/// killed). Call once, from `main`.
#[cfg(unix)]
pub fn install_signal_cleanup() -> io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new()
        .name("signal-cleanup".into())
        .spawn(move || {
            if let Some(sig) = signals.forever().next() {
                // Holding the lock while exiting keeps a rename from completing afterwards.
                let mut registry = live();
                for p in registry.drain(..) {
                    let _ = std::fs::remove_file(p);
                }
                std::process::exit(128 + sig);
            }
        })?;
    Ok(())
}

/// Signals are a Unix notion; elsewhere temporary files are removed on drop only.
#[cfg(not(unix))]
pub fn install_signal_cleanup() -> io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dropped_temp_files_are_removed_and_persisted_ones_renamed() {
        let dir = tempfile::tempdir().unwrap();
        let t = TempFile::create_in(dir.path()).unwrap();
        let name = t.path().file_name().unwrap().len();
        assert!(name <= MAX_TEMP_NAME_LEN, "{name}");
        assert!(t.path().exists());
        let p = t.path().to_path_buf();
        assert!(live().contains(&p));
        drop(t);
        assert!(!p.exists());
        assert!(!live().contains(&p));
        let mut t = TempFile::create_in(dir.path()).unwrap();
        io::Write::write_all(t.file().unwrap(), b"data").unwrap();
        let dest = dir.path().join("dest");
        t.persist(&dest).unwrap();
        assert_eq!(std::fs::read(&dest).unwrap(), b"data");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    /// Removed: old files of a gone process, and an old file with this process's pid that is
    /// not one of its live files (a previous run's under the same pid, as in a container).
    /// Kept: recent ones, this process's own live file however old, other names.
    #[test]
    fn stale_temp_files_of_gone_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // A process that has exited: its pid is free (and not reused within the test).
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let gone = child.id();
        child.wait().unwrap();
        let old = std::time::SystemTime::now() - STALE_TEMP_AGE - std::time::Duration::from_secs(1);
        let make = |name: &str, aged: bool| {
            let f = std::fs::File::create(dir.path().join(name)).unwrap();
            if aged {
                f.set_modified(old).unwrap();
            }
        };
        make(&format!(".halfray-{gone}-3.tmp"), true);
        make(&format!(".halfray-{gone}-4.tmp"), false);
        let me = std::process::id();
        // Far above this process's counter (files of a previous run under the same pid).
        make(&format!(".halfray-{me}-{}.tmp", u64::MAX - 5), true);
        make(&format!(".halfray-{me}-{}.tmp", u64::MAX - 6), false);
        make(".halfray-x-1.tmp", true);
        make("keep.png", true);
        let mut mine = TempFile::create_in(dir.path()).unwrap();
        mine.file().unwrap().set_modified(old).unwrap();
        let mine_name = mine
            .path()
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .to_owned();
        drop(TempFile::create_in(dir.path()).unwrap());
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        let mut want = vec![
            format!(".halfray-{gone}-4.tmp"),
            format!(".halfray-{me}-{}.tmp", u64::MAX - 6),
            mine_name,
            ".halfray-x-1.tmp".to_string(),
            "keep.png".to_string(),
        ];
        want.sort();
        assert_eq!(names, want, "only the old orphans go");
        drop(mine);
    }

    /// Two writes to one folder from one process at the same time never share a temporary
    /// file: 8 threads × 50 files at once, each written with its own content and persisted
    /// under its own name; every file ends with exactly its writer's bytes and no temporary
    /// file is left over.
    #[test]
    fn concurrent_temp_files_in_one_folder_never_collide() {
        let dir = tempfile::tempdir().unwrap();
        std::thread::scope(|s| {
            for thread in 0..8 {
                let dir = dir.path();
                s.spawn(move || {
                    for k in 0..50 {
                        let mut t = TempFile::create_in(dir).unwrap();
                        let body = format!("{thread}-{k}");
                        io::Write::write_all(t.file().unwrap(), body.as_bytes()).unwrap();
                        t.persist(&dir.join(format!("out-{thread}-{k}"))).unwrap();
                    }
                });
            }
        });
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(names.len(), 400, "{names:?}");
        for name in names {
            let body = std::fs::read_to_string(dir.path().join(&name)).unwrap();
            assert_eq!(Some(body.as_str()), name.strip_prefix("out-"), "{name}");
        }
    }
}
