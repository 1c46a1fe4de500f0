#!/usr/bin/env bash
# A long fuzzing campaign: every target (or the ones named) for FUZZ_SECONDS each (default
# 1200 = 20 min), JOBS at a time (default 2), in libFuzzer's fork mode so a crash is saved and
# the campaign goes on. The binaries are built once and copied, so editing the code while it
# runs does not change what is being fuzzed.
#
#   bash scripts/fuzz-campaign.sh                          # all targets, 20 min each
#   FUZZ_SECONDS=3600 JOBS=4 bash scripts/fuzz-campaign.sh bvh ray_triangle
#
# Output in target/fuzz-campaign/: <target>.log (libFuzzer's output), corpus/<target>/ (new
# inputs; seeded from fuzz/corpus/<target>/, which is never written), artifacts/<target>/
# (crashes, timeouts, OOMs), and summary.md (executions, coverage and findings per target,
# the table fuzz/README.md records). Every crash found goes to fuzz/regressions/<target>/.
SECONDS_EACH=${FUZZ_SECONDS:-1200}
JOBS=${JOBS:-2}

source "$(dirname "${BASH_SOURCE[0]}")/fuzz-tools.sh" "$@"

out=target/fuzz-campaign
mkdir -p "$out/bin"
triple=$(rustc -vV | sed -n 's/^host: //p')
for t in "${targets[@]}"; do
    cp "fuzz/target/$triple/release/$t" "$out/bin/$t"
done

run_one() {
    local t=$1
    mkdir -p "$out/corpus/$t" "$out/artifacts/$t"
    "$out/bin/$t" "$out/corpus/$t" "fuzz/corpus/$t" \
        -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
        -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 \
        -dict=fuzz/dict/floats.dict -artifact_prefix="$out/artifacts/$t/" \
        >"$out/$t.log" 2>&1 || true
}

running=0
for t in "${targets[@]}"; do
    echo "$(date +%H:%M:%S) start $t (${SECONDS_EACH} s)"
    run_one "$t" &
    running=$((running + 1))
    if [ "$running" -ge "$JOBS" ]; then
        wait -n
        running=$((running - 1))
    fi
done
wait

{
    echo "| target | seconds | executions | coverage (edges) | features | corpus | OOMs / timeouts / crashes |"
    echo "|---|---|---|---|---|---|---|"
    for t in "${targets[@]}"; do
        # Fork mode's status lines: `#EXECS: cov: C ft: F corp: N exec/s: E oom/timeout/crash: a/b/c time: T ...`
        last=$(grep -E '^#[0-9]+: cov:' "$out/$t.log" | tail -n 1 || true)
        execs=$(sed -n 's/^#\([0-9]*\):.*/\1/p' <<<"$last")
        cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
        ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
        corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<<"$last")
        otc=$(sed -n 's/.* oom\/timeout\/crash: \([0-9/]*\).*/\1/p' <<<"$last")
        secs=$(sed -n 's/.* time: \([0-9]*\)s.*/\1/p' <<<"$last")
        ntc=$(ls "$out/artifacts/$t" 2>/dev/null | wc -l)
        echo "| \`$t\` | ${secs:-?} | ${execs:-?} | ${cov:-?} | ${ft:-?} | ${corp:-?} | ${otc:-?} (files: $ntc) |"
    done
} >"$out/summary.md"
cat "$out/summary.md"
