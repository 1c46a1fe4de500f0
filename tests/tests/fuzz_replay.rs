//! Replays the fuzz corpora on stable: every file under `fuzz/corpus/<target>/` and
//! `fuzz/regressions/<target>/` goes through the same property checks the cargo-fuzz targets
//! run (the `halfray-fuzz-props` crate, `tests/fuzz-props`), so a plain `cargo test` catches a
//! regression of any crash the fuzzers ever found, without nightly or libFuzzer.
//!
//! A seed (`seed-*`, built by `props::seeds()` to exercise its target's properties) must also
//! reach a decisive check of its target ([`props::Outcome::Checked`]): a seed that every check
//! lets pass unjudged tests nothing, unless it is one of `props::UNJUDGED_SEEDS` (boundary
//! seeds, each with its reason). The minimised corpus (`min-*`) may hold such inputs.
//!
//! A regression file whose name starts with `open-` is a reported, unfixed bug: it must still
//! fail, and with the reported failure: its panic message must contain the text of the
//! sibling file `<name>.expected` (required; not replayed as an input), so a different
//! failure of the same input is not taken for the known one. Once it passes the test asks for
//! the prefix to be dropped.
//!
//! `HALFRAY_WRITE_SEEDS=1 cargo test -p halfray-tests --test fuzz_replay` rewrites the seed
//! and code-defined regression files from `props::seeds()` and `props::regressions()`.

use halfray_fuzz_props as props;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz")
}

/// `(target, file)` for every file under `fuzz/<kind>/<target>/`.
fn inputs(kind: &str) -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    let Ok(dirs) = std::fs::read_dir(fuzz_dir().join(kind)) else {
        return out;
    };
    for dir in dirs.flatten() {
        if !dir.path().is_dir() {
            continue;
        }
        let target = dir.file_name().to_string_lossy().into_owned();
        assert!(
            props::TARGETS.contains(&target.as_str()),
            "fuzz/{kind}/{target}: no such fuzz target (known: {:?})",
            props::TARGETS
        );
        for f in std::fs::read_dir(dir.path()).unwrap().flatten() {
            if f.path().is_file() && f.path().extension().is_none_or(|e| e != "expected") {
                out.push((target.clone(), f.path()));
            }
        }
    }
    out.sort();
    out
}

/// `true` for a seed listed in `props::UNJUDGED_SEEDS`.
fn unjudged_seed(target: &str, name: &str) -> bool {
    props::UNJUDGED_SEEDS
        .iter()
        .any(|&(t, n, _)| t == target && n == name)
}

fn replay(kind: &str) -> usize {
    let files = inputs(kind);
    let mut failures = Vec::new();
    for (target, path) in &files {
        let data = std::fs::read(path).unwrap();
        let r = catch_unwind(AssertUnwindSafe(|| props::run(target, &data)));
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let open = name.starts_with("open-");
        let panic_message = |e: &Box<dyn std::any::Any + Send>| {
            e.downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        };
        if open {
            let expected_path = PathBuf::from(format!("{}.expected", path.display()));
            let Ok(expected) = std::fs::read_to_string(&expected_path) else {
                failures.push(format!(
                    "{}: an `open-` file needs {} holding (part of) its panic message",
                    path.display(),
                    expected_path.display()
                ));
                continue;
            };
            let expected = expected.trim();
            match &r {
                Ok(Some(_)) => failures.push(format!(
                    "{}: passes now: drop the `open-` prefix (the bug it reports is fixed)",
                    path.display()
                )),
                Ok(None) => failures.push(format!("{}: unknown target", path.display())),
                Err(e) if expected.is_empty() || !panic_message(e).contains(expected) => failures
                    .push(format!(
                        "{}: fails, but not with the expected {expected:?}:\n{}",
                        path.display(),
                        panic_message(e)
                    )),
                Err(_) => {}
            }
            continue;
        }
        match r {
            Ok(Some(props::Outcome::Unjudged))
                if name.starts_with("seed-") && !unjudged_seed(target, &name) =>
            {
                failures.push(format!(
                    "{}: a seed that reaches no decisive check",
                    path.display()
                ))
            }
            Ok(Some(_)) => {}
            Ok(None) => failures.push(format!("{}: unknown target", path.display())),
            Err(e) => failures.push(format!("{}:\n{}", path.display(), panic_message(&e))),
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} fuzz/{kind} inputs fail:\n\n{}",
        failures.len(),
        files.len(),
        failures.join("\n\n")
    );
    files.len()
}

