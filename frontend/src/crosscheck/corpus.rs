//! Corpora: `--mesh-list FILE` and the resumable JSON-lines results log (`--jsonl`).
//!
//! The log holds one [`MeshResult`] per line, appended and flushed to disk as each mesh
//! finishes, so a run that is killed loses at most the mesh in progress. `--resume` reads the
//! log back, drops a torn last line (a write cut off mid-line), checks that every line belongs
//! to the same run (intersector, seed, rays, sets, shard) and skips the meshes already checked;
//! meshes that failed are tried again and their new line appended. The last line of a path
//! wins when a log is read.

use super::report::{MeshResult, RunConfig};
use super::shard::Shard;
use crate::error::{Error, Location, Result};
use crate::outputs::Named;
use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The mesh paths of a list file: one per line, surrounding whitespace trimmed, blank lines and
/// lines starting with `#` skipped. Relative paths are relative to the current directory (as
/// `find … > list` writes them), not to the list file.
pub fn read_mesh_list(list: &Path) -> Result<Vec<PathBuf>> {
    let text = crate::input::read_text(list, "text (one mesh path per line)")?;
    Ok(text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(PathBuf::from)
        .collect())
}

/// The inputs of a run over `meshes`, some of them named by the file `list`, as the messages
/// name them (`mesh`, `--mesh-list`): what no output of the run may be.
pub fn run_inputs<'a>(meshes: &'a [PathBuf], list: Option<&'a Path>) -> Vec<Named<'a>> {
    let mut inputs: Vec<Named<'a>> = meshes.iter().map(|p| Named::new("mesh", p)).collect();
    inputs.extend(list.map(|p| Named::new("--mesh-list", p)));
    inputs
}

/// Parses the complete lines of a results log (`text` ends at a newline or is empty).
/// Every line must be a [`MeshResult`]; the last line of each path wins.
pub fn parse_log(path: &Path, text: &str) -> Result<Vec<MeshResult>> {
    // Keyed by mesh and shard: a resumed log repeats a mesh of its own shard (the later line
    // wins), a concatenation of shard logs holds each mesh once per shard (all kept).
    let mut order: Vec<(String, Shard)> = Vec::new();
    let mut latest: HashMap<(String, Shard), MeshResult> = HashMap::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let result: MeshResult = serde_json::from_str(line).map_err(|e| {
            Error::input(
                Location::file(path).line(i + 1).json_position(&e),
                format!("not a cross-check result line: {e}"),
            )
        })?;
        let key = (result.path.clone(), result.config.shard);
        if !latest.contains_key(&key) {
            order.push(key.clone());
        }
        latest.insert(key, result);
    }
    Ok(order
        .into_iter()
        .filter_map(|p| latest.remove(&p))
        .collect())
}

/// An open results log.
pub struct ResultLog {
    path: PathBuf,
    file: File,
    done: HashMap<String, MeshResult>,
}

impl ResultLog {
    /// Opens `path` for this run. Without `resume`, an existing non-empty file is refused (its
    /// results would be lost); with it, the file is read back (see the module docs) and every
    /// line must belong to `config`'s run.
    pub fn open(path: &Path, resume: bool, config: &RunConfig) -> Result<Self> {
        let mut file = OpenOptions::new()
            .read(true)
            .append(true)
            .create(true)
            .open(path)
            .map_err(|e| Error::io(path, e))?;
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes)
            .map_err(|e| Error::io(path, e))?;
        if !resume && !bytes.is_empty() {
            return Err(Error::Usage(format!(
                "--jsonl `{}` already holds results: pass --resume to continue that run, or choose another file",
                path.display()
            )));
        }
        // A torn last line (no newline) is dropped: its mesh is checked again.
        let complete = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        if complete < bytes.len() {
            eprintln!(
                "crosscheck: {}: dropping a torn last line ({} bytes); its mesh is checked again",
                path.display(),
                bytes.len() - complete
            );
            file.set_len(complete as u64)
                .and_then(|()| file.seek(SeekFrom::End(0)).map(|_| ()))
                .map_err(|e| Error::io(path, e))?;
        }
        let text = std::str::from_utf8(&bytes[..complete])
            .map_err(|_| Error::input(Location::file(path), "is not UTF-8 text (a results log)"))?;
        let mut done = HashMap::new();
        for result in parse_log(path, text)? {
            if let Some(diff) = result.config.difference(config) {
                return Err(Error::Usage(format!(
                    "--resume: `{}` holds results of another run (log vs this run: {diff}; mesh `{}`)",
                    path.display(),
                    result.path
                )));
            }
            if result.config.shard != config.shard {
                return Err(Error::Usage(format!(
                    "--resume: `{}` holds shard {} results, this run is shard {}",
                    path.display(),
                    result.config.shard,
                    config.shard
                )));
            }
            if result.error.is_none() {
                done.insert(result.path.clone(), result);
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            file,
            done,
        })
    }

    /// The result already in the log for `mesh` (checked successfully), if any.
    pub fn done(&self, mesh: &str) -> Option<&MeshResult> {
        self.done.get(mesh)
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
            ["a.obj", "b/c.obj", "d.obj"].map(PathBuf::from)
        );
        std::fs::write(&list, b"a.obj\n\xff.obj\n").unwrap();
        let e = read_mesh_list(&list).unwrap_err().to_string();
        assert!(e.contains("list.txt:2"), "{e}");
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
        assert_eq!(log.done("a.obj"), Some(&ok("a.obj")));
        assert_eq!(log.done("c.obj"), Some(&ok("c.obj")));
        assert!(log.done("b.obj").is_none(), "a failed mesh is tried again");
        assert!(log.done("d.obj").is_none(), "a torn line is not a result");
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.ends_with('\n') && !text.contains("d.obj"),
            "torn line dropped"
        );
        assert_eq!(parse_log(&path, &text).unwrap().len(), 3);
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
}
