#!/usr/bin/env bash
# Mutation testing of the core's most critical files with cargo-mutants: a fixed, reproducible
# sample of at most PER_FILE mutants per file (every n-th of the file's mutants in cargo-mutants'
# own order, `--shard 0/n`, n = ceil(count / PER_FILE)), tested by TEST_PACKAGES. Prints one
# table row per file: mutants in the file, sampled, caught / missed / unviable / timeout; the
# missed ones are listed under target/mutation/<file>/mutants.out/missed.txt.
#
# Two stages, one outcome: every sampled mutant is first tested by the core's own tests alone
# (a build of one crate, seconds); only the ones those tests miss or time out on are tested
# again by all of TEST_PACKAGES (a mutant the core's tests catch is caught by any superset).
# Builds use the `mutants` profile (Cargo.toml: no debug info, opt-level 1).
#
#   PER_FILE=100 TEST_PACKAGES=halfray-core,halfray-tests bash scripts/mutants.sh   # the full run
#   PER_FILE=4 TEST_PACKAGES=halfray-core bash scripts/mutants.sh                   # a quick sample
#   FILES="core/src/kdtree/sah.rs core/src/collide" SHARD=1 bash scripts/mutants.sh # other shards
#   bash scripts/mutants.sh --in-diff DIFF                                          # a branch's lines
#
# FILES: files or folders (every `.rs` under a folder except `tests.rs` and `tests/`); default
# the five older critical files and the newer modules. SHARD: which of the n shards to sample
# (default 0; a held-out check samples another, e.g. `SHARD=3`).
#
# A mutant costs ~5–20 s to build and test here (2 cores, unloaded; ~40 s with eight builds
# sharing them), and the default files hold 3 580 mutants (~2 400 sampled at PER_FILE=100):
# the full run is a job of hours, not a CI stage. Run it per file or shard, in the background.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PER_FILE=${PER_FILE:-100}
TEST_PACKAGES=${TEST_PACKAGES:-halfray-core,halfray-tests}
SHARD=${SHARD:-0}
DEFAULT_FILES="core/src/aabb.rs core/src/triangle/watertight.rs core/src/bvh/traverse.rs
    core/src/halfedge/subdivide.rs core/src/halfedge/collapse.rs core/src/bvh/load.rs
    core/src/collide core/src/volume core/src/grid core/src/kdtree core/src/bvh/wide
    core/src/simd"
SELECTED=${FILES:-$DEFAULT_FILES}
FILES=()
for f in $SELECTED; do
    if [ -d "$f" ]; then
        while IFS= read -r g; do FILES+=("$g"); done \
            < <(find "$f" -name '*.rs' ! -name tests.rs ! -path '*/tests/*' | sort)
    else
        FILES+=("$f")
    fi
done

if ! cargo mutants --version >/dev/null 2>&1; then
    cargo install cargo-mutants --locked
fi
out=target/mutation
mkdir -p "$out"

if [ "${1:-}" = "--in-diff" ]; then
    cargo mutants --in-diff "$2" --test-package "$TEST_PACKAGES" -o "$out/diff" || true
    exit 0
fi

count() { if [ -f "$1" ]; then grep -c . "$1" || true; else echo 0; fi; }
echo "| file | mutants | sampled | caught | missed | unviable | timeout |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for f in "${FILES[@]}"; do
    total=$(cargo mutants --list -f "$f" 2>/dev/null | wc -l)
    [ "$total" -ge 1 ] || continue
    n=$(( (total + PER_FILE - 1) / PER_FILE )); [ "$n" -ge 1 ] || n=1
    [ "$SHARD" -lt "$n" ] || continue
    f_id=${f#core/src/}; dir="$out/${f_id//\//_}"; dir="${dir%.rs}.s$SHARD"
    # cargo-mutants exits non-zero when a mutant is missed: the table says so.
    cargo mutants -f "$f" --shard "$SHARD/$n" --test-package halfray-core --profile mutants \
        -o "$dir" >"$dir.log" 2>&1 || true
    m="$dir/mutants.out"
    if [ "$TEST_PACKAGES" != halfray-core ]; then
        # Stage two: the survivors, by name (regex-escaped), against every test package.
        survivors=$(cat "$m/missed.txt" "$m/timeout.txt" 2>/dev/null | sed 's/[][\\.^$*+?(){}|]/\\&/g' \
            | paste -sd'|' -)
        if [ -n "$survivors" ]; then
            # Every mutant relinks every test binary here (~2 min): a generous test timeout,
            # so that a slow machine is not read as a mutant's endless loop.
            cargo mutants -f "$f" -F "^($survivors)\$" --test-package "$TEST_PACKAGES" \
                --profile mutants --minimum-test-timeout 180 -o "$dir/wide" \
                >"$dir.wide.log" 2>&1 || true
            w="$dir/wide/mutants.out"
            # The wide run's verdicts replace stage one's for the survivors.
            c1=$(count "$m/caught.txt"); u1=$(count "$m/unviable.txt")
            c=$((c1 + $(count "$w/caught.txt"))); x=$(count "$w/missed.txt")
            u=$((u1 + $(count "$w/unviable.txt"))); t=$(count "$w/timeout.txt")
            echo "| \`$f\` | $total | $((c + x + u + t)) | $c | $x | $u | $t |"
            continue
        fi
    fi
    c=$(count "$m/caught.txt"); x=$(count "$m/missed.txt")
    u=$(count "$m/unviable.txt"); t=$(count "$m/timeout.txt")
    echo "| \`$f\` | $total | $((c + x + u + t)) | $c | $x | $u | $t |"
done
