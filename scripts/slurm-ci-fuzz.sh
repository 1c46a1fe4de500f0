#!/usr/bin/env bash
# The fuzzing Slurm files on a real cluster (CI's `cluster` stage, issue 39). Run inside
# scripts/slurm-local.sh (or on any Slurm cluster whose nodes share OUT_DIR and this checkout):
#
#   bash scripts/slurm-local.sh bash scripts/slurm-ci-fuzz.sh OUT_DIR
#
# Builds the fuzz targets (scripts/fuzz-tools.sh: nightly and cargo-fuzz installed when missing)
# and the test-only target `planted` (docs/cluster/fuzz-planted: it crashes on exactly one input,
# planted among its seeds), then submits docs/cluster/fuzz.sbatch as an array over
# FUZZ_TARGETS="ray_box obj_file planted" (CLUSTER_FUZZ_SECONDS each, default 20, one CPU per
# task) and docs/cluster/fuzz-merge.sbatch with --dependency=afterany. Checks that every task
# completed, that the real targets' corpora were merged (`-merge=1`: some inputs, no more than
# went in), and that the merge job failed (exit 1) reporting the planted input as a finding of
# `planted` and nothing else. Every wait is bounded; a failed check prints the jobs as the scheduler
# reports them. OUT_DIR is this script's own: it is emptied first, and refused (exit 2, nothing
# deleted, nothing built) when it is not a folder or holds anything but what the campaign writes
# there (bin/, seeds/, corpus/, artifacts/, logs/, merged/, summary.md, fuzz-*.log;
# scripts/out-dir.sh).
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 OUT_DIR" >&2; exit 2; }
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
source "$root/scripts/out-dir.sh"
# What this script, the tasks (scripts/fuzz-task.sh), the merge (scripts/fuzz-merge.sh) and
# their Slurm logs write in OUT_DIR.
own_out_dir slurm-ci-fuzz "$1" bin seeds corpus artifacts logs merged summary.md 'fuzz-*.log'
out=$(mkdir -p "$1" && cd "$1" && pwd)
real=(ray_box obj_file)
# Builds every target (a no-op after the fuzz stage) and leaves us in the repository root.
source "$root/scripts/fuzz-tools.sh" "${real[@]}"
source "$root/scripts/slurm-jobs.sh"
cargo +nightly fuzz build --fuzz-dir docs/cluster/fuzz-planted --target-dir fuzz/target planted
rm -rf "${out:?}"/*
mkdir -p "$out/bin" "$out/seeds"
triple=$(rustc -vV | sed -n 's/^host: //p')
for t in "${real[@]}" planted; do cp "fuzz/target/$triple/release/$t" "$out/bin/"; done
for t in "${real[@]}"; do ln -s "$root/fuzz/corpus/$t" "$out/seeds/$t"; done
ln -s "$root/docs/cluster/fuzz-planted/corpus" "$out/seeds/planted"

seconds=${CLUSTER_FUZZ_SECONDS:-20}
export FUZZ_TARGETS="${real[*]} planted" FUZZ_BIN=$out/bin FUZZ_SEEDS=$out/seeds \
    FUZZ_SECONDS=$seconds OUT=$out
submit array --array=0-2 --cpus-per-task=1 --mem=2G --time=10 --chdir="$out" \
    "$root/docs/cluster/fuzz.sbatch"
submit merge --dependency=afterany:"$array" --mem=2G --chdir="$out" \
    "$root/docs/cluster/fuzz-merge.sbatch"
# Three tasks of `seconds` each on as few as one CPU, plus start-up and the merge.
wait_jobs $((3 * seconds + 300)) "$array" "$merge"
for k in 0 1 2; do expect_job "${array}_$k" COMPLETED 0:0; done
expect_job "$merge" FAILED 1:0
log=$out/fuzz-merge-$merge.log
planted=$(grep -m 1 "^finding: target planted: $out/seeds/planted/planted-crash " "$log") ||
    fail "the merge job did not report the planted input as a finding of target planted"
others=$(grep '^finding: ' "$log" | grep -v '^finding: target planted: ' || true)
[ -z "$others" ] || fail "real findings (check them in under fuzz/regressions/): $others"
for t in "${real[@]}"; do
    merged=$(find "$out/merged/$t" -type f | wc -l)
    given=$(find "$out/corpus/$t" "$out/seeds/$t/" -type f | wc -l)
    [ "$merged" -ge 1 ] && [ "$merged" -le "$given" ] ||
        fail "target $t: $merged inputs after the merge of $given"
    grep -q '^MERGE-OUTER: .* new files' "$out/logs/$t.merge.log" ||
        fail "target $t: no MERGE-OUTER summary in $out/logs/$t.merge.log"
done
cat "$out/summary.md"
echo "cluster fuzz: ${#real[@]} targets x $seconds s and the test-only target merged their corpora; the merge job reported the planted input: $planted"
