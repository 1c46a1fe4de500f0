#!/usr/bin/env bash
# CI check of the sharded cross-check (issue 16): the same run unsharded and as 4 shards through
# the local runner (xargs -P) must merge to the same counts and the same recorded disagreements,
# row for row. (The Slurm array itself runs on a real cluster in CI's `cluster` stage,
# scripts/slurm-ci-crosscheck.sh.)
#
#   bash scripts/crosscheck-verify-shards.sh OUT_DIR [crosscheck arguments...]
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
out=$1
shift
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${HALFRAY:-$root/target/release/halfray}
rm -rf "$out" && mkdir -p "$out/local"
# The runs' progress goes to a log, shown when a step fails.
exec 3>&2 2>"$out/stderr.log"
trap 'echo "crosscheck-verify-shards: failed; last lines of $out/stderr.log:" >&3; tail -20 "$out/stderr.log" >&3' ERR
"$bin" crosscheck "$@" --json "$out/whole.json" >/dev/null
bash "$root/scripts/crosscheck-local.sh" 4 "$out/local" "$@" >/dev/null
echo "crosscheck shards: $(python3 "$root/scripts/crosscheck-same-run.py" "$out/whole.json" "$out/local/merged.json:4")"