/// Files per target under `fuzz/<kind>/`.
fn per_target(kind: &str) -> std::collections::BTreeMap<String, usize> {
    let mut count = std::collections::BTreeMap::new();
    for (target, _) in inputs(kind) {
        *count.entry(target).or_insert(0) += 1;
    }
    count
}

#[test]
fn corpus_replays_clean() {
    let n = replay("corpus");
    // A missing or emptied folder must fail, not pass with nothing replayed: every target
    // has its corpus.
    let count = per_target("corpus");
    let empty: Vec<_> = props::TARGETS
        .iter()
        .filter(|t| count.get(**t).copied().unwrap_or(0) == 0)
        .collect();
    assert!(
        empty.is_empty(),
        "targets without corpus files under {}: {empty:?}",
        fuzz_dir().display()
    );
    assert!(n >= props::TARGETS.len());
}

#[test]
fn regressions_replay_clean() {
    let n = replay("regressions");
    // Every code-defined regression is a file here, and nothing vanished: the replay covered
    // at least those.
    let defined = props::regressions().len();
    assert!(
        n >= defined.max(1),
        "{n} regression files replayed, {defined} defined in halfray-fuzz-props"
    );
}

#[test]
fn seed_files_match_their_definitions() {
    let write = std::env::var_os("HALFRAY_WRITE_SEEDS").is_some();
    let mut stale = Vec::new();
    let all = props::seeds()
        .into_iter()
        .map(|s| ("corpus", s))
        .chain(props::regressions().into_iter().map(|s| ("regressions", s)));
    for (kind, (target, name, bytes)) in all {
        let path = fuzz_dir().join(kind).join(target).join(&name);
        if write {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &bytes).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), bytes, "{}", path.display());
        } else if std::fs::read(&path).ok().as_deref() != Some(&bytes[..]) {
            stale.push(path.display().to_string());
        }
    }
    assert!(
        stale.is_empty(),
        "seed files missing or stale (rerun with HALFRAY_WRITE_SEEDS=1): {stale:#?}"
    );
    if write {
        halfray::skips::record_skip(
            "fuzz_replay: seed files rewritten from their definitions (HALFRAY_WRITE_SEEDS), not compared with the committed ones",
        );
    }
}

/// Every seed passes its own target and reaches a decisive check of it, except the listed
/// boundary seeds, which must still pass unjudged (also covered by the corpus replay; this one
/// works before the files are written).
#[test]
fn seeds_pass() {
    let mut failed = Vec::new();
    let mut unjudged = Vec::new();
    let mut judged_listed = Vec::new();
    let seeds = props::seeds();
    for (target, name, bytes) in &seeds {
        let r = catch_unwind(AssertUnwindSafe(|| props::run(target, bytes)));
        let listed = unjudged_seed(target, name);
        match r {
            Ok(Some(props::Outcome::Checked)) if listed => {
                judged_listed.push(format!("{target}/{name}"))
            }
            Ok(Some(props::Outcome::Unjudged)) if !listed => {
                unjudged.push(format!("{target}/{name}"))
            }
            Ok(Some(_)) => {}
            _ => failed.push(format!("{target}/{name}")),
        }
    }
    assert!(failed.is_empty(), "seeds failing: {failed:#?}");
    assert!(
        unjudged.is_empty(),
        "seeds that reach no decisive check (every check let them pass): {unjudged:#?}"
    );
    assert!(
        judged_listed.is_empty(),
        "seeds in UNJUDGED_SEEDS that are judged now (drop them from the list): \
         {judged_listed:#?}"
    );
    let unknown: Vec<_> = props::UNJUDGED_SEEDS
        .iter()
        .filter(|&&(t, n, _)| !seeds.iter().any(|(st, sn, _)| st == &t && sn == n))
        .collect();
    assert!(
        unknown.is_empty(),
        "UNJUDGED_SEEDS names no seed: {unknown:?}"
    );
}
