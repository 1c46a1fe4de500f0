#!/usr/bin/env bash
# One shard of a cross-check run: the task a cluster scheduler runs (docs/cluster/), and what
# scripts/crosscheck-local.sh runs N of.
#
#   bash scripts/crosscheck-shard.sh K N OUT_DIR [crosscheck arguments...]
#   bash scripts/crosscheck-shard.sh --check K N OUT_DIR [crosscheck arguments...]
#
# Runs `halfray crosscheck ARGS --shard K/N --jsonl OUT_DIR/part-K-of-N.jsonl --resume
# --json OUT_DIR/part-K-of-N.json`: a task that is killed and started again continues where its
# results log stops. OUT_DIR/part-K-of-N.json is the shard's completion marker: deleted when the
# task starts, written by the run only when it ends, so the merge (scripts/crosscheck-merge.sh)
# refuses a shard that did not complete. Findings are not task failures: when the shard ran to
# the end (its report is written) but found mismatches, leaks or unreadable meshes (exit 3 or
# 1), this script exits 0 and leaves the verdict to the merge, so a scheduler does not retry a
# shard that worked. Any other failure keeps its exit code.
#
# The run's arguments (all but --threads and --max-mismatch, which do not change the results;
# with the content of a --mesh-list file) are recorded in OUT_DIR/part-K-of-N.args. A results
# log left by a run with other arguments (other meshes, rays, sets...), or by one that recorded
# none, is refused (exit 2) before anything is deleted: use a new OUT_DIR, or delete the old
# one's files, to start another run. A refused shard writes the reason to
# OUT_DIR/part-K-of-N.refused (and touches none of the old run's files), so the merge refuses
# the old run's reports rather than merging them as this run's; a shard that starts deletes it.
# `--check` only makes that check (exit 0 or 2; writes nothing), so
# scripts/crosscheck-local.sh can refuse before any shard starts.
#
# The binary is $HALFRAY, else this repository's target/release/halfray (built with
# `--features embree`), else `halfray` on PATH.
set -euo pipefail
check_only=0
if [ "${1:-}" = --check ]; then check_only=1; shift; fi
[ $# -ge 3 ] || { echo "usage: $0 K N OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
k=$1 n=$2 out=$3
shift 3
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=scripts/crosscheck-lib.sh
source "$root/scripts/crosscheck-lib.sh"
bin=$(halfray_bin)
[ "$check_only" = 1 ] || mkdir -p "$out"
part=$out/part-$k-of-$n
# The run's identity: its arguments, one a line, and each mesh list's content.
identity() {
    local skip=0 list=0 a
    echo "shard $k/$n"
    for a in "$@"; do
        if [ "$skip" = 1 ]; then skip=0; continue; fi
        if [ "$list" = 1 ]; then
            list=0
            echo "arg $a"
            if [ -f "$a" ]; then echo "mesh-list sha256 $(sha256sum <"$a" | cut -c1-64)"; fi
            continue
        fi
        case $a in
            --threads | --max-mismatch) skip=1 ;;
            --threads=* | --max-mismatch=*) ;;
            --mesh-list) list=1; echo "arg $a" ;;
            --mesh-list=*)
                echo "arg $a"
                if [ -f "${a#*=}" ]; then echo "mesh-list sha256 $(sha256sum <"${a#*=}" | cut -c1-64)"; fi ;;
            *) echo "arg $a" ;;
        esac
    done
}
this=$(identity "$@")
# refuse REASON: exit 2 naming REASON; outside --check, REASON is also written to $part.refused
# (the old run's own files are left as they are), so that the merge refuses this shard.
refuse() {
    echo "crosscheck-shard $k/$n: $1" >&2
    [ "$check_only" = 1 ] || printf '%s\n' "$1" >"$part.refused" ||
        echo "crosscheck-shard $k/$n: could not write $part.refused: a merge of OUT_DIR cannot tell that this shard was refused" >&2
    exit 2
}
if [ -e "$part.jsonl" ]; then
    if [ ! -e "$part.args" ]; then
        refuse "$part.jsonl records no arguments ($part.args is missing): refusing to resume or overwrite it; use a new OUT_DIR or delete the old run's files"
    fi
    if [ "$(cat "$part.args")" != "$this" ]; then
        refuse "$part.jsonl belongs to a run with other arguments; refusing to mix them (use a new OUT_DIR or delete the old run's files):
$(diff <(cat "$part.args") <(echo "$this") | sed 's/^/  /' || true)"
    fi
fi
[ "$check_only" = 0 ] || exit 0
[ -e "$part.jsonl" ] || printf '%s\n' "$this" >"$part.args"
rm -f "$part.json" "$part.refused"
rc=0
"$bin" crosscheck "$@" --shard "$k/$n" --jsonl "$part.jsonl" --resume --json "$part.json" \
    >"$part.txt" || rc=$?
if { [ "$rc" -eq 1 ] || [ "$rc" -eq 3 ]; } && [ -s "$part.json" ]; then
    echo "crosscheck-shard $k/$n: findings recorded in $part.json (exit $rc); the merge decides" >&2
    rc=0
fi
exit "$rc"
