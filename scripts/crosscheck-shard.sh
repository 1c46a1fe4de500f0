#!/usr/bin/env bash
# One shard of a cross-check run: the task a cluster scheduler runs (docs/cluster/), and what
# scripts/crosscheck-local.sh runs N of with xargs -P.
#
#   bash scripts/crosscheck-shard.sh K N OUT_DIR [crosscheck arguments...]
#
# Runs `halfray crosscheck ARGS --shard K/N --jsonl OUT_DIR/part-K-of-N.jsonl --resume
# --json OUT_DIR/part-K-of-N.json`: a task that is killed and started again continues where its
# results log stops. Findings are not task failures: when the shard ran to the end (its report
# is written) but found mismatches, leaks or unreadable meshes (exit 3 or 1), this script exits
# 0 and leaves the verdict to the merge (scripts/crosscheck-merge.sh), so a scheduler does not
# retry a shard that worked. Any other failure keeps its exit code.
#
# The binary is $HALFRAY, else this repository's target/release/halfray (built with
# `--features embree`), else `halfray` on PATH.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 K N OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
k=$1 n=$2 out=$3
shift 3
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${HALFRAY:-}
if [ -z "$bin" ]; then
    if [ -x "$root/target/release/halfray" ]; then bin=$root/target/release/halfray; else bin=halfray; fi
fi
mkdir -p "$out"
part=$out/part-$k-of-$n
rm -f "$part.json"
rc=0
"$bin" crosscheck "$@" --shard "$k/$n" --jsonl "$part.jsonl" --resume --json "$part.json" \
    >"$part.txt" || rc=$?
if { [ "$rc" -eq 1 ] || [ "$rc" -eq 3 ]; } && [ -s "$part.json" ]; then
    echo "crosscheck-shard $k/$n: findings recorded in $part.json (exit $rc); the merge decides" >&2
    rc=0
fi
exit "$rc"
