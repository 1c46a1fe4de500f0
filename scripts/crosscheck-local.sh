#!/usr/bin/env bash
# A sharded cross-check on this machine, the way a cluster runs it: N shards
# (scripts/crosscheck-shard.sh), JOBS at a time, then the merge (scripts/crosscheck-merge.sh).
#
#   bash scripts/crosscheck-local.sh N OUT_DIR [crosscheck arguments...]
#   e.g. bash scripts/crosscheck-local.sh 4 target/shards ../shared/meshes/*.obj --rays 100000
#
# JOBS shards run at once (default: every core / THREADS); each gets --threads THREADS
# (default 1), so `--threads` among the arguments is a usage error. `--max-mismatch M` among
# the arguments is passed to the merge too, so the verdict is the unsharded run's. The exit
# status is the merge's (the run's verdict: 0; 3 on genuine mismatches or leaks; 1 when a mesh
# could not be checked; 2 when a shard is missing or refused). When a shard fails, is
# interrupted or is refused, nothing is merged: the shards that did not complete are named,
# OUT_DIR/merged.json is deleted (never a partial or stale report) and the exit status is 2;
# 2 also on a usage error (N, THREADS or JOBS not a positive integer, `--threads` among the
# arguments) or an OUT_DIR holding another run's files.
#
# Running it again with the same N, arguments and OUT_DIR resumes the run (each shard skips the
# meshes its results log holds). An OUT_DIR holding another run's shards (another N, or other
# arguments: scripts/crosscheck-shard.sh) is refused with exit 2, nothing deleted or mixed.
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 N OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
n=$1 out=$2
shift 2
here=$(dirname "${BASH_SOURCE[0]}")
# shellcheck source=scripts/crosscheck-lib.sh
source "$here/crosscheck-lib.sh"
positive_int crosscheck-local N "$n"
no_threads_arg crosscheck-local "$@"
threads=${THREADS:-1}
positive_int crosscheck-local THREADS "$threads"
jobs=${JOBS:-$(( $(nproc) / threads > 0 ? $(nproc) / threads : 1 ))}
positive_int crosscheck-local JOBS "$jobs"
# Shards of another shard count: another run.
for f in "$out"/part-*-of-*.*; do
    [ -e "$f" ] || continue
    m=${f##*-of-}; m=${m%%.*}
    if [ "$m" != "$n" ]; then
        echo "crosscheck-local: $out holds $f, a shard of another run ($m shards, this one $n); refusing to mix them (use a new OUT_DIR or delete the old run's files)" >&2
        exit 2
    fi
done
# Shards of this N with other arguments: refused before any shard starts, nothing touched.
for ((k = 0; k < n; k++)); do
    bash "$here/crosscheck-shard.sh" --check "$k" "$n" "$out" "$@" --threads "$threads"
done
merge_args=()
prev=
for a in "$@"; do
    case $prev in --max-mismatch) merge_args+=(--max-mismatch "$a") ;; esac
    case $a in --max-mismatch=*) merge_args+=("$a") ;; esac
    prev=$a
done
# The shards, JOBS at a time, each with the arguments exactly as given.
declare -A shard=()   # pid -> shard index
failed=0
# Waits for one shard to end and counts it when it failed.
reap() {
    local pid rc=0
    wait -n -p pid || rc=$?
    if [ "$rc" -ne 0 ]; then
        echo "crosscheck-local: shard ${shard[$pid]}/$n failed (exit $rc)" >&2
        failed=$((failed + 1))
    fi
    unset "shard[$pid]"
}
for ((k = 0; k < n; k++)); do
    bash "$here/crosscheck-shard.sh" "$k" "$n" "$out" "$@" --threads "$threads" &
    shard[$!]=$k
    if [ "${#shard[@]}" -ge "$jobs" ]; then reap; fi
done
while [ "${#shard[@]}" -gt 0 ]; do reap; done
if [ "$failed" -ne 0 ]; then
    # No merge: a shard that stopped early left no report, or an old one that must not be merged.
    rm -f "$out/merged.json"
    for ((k = 0; k < n; k++)); do
        [ -e "$out/part-$k-of-$n.json" ] || echo "crosscheck-local: shard $k/$n did not complete (no report $out/part-$k-of-$n.json)" >&2
    done
    echo "crosscheck-local: $failed shard(s) failed, were interrupted or were refused (their messages above): not merged, no $out/merged.json; run the same command again to resume" >&2
    exit 2
fi
exec bash "$here/crosscheck-merge.sh" "$n" "$out" "${merge_args[@]}"
