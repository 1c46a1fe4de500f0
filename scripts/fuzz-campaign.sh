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
# records). Every finding is printed with its target; check each in under
# fuzz/regressions/<target>/ once it is understood. Exit status: the merge's (1 on findings).
export FUZZ_SECONDS=${FUZZ_SECONDS:-1200}
JOBS=${JOBS:-2}

source "$(dirname "${BASH_SOURCE[0]}")/fuzz-tools.sh" "$@"

out=target/fuzz-campaign
mkdir -p "$out/bin"
triple=$(rustc -vV | sed -n 's/^host: //p')
for t in "${targets[@]}"; do
    cp "fuzz/target/$triple/release/$t" "$out/bin/$t"
done
export FUZZ_TARGETS="${targets[*]}" FUZZ_BIN=$PWD/$out/bin

running=0
for k in "${!targets[@]}"; do
    echo "$(date +%H:%M:%S) start ${targets[k]} (${FUZZ_SECONDS} s)"
    bash scripts/fuzz-task.sh "$k" "$out" &
    running=$((running + 1))
    if [ "$running" -ge "$JOBS" ]; then
        wait -n || true # the task's log and the merge's summary show a failure
        running=$((running - 1))
    fi
done
wait
bash scripts/fuzz-merge.sh "$out"
