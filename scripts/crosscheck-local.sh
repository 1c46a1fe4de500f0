#!/usr/bin/env bash
# A sharded cross-check on this machine, the way a cluster runs it: N shards
# (scripts/crosscheck-shard.sh) through `xargs -P`, then the merge (scripts/crosscheck-merge.sh).
#
#   bash scripts/crosscheck-local.sh N OUT_DIR [crosscheck arguments...]
#   e.g. bash scripts/crosscheck-local.sh 4 target/shards ../shared/meshes/*.obj --rays 100000
#
# JOBS shards run at once (default: every core / THREADS); each gets --threads THREADS
# (default 1). The exit status is the merge's (the run's verdict).
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 N OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
n=$1 out=$2
shift 2
here=$(dirname "${BASH_SOURCE[0]}")
threads=${THREADS:-1}
jobs=${JOBS:-$(( $(nproc) / threads > 0 ? $(nproc) / threads : 1 ))}
rc=0
seq 0 $((n - 1)) | xargs -P "$jobs" -I{} bash "$here/crosscheck-shard.sh" {} "$n" "$out" "$@" --threads "$threads" || rc=$?
[ "$rc" -eq 0 ] || echo "crosscheck-local: a shard failed (xargs exit $rc); merging what is there" >&2
bash "$here/crosscheck-merge.sh" "$n" "$out"
exit "$rc"
