#!/usr/bin/env bash
# Merges the N shards a run left in OUT_DIR (scripts/crosscheck-shard.sh) into
# OUT_DIR/merged.json and prints the table; its exit status is the run's verdict (0, or 3 on
# genuine mismatches or watertight leaks, 1 when a mesh could not be checked, 2 when a shard
# is missing, did not complete, or belongs to another run).
#
#   bash scripts/crosscheck-merge.sh N OUT_DIR [merge arguments...]
#   MAX_MISMATCH=5 bash scripts/crosscheck-merge.sh N OUT_DIR   # = --max-mismatch 5
#
# A shard is complete when its report OUT_DIR/part-K-of-N.json (the completion marker, written
# only when the shard's run ends) exists; a shard without it (never started, cancelled,
# interrupted, failed) is named and the merge refuses (exit 2), as it does a shard whose last
# start was refused (OUT_DIR/part-K-of-N.refused, written by the shard script: OUT_DIR holds
# another run's files, which are not merged as this run's). MAX_MISMATCH, when set, is
# passed as `--max-mismatch` (a scheduler's merge job takes it from the environment). Any
# previous OUT_DIR/merged.json is deleted first, and the new report is written to a temporary
# file and renamed: merged.json exists only after a merge that wrote its whole report (verdict
# 0, 1 or 3), never a stale or partial one. The binary is found as scripts/crosscheck-shard.sh
# finds it.
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 N OUT_DIR [merge arguments...]" >&2; exit 2; }
n=$1 out=$2
shift 2
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=scripts/crosscheck-lib.sh
source "$root/scripts/crosscheck-lib.sh"
positive_int crosscheck-merge N "$n"
bin=$(halfray_bin)
merged=$out/merged.json
tmp=$out/merged.json.partial
rm -f "$merged" "$tmp"
parts=()
missing=0
for ((k = 0; k < n; k++)); do
    part=$out/part-$k-of-$n.jsonl
    refused=$out/part-$k-of-$n.refused
    if [ -e "$refused" ]; then
        # The shard's last start was refused (scripts/crosscheck-shard.sh): the files here are
        # another run's, not the one this merge follows.
        echo "crosscheck-merge: shard $k/$n was refused ($refused), so its files here belong to another run:" >&2
        sed 's/^/  /' "$refused" >&2
        missing=1
    elif [ ! -e "$part" ]; then
        # The task never started (cancelled while pending, or OUT_DIR is not shared): say which.
        echo "crosscheck-merge: shard $k/$n is missing: no results log $part" >&2
        missing=1
    elif [ ! -e "$out/part-$k-of-$n.json" ]; then
        # Started but did not end: killed, cancelled, interrupted or failed mid-run.
        echo "crosscheck-merge: shard $k/$n is missing: it did not complete (no report $out/part-$k-of-$n.json; its results log holds $(grep -c . "$part" || true) mesh(es)); run the shard again to resume it" >&2
        missing=1
    fi
    parts+=("$part")
done
[ "$missing" -eq 0 ] || exit 2
rc=0
"$bin" crosscheck merge "${parts[@]}" --json "$tmp" ${MAX_MISMATCH:+--max-mismatch "$MAX_MISMATCH"} "$@" || rc=$?
if { [ "$rc" -eq 0 ] || [ "$rc" -eq 1 ] || [ "$rc" -eq 3 ]; } && [ -s "$tmp" ]; then
    mv -f "$tmp" "$merged"
else
    rm -f "$tmp"
    echo "crosscheck-merge: the merge failed (exit $rc); no $merged written" >&2
    [ "$rc" -ne 0 ] || rc=2
fi
exit "$rc"
