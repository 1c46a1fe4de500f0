//! Corpora: `--mesh-list FILE` and the resumable JSON-lines results log (`--jsonl`).
//!
//! The log holds one [`MeshResult`] per line, appended and flushed to disk as each mesh
//! finishes, so a run that is killed loses at most the mesh in progress. `--resume` reads the
//! log back, drops a torn last line (a write cut off mid-line), checks that every line belongs
//! to the same run (intersector, seed, rays, sets, shard) and skips the meshes already checked;
//! meshes that failed are tried again and their new line appended. When a log is read, the
//! last line of a failed mesh wins; a mesh checked without error comes once per shard
//! ([`parse_log`]).

use super::report::{MeshResult, RunConfig};
use super::shard::Shard;
use crate::error::{Error, Location, Result, json_message};
use crate::outputs::{FileId, Named, file_id, first_repeat};
use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The mesh paths of a list file, each with its 1-based line: one per line, surrounding
/// whitespace trimmed, blank lines and lines starting with `#` skipped (a `#` later in a line
/// is part of the path: `a#1.obj` is a file name), a leading UTF-8 byte-order mark ignored. Relative paths are relative to the current directory (as
/// `find … > list` writes them), not to the list file.
pub fn read_mesh_list(list: &Path) -> Result<Vec<(PathBuf, usize)>> {
    // `read_text` drops a byte-order mark: it is no part of the first path.
    let text = crate::input::read_text(list, "text (one mesh path per line)")?;
    Ok(text
        .lines()
        .enumerate()
        .map(|(i, l)| (l.trim(), i + 1))
        .filter(|(l, _)| !l.is_empty() && !l.starts_with('#'))
        .map(|(l, line)| (PathBuf::from(l), line))
        .collect())
}

/// The meshes of a run: those named as arguments, then `list`'s ([`read_mesh_list`]).
pub struct RunMeshes {
    /// Every mesh, in run order.
    pub paths: Vec<PathBuf>,
    /// Where each was named: `None` for an argument, the list's file and line for an entry.
    pub named_at: Vec<Option<Location>>,
}

impl RunMeshes {
    /// Reads `list` (when given) after the `meshes` named as arguments; a usage error naming
    /// `what` the run does when there are none ("no meshes to benchmark").
    pub fn read(meshes: &[PathBuf], list: Option<&Path>, what: &str) -> Result<Self> {
        let mut run = Self {
            paths: meshes.to_vec(),
            named_at: vec![None; meshes.len()],
        };
        if let Some(list) = list {
            for (path, line) in read_mesh_list(list)? {
                run.paths.push(path);
                run.named_at.push(Some(Location::file(list).line(line)));
            }
        }
        if run.paths.is_empty() {
            return Err(Error::Usage(format!("no meshes to {what}")));
        }
        Ok(run)
    }

    /// `e`, an error of mesh `k`'s run, with the list line that named the mesh when an
    /// input error names another place (the mesh file's own line): `bunny.obj:7:3: … (named
    /// at list.txt:2)`. Other errors, and meshes named as arguments, unchanged.
    pub fn noting_list(&self, k: usize, e: Error) -> Error {
        noting_list_line(self.named_at.get(k).and_then(Option::as_ref), e)
    }

    /// Refuses a run that names one mesh file twice (the same path again, another spelling,
    /// a symlink): its figures would count twice. The usage error names the later path and
    /// the earlier one (each with its list line) and says each mesh is `done` once
    /// ("checked"). A path that cannot be identified (a missing file) is not compared: it
    /// fails when its turn comes.
    pub fn refuse_repeated(&self, done: &str) -> Result<()> {
        let ids: Vec<Option<FileId>> = self.paths.iter().map(|m| file_id(m).ok()).collect();
        let Some((j, k)) = first_repeat(ids.iter().map(Option::as_ref)) else {
            return Ok(());
        };
        let at = |i: usize| match &self.named_at[i] {
            Some(at) => format!(" (named at {at})"),
            None => String::new(),
        };
        Err(Error::Usage(format!(
            "mesh `{}`{} is mesh `{}`{} again (the same file): each mesh is {done} once",
            crate::text::path(&self.paths[k]),
            at(k),
            crate::text::path(&self.paths[j]),
            at(j),
        )))
    }
}

