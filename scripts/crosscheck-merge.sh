#!/usr/bin/env bash
# Merges the N shards a run left in OUT_DIR (scripts/crosscheck-shard.sh) into
# OUT_DIR/merged.json and prints the table; its exit status is the run's verdict (0, or 3 on
# genuine mismatches or watertight leaks, 1 when a mesh could not be checked, 2 when a shard
# is missing or belongs to another run).
#
#   bash scripts/crosscheck-merge.sh N OUT_DIR [merge arguments...]
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 N OUT_DIR [merge arguments...]" >&2; exit 2; }
n=$1 out=$2
shift 2
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${HALFRAY:-}
if [ -z "$bin" ]; then
    if [ -x "$root/target/release/halfray" ]; then bin=$root/target/release/halfray; else bin=halfray; fi
fi
parts=()
missing=0
for ((k = 0; k < n; k++)); do
    part=$out/part-$k-of-$n.jsonl
    if [ ! -e "$part" ]; then
        # The task never started (cancelled while pending, or OUT_DIR is not shared): say which.
        echo "crosscheck-merge: shard $k/$n is missing: no results log $part" >&2
        missing=1
    fi
    parts+=("$part")
done
[ "$missing" -eq 0 ] || exit 2
exec "$bin" crosscheck merge "${parts[@]}" --json "$out/merged.json" "$@"
