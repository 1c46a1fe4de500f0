#!/usr/bin/env bash
# CI check of the sharded cross-check (issue 16): the same run unsharded and as 4 shards through
# the local runner (scripts/crosscheck-local.sh) must merge to the same counts and the same
# recorded disagreements, row for row (scripts/crosscheck-same-run.py). (The Slurm array itself
# runs on a real cluster in CI's `cluster` stage, scripts/slurm-ci-crosscheck.sh.)
#
#   bash scripts/crosscheck-verify-shards.sh OUT_DIR [crosscheck arguments...]
#
# Exit status: 0 when the merged report equals the unsharded run; 1 when it differs (the first
# difference is named) or a run failed (any exit status: mismatches, a shard refused or
# interrupted, no binary); 2 on a usage error (`--threads` among the arguments is one: the
# shards' threads are THREADS, as in scripts/crosscheck-local.sh). The binary is found as
# scripts/crosscheck-shard.sh finds it. OUT_DIR is this script's own: it is emptied first, and
# refused (exit 2, nothing deleted) when it is not a folder or holds anything but a previous
# run's files (whole.json, stderr.log, local/; scripts/out-dir.sh).
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
out=$1
shift
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
source "$root/scripts/out-dir.sh"
# shellcheck source=scripts/crosscheck-lib.sh
source "$root/scripts/crosscheck-lib.sh"
no_threads_arg crosscheck-verify-shards "$@"
bin=$(halfray_bin)
own_out_dir crosscheck-verify-shards "$out" whole.json stderr.log local
rm -rf "$out" && mkdir -p "$out/local"
# The runs' progress goes to a log, shown when a run fails.
exec 3>&2 2>"$out/stderr.log"
# run WHAT COMMAND...: a run that fails, whatever its status, stops the script with exit 1.
run() {
    local what=$1 rc=0
    shift
    "$@" >/dev/null || rc=$?
    [ "$rc" -ne 0 ] || return 0
    echo "crosscheck-verify-shards: $what failed (exit $rc); last lines of $out/stderr.log:" >&3
    tail -20 "$out/stderr.log" >&3
    exit 1
}
run "the unsharded run" "$bin" crosscheck "$@" --json "$out/whole.json"
run "the sharded run (scripts/crosscheck-local.sh 4)" bash "$root/scripts/crosscheck-local.sh" 4 "$out/local" "$@"
if ! same=$(python3 "$root/scripts/crosscheck-same-run.py" "$out/whole.json" "$out/local/merged.json:4" 2>&3); then
    echo "crosscheck-verify-shards: the merged report of 4 shards differs from the unsharded run (above)" >&2
    echo "crosscheck-verify-shards: the merged report of 4 shards differs from the unsharded run (above)" >&3
    exit 1
fi
echo "crosscheck shards: $same"
