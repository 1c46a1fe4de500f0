#!/usr/bin/env bash
# The cross-check's Slurm files on a real cluster (CI's `cluster` stage, issue 39). Run inside
# scripts/slurm-local.sh (or on any Slurm cluster whose nodes share OUT_DIR and this checkout):
#
#   bash scripts/slurm-local.sh bash scripts/slurm-ci-crosscheck.sh OUT_DIR MESH...
#
# Needs target/release/halfray built with `--features embree` (or HALFRAY). RAYS (default
# 10000) rays per set. Two submissions of docs/cluster/crosscheck.sbatch as a 3-task array, each
# followed by docs/cluster/crosscheck-merge.sbatch with --dependency=afterany:
#   1. task 1 is requeued (`scontrol requeue`) once it has checked its first mesh: it must
#      restart, skip the meshes its results log holds (its Slurm log lists them) and check the
#      rest; the merge must succeed and equal the unsharded run row for row;
#   2. task 1 is cancelled (`scancel`) once it has checked its first mesh: the merge job must
#      fail (exit 2) with a message naming shard 1/3.
# Every wait is bounded (TIMEOUT seconds per submission, default 600); a failed check prints the
# jobs as the scheduler reports them. OUT_DIR is this script's own: it is emptied first, and
# refused (exit 2, nothing deleted) when it is not a folder or holds anything but what the
# script writes there (meshes.txt, whole.json, whole.txt, requeue/, cancel/; scripts/out-dir.sh).
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 OUT_DIR MESH..." >&2; exit 2; }
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
source "$root/scripts/slurm-jobs.sh"
source "$root/scripts/out-dir.sh"
own_out_dir slurm-ci-crosscheck "$1" meshes.txt whole.json whole.txt requeue cancel
out=$(mkdir -p "$1" && cd "$1" && pwd)
shift
rays=${RAYS:-10000}
timeout=${TIMEOUT:-600}
export HALFRAY=${HALFRAY:-$root/target/release/halfray}
[ -x "$HALFRAY" ] || { echo "slurm-ci-crosscheck: no $HALFRAY (build it with --features embree)" >&2; exit 2; }
rm -rf "${out:?}"/*
for m in "$@"; do realpath "$m"; done >"$out/meshes.txt"
meshes=$(wc -l <"$out/meshes.txt")
export MESH_LIST=$out/meshes.txt RAYS=$rays

"$HALFRAY" crosscheck --mesh-list "$MESH_LIST" --rays "$rays" --json "$out/whole.json" \
    >"$out/whole.txt" 2>&1 || { tail -n 20 "$out/whole.txt" >&2; fail "the unsharded run"; }

# Submits the array (3 tasks of 1 CPU each; the script asks for a cluster node's 8) and its
# merge into $OUT; sets `array` and `merge`.
submit_run() {
    export OUT=$1
    mkdir -p "$OUT"
    submit array --array=0-2 --cpus-per-task=1 --mem=2G --chdir="$OUT" \
        "$root/docs/cluster/crosscheck.sbatch"
    submit merge --dependency=afterany:"$array" --export=ALL,SHARDS=3 --chdir="$OUT" \
        "$root/docs/cluster/crosscheck-merge.sbatch"
}

# True once task 1 is running and its results log holds at least one mesh.
first_mesh_done() {
    [ "$(job_field "${array}_1" JobState)" = RUNNING ] &&
        [ -s "$OUT/part-1-of-3.jsonl" ]
}

# 1. Requeue in the middle of the run.
submit_run "$out/requeue"
wait_for "$timeout" "task ${array}_1 to check its first mesh" first_mesh_done
scontrol requeue "${array}_1"
wait_jobs "$timeout" "$array" "$merge"
for k in 0 1 2; do expect_job "${array}_$k" COMPLETED 0:0; done
expect_job "$merge" COMPLETED 0:0
restarts=$(job_field "${array}_1" Restarts)
[ "$restarts" = 1 ] || fail "task ${array}_1 was requeued but shows Restarts=$restarts"
log=$OUT/crosscheck-${array}_1.log
skipped=$(grep -c 'already in the results log, skipped (--resume)' "$log" || true)
[ "$skipped" -ge 1 ] && [ "$skipped" -lt "$meshes" ] ||
    fail "the requeued task skipped $skipped of $meshes meshes (expected 1..$((meshes - 1)): resumed mid-run)"
logged=$(wc -l <"$OUT/part-1-of-3.jsonl")
[ "$logged" -eq "$meshes" ] ||
    fail "the requeued task's results log holds $logged lines for $meshes meshes"
same=$(python3 "$root/scripts/crosscheck-same-run.py" "$out/whole.json" "$OUT/merged.json:3") ||
    fail "the merged report differs from the unsharded run"
echo "cluster crosscheck: requeued task ${array}_1 resumed its log (skipped $skipped of $meshes meshes, checked the rest); $same"

# 2. Cancel one task for good.
submit_run "$out/cancel"
wait_for "$timeout" "task ${array}_1 to check its first mesh" first_mesh_done
scancel "${array}_1"
wait_jobs "$timeout" "$array" "$merge"
expect_job "${array}_1" CANCELLED 0:15
expect_job "$merge" FAILED 2:0
named=$(grep -m 1 'shard 1/3 is missing' "$OUT/crosscheck-merge-$merge.log") ||
    fail "the merge failed without naming shard 1/3"
echo "cluster crosscheck: task ${array}_1 cancelled, the merge job failed (exit 2): $named"