/// `e`, an error of a mesh that the list line `listed` named (`None` for a mesh named as an
/// argument), with that line when an input error names another place (the mesh file's own
/// line): `bunny.obj:7:3: … (named at list.txt:2)`. Other errors, and `None`, unchanged.
pub fn noting_list_line(listed: Option<&Location>, e: Error) -> Error {
    match (e, listed) {
        (Error::Input { at, message }, Some(listed)) if at != *listed => {
            Error::input(at, format!("{message} (named at {listed})"))
        }
        (e, _) => e,
    }
}

/// The inputs of a run over `meshes`, some of them named by the file `list`, as the messages
/// name them (`mesh`, `--mesh-list`): what no output of the run may be.
pub fn run_inputs<'a>(meshes: &'a [PathBuf], list: Option<&'a Path>) -> Vec<Named<'a>> {
    let mut inputs: Vec<Named<'a>> = meshes.iter().map(|p| Named::new("mesh", p)).collect();
    inputs.extend(list.map(|p| Named::new("--mesh-list", p)));
    inputs
}

/// Parses the complete lines of a results log (`text` ends at a newline or is empty).
/// Every line must be a [`MeshResult`]. A mesh that failed may come again in the same shard
/// (a resumed run checks it again: the later line wins); a mesh checked without error comes
/// once per shard, and a later line for it is an input error naming both lines (no run writes
/// one, and keeping either would hide the other's counts).
pub fn parse_log(path: &Path, text: &str) -> Result<Vec<MeshResult>> {
    // Keyed by mesh and shard: a concatenation of shard logs holds each mesh once per shard
    // (all kept). The line number of each key's latest line.
    let mut order: Vec<(String, Shard)> = Vec::new();
    let mut latest: HashMap<(String, Shard), (usize, MeshResult)> = HashMap::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let result: MeshResult = serde_json::from_str(line).map_err(|e| {
            Error::input(
                Location::file(path).line(i + 1).json_position(&e),
                format!("not a cross-check result line: {}", json_message(&e)),
            )
        })?;
        let key = (result.path.clone(), result.config.shard);
        match latest.get(&key) {
            None => order.push(key.clone()),
            Some((at, earlier)) if earlier.error.is_none() => {
                return Err(Error::input(
                    Location::file(path).line(i + 1),
                    format!(
                        "mesh `{}` (shard {}) was checked already at line {}: a results log holds a checked mesh once per shard",
                        result.path,
                        result.config.shard,
                        at + 1
                    ),
                ));
            }
            Some(_) => {}
        }
        latest.insert(key, (i, result));
    }
    Ok(order
        .into_iter()
        .filter_map(|p| latest.remove(&p).map(|(_, r)| r))
        .collect())
}

/// An open results log.
pub struct ResultLog {
    path: PathBuf,
    file: File,
    done: HashMap<String, MeshResult>,
    /// The file identities of `done`'s paths, for a mesh spelt otherwise in this run.
    ids: HashMap<FileId, String>,
}

/// How every line of a results log starts (`MeshResult` serialises its path first): a torn
/// last line is dropped only when it is a beginning of such a line.
const LINE_START: &str = "{\"path\":";

