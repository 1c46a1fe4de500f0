#!/usr/bin/env bash
# Builds every cargo-fuzz target and runs each for FUZZ_SECONDS (default 30), seeded with the
# checked-in corpus and its dictionary (scripts/fuzz-dict.sh); any crash, timeout or out-of-memory fails the run.
# Installs what it needs when missing (nightly toolchain, cargo-fuzz). Called by test-all.sh.
#
#   FUZZ_SECONDS=30 bash scripts/fuzz-ci.sh            # every target
#   FUZZ_SECONDS=60 bash scripts/fuzz-ci.sh bvh ray_box  # some targets
#
# New inputs go to target/fuzz-ci/corpus/<target> (the checked-in corpus is read, never
# written); a crashing input is saved under target/fuzz-ci/artifacts/<target>/ and printed.
SECONDS_EACH=${FUZZ_SECONDS:-30}

source "$(dirname "${BASH_SOURCE[0]}")/fuzz-tools.sh" "$@"
source scripts/fuzz-dict.sh

out=target/fuzz-ci
for t in "${targets[@]}"; do
    mkdir -p "$out/corpus/$t" "$out/artifacts/$t"
    echo "-- fuzz $t for ${SECONDS_EACH} s"
    if ! cargo +nightly fuzz run "$t" "$out/corpus/$t" "fuzz/corpus/$t" -- \
        -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 \
        -dict="$(fuzz_dict "$t")" -artifact_prefix="$out/artifacts/$t/" \
        -print_final_stats=1 >"$out/$t.log" 2>&1; then
        tail -n 60 "$out/$t.log"
        echo "fuzz target $t failed; the input is in $out/artifacts/$t/ (reproduce with"
        echo "  cargo +nightly fuzz run $t <file>, then check it in under fuzz/regressions/$t/)"
        exit 1
    fi
    grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|cov: " "$out/$t.log" | tail -n 3
done
echo "fuzz: ${#targets[@]} targets ran ${SECONDS_EACH} s each without a crash"
