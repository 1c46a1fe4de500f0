//! The scheduler files under `docs/cluster/` stay consistent with the scripts they call: the
//! Kubernetes shard count (`completions`) is the `N` its command passes, the merge Job merges
//! that many shards, and every script they name exists. (`.ci/run` executes the Slurm scripts
//! themselves through `scripts/crosscheck-verify-shards.sh`; no Kubernetes runs here.)

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

#[test]
fn every_script_the_scheduler_files_name_exists() {
    for file in [
        "docs/cluster/crosscheck-job.yaml",
        "docs/cluster/crosscheck-merge-job.yaml",
        "docs/cluster/crosscheck.sbatch",
        "docs/cluster/crosscheck-merge.sbatch",
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
