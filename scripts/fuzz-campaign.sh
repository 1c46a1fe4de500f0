#!/usr/bin/env bash
# A long fuzzing campaign on this machine: every target (or the ones named) for FUZZ_SECONDS
# each (default 1200 = 20 min), JOBS at a time (default 2), each one task of
# scripts/fuzz-task.sh (libFuzzer's fork mode, so a crash is saved and the campaign goes on),
# then the merge, scripts/fuzz-merge.sh: the same two scripts a cluster runs
# (docs/cluster/fuzz.sbatch). The binaries are built once and copied, so editing the code while
# it runs does not change what is being fuzzed.
#
#   bash scripts/fuzz-campaign.sh                          # all targets, 20 min each
#   FUZZ_SECONDS=3600 JOBS=4 bash scripts/fuzz-campaign.sh bvh ray_triangle
#
# Output in target/fuzz-campaign/: logs/<target>.log (libFuzzer's output), corpus/<target>/ (new
# inputs; seeded from fuzz/corpus/<target>/, which is never written), merged/<target>/ (corpus
# and seeds minimised by `-merge=1`), artifacts/<target>/ (crashes, timeouts, OOMs), and
# summary.md (executions, coverage, corpus and findings per target, the table fuzz/README.md
# records). An earlier campaign's artifacts/ holding any file is first moved aside to
# artifacts.<UTC time>/ (said so), so only this campaign's findings are reported; corpus/ is
# kept and grown. Every finding is printed with its target; check each in under
# fuzz/regressions/<target>/ once it is understood. Exit status: the merge's (1 on findings, 2
# when a target's task failed or could not be merged, named); a task that failed (its status is
# printed as it ends) makes it 2 even if the merge passed.
export FUZZ_SECONDS=${FUZZ_SECONDS:-1200}
JOBS=${JOBS:-2}

source "$(dirname "${BASH_SOURCE[0]}")/fuzz-tools.sh" "$@"

out=target/fuzz-campaign
# The merge reports every file under artifacts/: an earlier campaign's go aside, once for the
# whole campaign (a task restarted within it keeps its own).
if [ -n "$(find "$out/artifacts" -type f -print -quit 2>/dev/null)" ]; then
    aside=$out/artifacts.$(date -u +%Y%m%dT%H%M%SZ)
    while [ -e "$aside" ]; do aside+=+; done
    mv "$out/artifacts" "$aside"
    echo "fuzz-campaign: an earlier campaign's findings moved to $aside" >&2
fi
rm -rf "$out/artifacts"
mkdir -p "$out/bin"
triple=$(rustc -vV | sed -n 's/^host: //p')
for t in "${targets[@]}"; do
    cp "fuzz/target/$triple/release/$t" "$out/bin/$t"
done
export FUZZ_TARGETS="${targets[*]}" FUZZ_BIN=$PWD/$out/bin

declare -A task=()   # pid -> target
failed=0
# Waits for one task to end and reports its status.
reap() {
    local pid rc=0
    wait -n -p pid || rc=$?
    echo "$(date +%H:%M:%S) end ${task[$pid]} (exit $rc)"
    [ "$rc" -eq 0 ] || failed=$((failed + 1))
    unset "task[$pid]"
}
for k in "${!targets[@]}"; do
    echo "$(date +%H:%M:%S) start ${targets[k]} (${FUZZ_SECONDS} s)"
    bash scripts/fuzz-task.sh "$k" "$out" &
    task[$!]=${targets[k]}
    if [ "${#task[@]}" -ge "$JOBS" ]; then reap; fi
done
while [ "${#task[@]}" -gt 0 ]; do reap; done
rc=0
bash scripts/fuzz-merge.sh "$out" || rc=$?
if [ "$failed" -ne 0 ] && [ "$rc" -eq 0 ]; then
    echo "fuzz-campaign: $failed task(s) failed (above)" >&2
    rc=2
fi
exit "$rc"
