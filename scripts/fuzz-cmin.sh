#!/usr/bin/env bash
# Grows each fuzz target's corpus for FUZZ_SECONDS (default 120) from the checked-in files,
# minimises it with `cargo fuzz cmin` (the smallest set with the same coverage) and checks the
# result in as fuzz/corpus/<target>/min-<sha1> (replayed by `cargo test`, tests/tests/fuzz_replay.rs,
# and read by every CI fuzz run). Old min-* files of the target are replaced; an input with a
# seed-* file's content is not checked in again. A minimisation that fails (cargo fuzz cmin says
# `Failed to minimize corpus`, though it exits 0) stops the script with exit 1 and the log's tail,
# the checked-in files of that target unchanged.
#
#   bash scripts/fuzz-cmin.sh [TARGET...]
SECONDS_EACH=${FUZZ_SECONDS:-120}

source "$(dirname "${BASH_SOURCE[0]}")/fuzz-tools.sh" "$@"
source scripts/fuzz-dict.sh

work=target/fuzz-cmin
for t in "${targets[@]}"; do
    rm -rf "$work/$t" && mkdir -p "$work/$t" "$work/artifacts/$t"
    cp fuzz/corpus/"$t"/* "$work/$t/"
    echo "-- grow $t for ${SECONDS_EACH} s"
    cargo +nightly fuzz run "$t" "$work/$t" -- -max_total_time="$SECONDS_EACH" -timeout=10 \
        -rss_limit_mb=2048 -dict="$(fuzz_dict "$t")" -artifact_prefix="$work/artifacts/$t/" \
        >"$work/$t.log" 2>&1 || { tail -n 40 "$work/$t.log"; echo "fuzz-cmin: $t crashed"; exit 1; }
    if ! cargo +nightly fuzz cmin "$t" "$work/$t" >"$work/$t.cmin.log" 2>&1 ||
        grep -q 'Failed to minimize corpus' "$work/$t.cmin.log"; then
        tail -n 40 "$work/$t.cmin.log"
        echo "fuzz-cmin: minimising $t failed (log: $work/$t.cmin.log); fuzz/corpus/$t is unchanged"
        exit 1
    fi
    # libFuzzer names the inputs it keeps by their SHA-1, the seeds' copies included.
    declare -A seed=()
    for f in fuzz/corpus/"$t"/seed-*; do
        [ -f "$f" ] && seed[$(sha1sum <"$f" | cut -c1-40)]=1
    done
    rm -f fuzz/corpus/"$t"/min-*
    for f in "$work/$t"/*; do
        sum=$(sha1sum <"$f" | cut -c1-40)
        [ -z "${seed[$sum]:-}" ] || continue
        cp "$f" "fuzz/corpus/$t/min-${sum:0:16}"
    done
    unset seed
    echo "$t: $(ls fuzz/corpus/"$t"/min-* 2>/dev/null | wc -l) minimised inputs"
done
