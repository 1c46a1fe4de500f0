#!/usr/bin/env bash
# CI check of the sharded cross-check (issue 16): the same run unsharded, as 4 shards through
# the local runner (xargs -P), and as 3 tasks of the Slurm array script (SLURM_* set by hand)
# must merge to the same counts and the same recorded disagreements, row for row.
#
#   bash scripts/crosscheck-verify-shards.sh OUT_DIR [crosscheck arguments...]
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 OUT_DIR [crosscheck arguments...]" >&2; exit 2; }
out=$1
shift
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bin=${HALFRAY:-$root/target/release/halfray}
rm -rf "$out" && mkdir -p "$out/local" "$out/slurm"
# The runs' progress goes to a log, shown when a step fails.
exec 3>&2 2>"$out/stderr.log"
trap 'echo "crosscheck-verify-shards: failed; last lines of $out/stderr.log:" >&3; tail -20 "$out/stderr.log" >&3' ERR
"$bin" crosscheck "$@" --json "$out/whole.json" >/dev/null
bash "$root/scripts/crosscheck-local.sh" 4 "$out/local" "$@" >/dev/null
# The Slurm script takes the mesh list and ray count from the environment.
list=$out/meshes.txt
rays=100000
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
    case ${args[i]} in
        --rays) rays=${args[i + 1]}; i=$((i + 1)) ;;
        --*) echo "crosscheck-verify-shards: only meshes and --rays are supported (got ${args[i]})" >&2; exit 2 ;;
        *) echo "${args[i]}" ;;
    esac
done >"$list"
for k in 0 1 2; do
    SLURM_ARRAY_TASK_ID=$k SLURM_ARRAY_TASK_COUNT=3 SLURM_CPUS_PER_TASK=1 SLURM_SUBMIT_DIR=$root \
        MESH_LIST=$list OUT=$out/slurm RAYS=$rays bash "$root/docs/cluster/crosscheck.sbatch"
done
SHARDS=3 OUT=$out/slurm SLURM_SUBMIT_DIR=$root bash "$root/docs/cluster/crosscheck-merge.sbatch" >/dev/null
python3 - "$out/whole.json" "$out/local/merged.json" "$out/slurm/merged.json" <<'PY'
import json, sys
def rows(path):
    report = json.load(open(path))
    return [{k: v for k, v in row.items() if not k.startswith(("secs_", "mrays_"))}
            for row in report["sets"]], report
whole, w = rows(sys.argv[1])
for path, shards in ((sys.argv[2], 4), (sys.argv[3], 3)):
    merged, m = rows(path)
    assert m["merged_shards"] == shards, (path, m["merged_shards"])
    assert len(merged) == len(whole), (path, len(merged), len(whole))
    for a, b in zip(whole, merged):
        diff = [k for k in a if a[k] != b.get(k)]
        assert not diff, f"{path}: {a['mesh']} {a['name']}: {diff}"
rays = sum(r["rays"] for r in whole)
details = sum(len(r["disagreements"]) for r in whole)
print(f"crosscheck shards: 4 local shards and 3 Slurm tasks merge to the unsharded run "
      f"({len(whole)} rows, {rays} rays, {details} recorded disagreements)")
PY
