#!/usr/bin/env bash
# One fuzz target for a fixed time in libFuzzer's fork mode: the task a scheduler runs per target
# (docs/cluster/fuzz.sbatch, docs/cluster/fuzz-job.yaml) and what scripts/fuzz-campaign.sh runs
# for each target. The findings are judged by the merge (scripts/fuzz-merge.sh).
#
#   FUZZ_TARGETS="bvh ray_box" bash scripts/fuzz-task.sh K OUT_DIR
#
# Fuzzes the K-th (0-based) name of FUZZ_TARGETS (binaries and seeds: scripts/fuzz-paths.sh) for
# FUZZ_SECONDS (default 1200) with FUZZ_FORKS parallel fuzzing processes (default 1; fork mode,
# `-ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1`, so a crash is saved and fuzzing goes
# on), seeded with the target's seed folder (never written) and its dictionary
# (scripts/fuzz-dict.sh). Writes
#   OUT_DIR/corpus/TARGET/     new inputs (a task that is restarted continues from them)
#   OUT_DIR/artifacts/TARGET/  crashes, timeouts, OOMs: the findings
#   OUT_DIR/logs/TARGET.log    libFuzzer's output (appended to; each attempt starts with a
#                              `fuzz-task TARGET: ...` line and ends with `fuzz-task TARGET: exit N`)
#   OUT_DIR/logs/TARGET.status `started` while an attempt runs, `exit N` when it ends: the
#                              merge fails a target whose last attempt did not end with `exit 0`
#                              (killed, failed at start-up)
# Findings are not task failures, so a scheduler does not retry a task that worked: the exit
# status is 0 once the fuzzer has run its time, else the fuzzer's.
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: FUZZ_TARGETS=\"T0 T1 ...\" $0 K OUT_DIR" >&2; exit 2; }
k=$1 out=$2
source "$(dirname "${BASH_SOURCE[0]}")/fuzz-paths.sh"
source "$(dirname "${BASH_SOURCE[0]}")/fuzz-dict.sh"
t=${fuzz_targets[k]:-}
[ -n "$t" ] || { echo "fuzz-task: no target $k in FUZZ_TARGETS ($FUZZ_TARGETS)" >&2; exit 2; }
mkdir -p "$out/logs"
log=$out/logs/$t.log
status=$out/logs/$t.status
# This attempt's end, whatever ends it (a signal that kills the shell outright leaves `started`).
echo started >"$status"
trap 'rc=$?; echo "exit $rc" >"$status"; echo "fuzz-task $t: exit $rc" >>"$log"' EXIT
bin=$(fuzz_bin "$t")
seconds=${FUZZ_SECONDS:-1200}
forks=${FUZZ_FORKS:-1}
seeds=()
if s=$(fuzz_seeds "$t"); then seeds+=("$s"); fi
mkdir -p "$out/corpus/$t" "$out/artifacts/$t"
touch "$log"
before=$(wc -l <"$log")
echo "fuzz-task $t: ${seconds} s, ${forks} fork(s), on $(hostname), $(date -u +%FT%TZ)" | tee -a "$log" >&2
rc=0
"$bin" "$out/corpus/$t" "${seeds[@]}" -fork="$forks" \
    -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=2048 -dict="$(fuzz_dict "$t")" \
    -artifact_prefix="$out/artifacts/$t/" >>"$log" 2>&1 || rc=$?
found=$(find "$out/artifacts/$t" -type f | wc -l)
echo "fuzz-task $t: exit $rc, $(find "$out/corpus/$t" -type f | wc -l) inputs in the corpus, $found finding(s)" >&2
# Fork mode ends with `INFO: exiting: CODE`, non-zero when it met (and ignored) a crash.
if [ "$rc" -ne 0 ] && tail -n +$((before + 1)) "$log" | grep -q '^INFO: exiting: '; then
    echo "fuzz-task $t: ran its time; its findings are for the merge to report" >&2
    rc=0
fi
exit "$rc"