impl ResultLog {
    /// Opens `path` for this run. It must be a regular file (or not exist yet), writable and
    /// with one name (a hard link would change under its other names too). A stream (`-`,
    /// `/dev/stdout`) is a usage error, since `--resume` reads the log back; a missing folder,
    /// a folder, device or FIFO, a read-only or hard-linked file is an I/O error naming the
    /// path, as for every other output (exit 1).
    /// Without `resume`, an existing non-empty file is refused (its results would be lost);
    /// with it, the file is read back (see the module docs) and every line must belong to
    /// `config`'s run. Nothing is written to the file until all of that has been checked: a
    /// file that is not such a log, or the log of another run, is left as it was.
    pub fn open(path: &Path, resume: bool, config: &RunConfig) -> Result<Self> {
        use crate::outputs::target::{Target, resolve};
        let refuse =
            |kind: std::io::ErrorKind, why: String| Error::io(path, std::io::Error::new(kind, why));
        let bytes = match resolve(path).map_err(|e| Error::io(path, e))? {
            Target::Missing { path: target } => {
                let folder = crate::outputs::file::folder_of(&target);
                if !folder.is_dir() {
                    return Err(refuse(
                        std::io::ErrorKind::NotFound,
                        format!("folder `{}` does not exist", crate::text::path(folder)),
                    ));
                }
                Vec::new()
            }
            Target::Stream { .. } => {
                return Err(Error::Usage(format!(
                    "--jsonl `{}` names a stream: the results log must be a file, since --resume reads it back",
                    crate::text::path(path)
                )));
            }
            Target::Special { .. } | Target::Directory { .. } => {
                return Err(refuse(
                    std::io::ErrorKind::InvalidInput,
                    "is not a regular file: the results log is appended to and read back by --resume"
                        .into(),
                ));
            }
            Target::Regular { permissions, .. } if permissions.readonly() => {
                return Err(refuse(
                    std::io::ErrorKind::PermissionDenied,
                    "is read-only".into(),
                ));
            }
            Target::Regular { links, .. } if links > 1 => {
                return Err(refuse(
                    std::io::ErrorKind::InvalidInput,
                    "has more than one hard link: appending would change the file under its other names too"
                        .into(),
                ));
            }
            Target::Regular { .. } => crate::input::read_bytes(path)?,
        };
        if !resume && !bytes.is_empty() {
            return Err(Error::Usage(format!(
                "--jsonl `{}` is not empty: pass --resume to continue the run it logs, or choose another file",
                crate::text::path(path)
            )));
        }
        let mut complete = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        // A last line without its newline that is a whole result is kept (the newline is
        // added); one that is the beginning of a result is torn (a write cut off mid-line)
        // and dropped, so its mesh is checked again; anything else is not a results log.
        let tail = &bytes[complete..];
        let whole_tail = !tail.is_empty() && serde_json::from_slice::<MeshResult>(tail).is_ok();
        if whole_tail {
            complete = bytes.len();
        }
        let text = std::str::from_utf8(&bytes[..complete])
            .map_err(|_| Error::input(Location::file(path), "is not UTF-8 text (a results log)"))?;
        let torn = &bytes[complete..];
        // A write cut off mid-line is never a whole JSON value: one that is (`{"path":"x"}`,
        // a hand-written note) is not a torn result, and is not dropped.
        let whole_value =
            !torn.is_empty() && serde_json::from_slice::<serde::de::IgnoredAny>(torn).is_ok();
        let begins_a_line = !whole_value
            && (torn.starts_with(LINE_START.as_bytes()) || LINE_START.as_bytes().starts_with(torn));
        if !begins_a_line {
            return Err(Error::input(
                Location::file(path).line(1 + text.lines().count()),
                "is not a results log: its last line is neither a result nor the beginning of one",
            ));
        }
        let mut done = HashMap::new();
        for result in parse_log(path, text)? {
            if let Some(diff) = result.config.difference(config) {
                return Err(Error::Usage(format!(
                    "--resume: `{}` holds results of another run (log vs this run: {diff}; mesh `{}`)",
                    crate::text::path(path),
                    crate::text::escaped(&result.path)
                )));
            }
            if result.config.shard != config.shard {
                return Err(Error::Usage(format!(
                    "--resume: `{}` holds shard {} results, this run is shard {}",
                    crate::text::path(path),
                    result.config.shard,
                    config.shard
                )));
            }
            if result.error.is_none() {
                done.insert(result.path.clone(), result);
            }
        }
        // Checked: from here on the file is this run's log.
        let mut file = OpenOptions::new()
            .append(true)
            .create(true)
            .open(path)
            .map_err(|e| Error::io(path, e))?;
        if whole_tail {
            file.write_all(b"\n").map_err(|e| Error::io(path, e))?;
        } else if !torn.is_empty() {
            crate::note!(
                "crosscheck: {}: dropping a torn last line ({} bytes); its mesh is checked again",
                crate::text::path(path),
                torn.len()
            );
            file.set_len(complete as u64)
                .and_then(|()| file.seek(SeekFrom::End(0)).map(|_| ()))
                .map_err(|e| Error::io(path, e))?;
        }
        let ids = done
            .keys()
            .filter_map(|k| Some((file_id(Path::new(k)).ok()?, k.clone())))
            .collect();
        Ok(Self {
            path: path.to_path_buf(),
            file,
            done,
            ids,
        })
    }

