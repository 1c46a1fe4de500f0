//! The scheduler files under `docs/cluster/` stay consistent with the scripts they call: the
//! Kubernetes shard count (`completions`) is the `N` its command passes, the merge Job merges
//! that many shards, the fuzz Jobs name every fuzz target once, and every script they name
//! exists. (`.ci/run`'s `cluster` stage runs the Slurm files on a real Slurm cluster,
//! scripts/slurm-local.sh; no Kubernetes runs here.)

use std::path::Path;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(ROOT).join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The integer after `key:` on its line.
fn field(text: &str, key: &str) -> usize {
    text.lines()
        .find_map(|l| l.trim().strip_prefix(&format!("{key}:")))
        .unwrap_or_else(|| panic!("no `{key}:`"))
        .trim()
        .parse()
        .unwrap()
}

#[test]
fn the_kubernetes_job_passes_its_own_shard_count() {
    let job = read("docs/cluster/crosscheck-job.yaml");
    assert!(job.contains("completionMode: Indexed"));
    let n = field(&job, "completions");
    let call = "scripts/crosscheck-shard.sh \"$JOB_COMPLETION_INDEX\" ";
    let after = &job[job
        .find(call)
        .expect("the shard script, by completion index")
        + call.len()..];
    let passed: usize = after.split_whitespace().next().unwrap().parse().unwrap();
    assert_eq!(passed, n, "completions and the N of K/N differ");
    assert!(field(&job, "parallelism") <= n);
    let merge = read("docs/cluster/crosscheck-merge-job.yaml");
    let merged = format!("[\"bash\", \"scripts/crosscheck-merge.sh\", \"{n}\", \"/results\"]");
    assert!(merge.contains(&merged), "the merge Job merges {n} shards");
}

/// The value of the `FUZZ_TARGETS` variable a Job sets, as names.
fn fuzz_targets(job: &str) -> Vec<String> {
    let at = job.find("name: FUZZ_TARGETS").expect("FUZZ_TARGETS is set");
    let value = job[at..]
        .lines()
        .nth(1)
        .and_then(|l| l.trim().strip_prefix("value:"))
        .expect("`value:` on the line after `name: FUZZ_TARGETS`");
    value
        .trim()
        .trim_matches('"')
        .split_whitespace()
        .map(String::from)
        .collect()
}

#[test]
fn the_kubernetes_fuzz_jobs_run_every_fuzz_target_once() {
    let manifest = read("fuzz/Cargo.toml");
    let mut bins: Vec<String> = manifest
        .split("[[bin]]")
        .skip(1)
        .map(|b| {
            b.lines()
                .find_map(|l| l.strip_prefix("name = "))
                .unwrap()
                .trim_matches('"')
                .to_string()
        })
        .collect();
    let job = read("docs/cluster/fuzz-job.yaml");
    assert!(job.contains("completionMode: Indexed"));
    let targets = fuzz_targets(&job);
    assert_eq!(
        field(&job, "completions"),
        targets.len(),
        "one completion per target"
    );
    assert!(job.contains("scripts/fuzz-task.sh \"$JOB_COMPLETION_INDEX\" /results/fuzz"));
    let merge = read("docs/cluster/fuzz-merge-job.yaml");
    assert_eq!(
        fuzz_targets(&merge),
        targets,
        "the merge Job merges the same targets"
    );
    let mut sorted = targets.clone();
    sorted.sort();
    bins.sort();
    assert_eq!(
        sorted, bins,
        "FUZZ_TARGETS lists every target of fuzz/Cargo.toml once"
    );
}

#[test]
fn every_script_the_scheduler_files_name_exists() {
    for file in [
        "docs/cluster/crosscheck-job.yaml",
        "docs/cluster/crosscheck-merge-job.yaml",
        "docs/cluster/crosscheck.sbatch",
        "docs/cluster/crosscheck-merge.sbatch",
        "docs/cluster/fuzz-job.yaml",
        "docs/cluster/fuzz-merge-job.yaml",
        "docs/cluster/fuzz.sbatch",
        "docs/cluster/fuzz-merge.sbatch",
    ] {
        let text = read(file);
        let mut named = 0;
        for word in text.split(|c: char| c.is_whitespace() || "\"',[]".contains(c)) {
            if let Some(rel) = word.strip_prefix("$root/").or(Some(word))
                && rel.starts_with("scripts/")
                && rel.ends_with(".sh")
            {
                assert!(Path::new(ROOT).join(rel).is_file(), "{file} names {rel}");
                named += 1;
            }
        }
        assert!(named > 0, "{file} runs one of the scripts");
    }
}