    /// The result already in the log for `mesh` (checked successfully), if any: logged under
    /// the same spelling, or under another path of the same file (`./a.obj`, a symlink).
    pub fn done(&self, mesh: &Path) -> Option<&MeshResult> {
        self.done.get(&mesh.display().to_string()).or_else(|| {
            let key = self.ids.get(&file_id(mesh).ok()?)?;
            self.done.get(key)
        })
    }

    /// Appends `result` as one line and flushes it to disk.
    pub fn append(&mut self, result: &MeshResult) -> Result<()> {
        let mut line =
            serde_json::to_vec(result).map_err(|e| Error::encode("a results-log line", e))?;
        line.push(b'\n');
        self.file
            .write_all(&line)
            .and_then(|()| self.file.sync_data())
            .map_err(|e| Error::io(&self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crosscheck::report::SetReport;
    use crate::crosscheck::shard::Shard;

    fn config() -> RunConfig {
        RunConfig {
            intersector: "watertight".into(),
            seed: 1,
            rays: 10,
            ray_sets: vec!["primary".into()],
            shard: Shard::WHOLE,
        }
    }

    fn ok(path: &str) -> MeshResult {
        MeshResult {
            path: path.into(),
            config: config(),
            error: None,
            sets: vec![SetReport {
                path: path.into(),
                name: "primary".into(),
                rays: 10,
                agree: 10,
                ..SetReport::default()
            }],
        }
    }

    #[test]
    fn mesh_list_skips_blanks_and_comments() {
        let dir = tempfile::tempdir().unwrap();
        let list = dir.path().join("list.txt");
        std::fs::write(&list, "a.obj\n\n# comment\n  b/c.obj  \r\nd.obj").unwrap();
        assert_eq!(
            read_mesh_list(&list).unwrap(),
            [("a.obj", 1), ("b/c.obj", 4), ("d.obj", 5)].map(|(p, l)| (PathBuf::from(p), l))
        );
        std::fs::write(&list, "\u{feff}a.obj\r\nb.obj\n").unwrap();
        assert_eq!(
            read_mesh_list(&list).unwrap(),
            [("a.obj", 1), ("b.obj", 2)].map(|(p, l)| (PathBuf::from(p), l)),
            "a byte-order mark is skipped"
        );
        // A `#` after the start is the path's: there are no trailing comments.
        std::fs::write(
            &list,
            "  # indented comment\nx#1/a.obj\ntet.obj # trailing\n",
        )
        .unwrap();
        assert_eq!(
            read_mesh_list(&list).unwrap(),
            [("x#1/a.obj", 2), ("tet.obj # trailing", 3)].map(|(p, l)| (PathBuf::from(p), l))
        );
        std::fs::write(&list, b"a.obj\n\xff.obj\n").unwrap();
        let e = read_mesh_list(&list).unwrap_err().to_string();
        assert!(e.contains("list.txt:2"), "{e}");
    }

    /// A log in a folder that does not exist is an I/O error (exit 1, as for every other
    /// output) naming the folder, and nothing is created.
    #[test]
    fn a_log_in_a_missing_folder_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing/out.jsonl");
        let e = ResultLog::open(&path, false, &config()).err().unwrap();
        assert_eq!(e.exit_code(), 1, "{e}");
        let e = e.to_string();
        assert!(
            e.contains("does not exist") && e.contains("missing`"),
            "{e}"
        );
        assert!(!dir.path().join("missing").exists());
    }

    #[test]
    fn log_round_trips_and_resume_skips_exactly_the_done_meshes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.jsonl");
        let mut log = ResultLog::open(&path, false, &config()).unwrap();
        log.append(&ok("a.obj")).unwrap();
        let mut failed = ok("b.obj");
        failed.error = Some("b.obj:3:1: bad".into());
        failed.sets.clear();
        log.append(&failed).unwrap();
        log.append(&ok("c.obj")).unwrap();
        drop(log);
        // A torn line, as a killed run leaves it.
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(br#"{"path":"d.obj","intersec"#).unwrap();
        drop(f);

        let log = ResultLog::open(&path, true, &config()).unwrap();
        assert_eq!(log.done(Path::new("a.obj")), Some(&ok("a.obj")));
        assert_eq!(log.done(Path::new("c.obj")), Some(&ok("c.obj")));
        assert!(
            log.done(Path::new("b.obj")).is_none(),
            "a failed mesh is tried again"
        );
        assert!(
            log.done(Path::new("d.obj")).is_none(),
            "a torn line is not a result"
        );
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.ends_with('\n') && !text.contains("d.obj"),
            "torn line dropped"
        );
        assert_eq!(parse_log(&path, &text).unwrap().len(), 3);
    }

    /// A failed mesh checked again by a resumed run: the later line wins. A mesh checked
    /// without error and then again (a line no run writes; an edited or doubled log): refused,
    /// naming both lines, whichever of the two holds more mismatches (a later line of 0
    /// genuine mismatches would have hidden an earlier one of 5, exit 0 instead of 3).
    #[test]
    fn a_checked_mesh_comes_once_per_shard_in_a_log() {
        let path = Path::new("log.jsonl");
        let line = |r: &MeshResult| serde_json::to_string(r).unwrap() + "\n";
        let mut failed = ok("b.obj");
        failed.error = Some("b.obj:3:1: bad".into());
        failed.sets.clear();
        let text = line(&ok("a.obj")) + &line(&failed) + &line(&ok("b.obj"));
        let parsed = parse_log(path, &text).unwrap();
        assert_eq!(parsed, [ok("a.obj"), ok("b.obj")]);
        let mut worse = ok("a.obj");
        worse.sets[0].genuine_mismatches = 5;
        for (text, want) in [
            (
                line(&worse) + &line(&ok("b.obj")) + &line(&ok("a.obj")),
                "log.jsonl:3: mesh `a.obj` (shard 0/1) was checked already at line 1",
            ),
            (
                line(&ok("a.obj")) + &line(&ok("b.obj")) + &line(&worse),
                "log.jsonl:3: mesh `a.obj` (shard 0/1) was checked already at line 1",
            ),
            (
                line(&failed) + &line(&ok("b.obj")) + &line(&failed),
                "log.jsonl:3: mesh `b.obj` (shard 0/1) was checked already at line 2",
            ),
        ] {
            let e = parse_log(path, &text).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
        }
    }

    #[test]
    fn log_refuses_to_lose_or_mix_results() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.jsonl");
        let mut log = ResultLog::open(&path, false, &config()).unwrap();
        log.append(&ok("a.obj")).unwrap();
        drop(log);
        let e = ResultLog::open(&path, false, &config()).err().unwrap();
        assert!(e.to_string().contains("--resume"), "{e}");
        assert_eq!(std::fs::read_to_string(&path).unwrap().lines().count(), 1);
        let mut other = config();
        other.rays = 11;
        let e = ResultLog::open(&path, true, &other).err().unwrap();
        assert!(e.to_string().contains("rays 10 vs 11"), "{e}");
        other = config();
        other.shard = Shard::new(1, 2).unwrap();
        let e = ResultLog::open(&path, true, &other).err().unwrap();
        assert!(e.to_string().contains("shard 0/1"), "{e}");
        std::fs::write(&path, "{\"path\": 3}\n").unwrap();
        let e = ResultLog::open(&path, true, &config()).err().unwrap();
        assert!(e.to_string().contains("out.jsonl:1:"), "{e}");
    }

    /// `--resume` changes the file only once it is known to be this run's log: a file of
    /// another kind, or another run's log with a torn last line, is left byte for byte.
    #[test]
    fn resume_leaves_a_file_that_is_not_this_runs_log_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.jsonl");
        let mut other = config();
        other.rays = 11;
        let mut log = ResultLog::open(&path, false, &other).unwrap();
        for mesh in ["a.obj", "b.obj"] {
            let mut result = ok(mesh);
            result.config = other.clone();
            log.append(&result).unwrap();
        }
        drop(log);
        let whole = std::fs::read(&path).unwrap();
        let torn = &whole[..whole.len() - 10]; // the last line cut off mid-line
        let unended = &whole[..whole.len() - 1]; // the last line without its newline
        let cases: [(&str, &[u8], &str); 6] = [
            ("another run's log, torn", torn, "rays 11 vs 10"),
            ("another run's log, unended", unended, "rays 11 vs 10"),
            ("notes", b"my notes", "is not a results log"),
            (
                "an image",
                b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\xff\xfe",
                "is not UTF-8",
            ),
            (
                "text, then a torn line",
                b"{\"path\":\"a.obj\"\n",
                "out.jsonl:1:",
            ),
            (
                "a whole JSON object that is not a result, unended",
                b"{\"path\":\"cube.obj\",\"note\":\"keep me\"}",
                "is not a results log",
            ),
        ];
        for (what, bytes, want) in cases {
            std::fs::write(&path, bytes).unwrap();
            let e = ResultLog::open(&path, true, &config())
                .err()
                .unwrap()
                .to_string();
            assert!(e.contains(want), "{what}: {e}");
            assert_eq!(std::fs::read(&path).unwrap(), bytes, "{what}: file changed");
        }
    }

    #[test]
    fn a_results_log_is_a_writable_regular_file_with_one_name() {
        let dir = tempfile::tempdir().unwrap();
        let line = format!("{}\n", serde_json::to_string(&ok("a.obj")).unwrap());
        let path = dir.path().join("out.jsonl");
        std::fs::write(&path, &line).unwrap();
        let link = dir.path().join("link.jsonl");
        std::fs::hard_link(&path, &link).unwrap();
        let e = ResultLog::open(&link, true, &config()).err().unwrap();
        assert_eq!(e.exit_code(), 1, "{e}");
        assert!(e.to_string().contains("hard link"), "{e}");
        std::fs::remove_file(&link).unwrap();
        let mut perms = std::fs::metadata(&path).unwrap().permissions();
        perms.set_readonly(true);
        std::fs::set_permissions(&path, perms).unwrap();
        let e = ResultLog::open(&path, true, &config()).err().unwrap();
        assert_eq!(e.exit_code(), 1, "{e}");
        assert!(e.to_string().contains("is read-only"), "{e}");
        for stream in ["-", "/dev/stdout", "/dev/fd/1"] {
            let e = ResultLog::open(Path::new(stream), false, &config())
                .err()
                .unwrap();
            assert!(matches!(e, Error::Usage(_)), "{stream}: {e}");
            assert!(e.to_string().contains("names a stream"), "{stream}: {e}");
        }
        for special in ["/dev/null", "/tmp"] {
            let e = ResultLog::open(Path::new(special), false, &config())
                .err()
                .unwrap();
            assert_eq!(e.exit_code(), 1, "{special}: {e}");
            assert!(
                e.to_string().contains("not a regular file"),
                "{special}: {e}"
            );
        }
        assert!(!Path::new("-").exists(), "no file named `-` was created");
        // A whole result without its newline is kept, the newline added.
        let mut perms = std::fs::metadata(&path).unwrap().permissions();
        #[allow(clippy::permissions_set_readonly_false)]
        perms.set_readonly(false);
        std::fs::set_permissions(&path, perms).unwrap();
        std::fs::write(&path, line.trim_end()).unwrap();
        let log = ResultLog::open(&path, true, &config()).unwrap();
        assert_eq!(log.done(Path::new("a.obj")), Some(&ok("a.obj")));
        drop(log);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), line);
    }

    /// A mesh logged under one spelling is done under any other path of the same file.
    #[test]
    fn a_mesh_is_done_whatever_its_spelling() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = dir.path().join("a.obj");
        std::fs::write(&mesh, "v 0 0 0\n").unwrap();
        let link = dir.path().join("link.obj");
        std::os::unix::fs::symlink(&mesh, &link).unwrap();
        let path = dir.path().join("out.jsonl");
        let mut log = ResultLog::open(&path, false, &config()).unwrap();
        log.append(&ok(&mesh.display().to_string())).unwrap();
        drop(log);
        let log = ResultLog::open(&path, true, &config()).unwrap();
        let other = dir.path().join(".").join("a.obj");
        for spelling in [&mesh, &other, &link] {
            assert!(log.done(spelling).is_some(), "{}", spelling.display());
        }
        assert!(log.done(&dir.path().join("b.obj")).is_none());
    }
}
