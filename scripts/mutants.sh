#!/usr/bin/env bash
# Mutation testing of the core's most critical files with cargo-mutants: a fixed, reproducible
# sample of at most PER_FILE mutants per file (in each file, the mutants whose index in
# cargo-mutants' own `--list` order is SHARD mod n, n = ceil(count / PER_FILE): spread over the
# whole file), tested by TEST_PACKAGES. Prints one table row per file: mutants in the file,
# sampled, caught / missed / unviable / timeout; the sample and the verdicts are listed under
# target/mutation/sample.s<SHARD>.p<PER_FILE>.f<HASH>/ (sample.txt, caught.txt, missed.txt, ...;
# HASH: the first 8 hex digits of the SHA-256 of the resolved file list, one path a line), so
# runs of other FILES, shards or sizes write apart; a second run of the same sample while one is
# under way is refused (exit 1; a lock on the folder's .lock).
#
# Two stages, one outcome: every sampled mutant is first tested by the core's own tests alone
# (one cargo-mutants run for all files, one build of the dependencies); only the ones those
# tests miss or time out on are tested again by all of TEST_PACKAGES (a mutant the core's tests
# catch is caught by any superset). A stage whose cargo-mutants run fails (its baseline — the
# tests on the unmutated tree — fails, or any exit status but 0, 2 missed and 3 timeouts) stops
# the script with exit 1 and the log's tail; a survivor stage two did not judge keeps stage
# one's verdict.
# Builds use the `mutants` profile (Cargo.toml: no debug info, opt-level 1).
#
#   PER_FILE=100 TEST_PACKAGES=halfray-core,halfray-tests bash scripts/mutants.sh   # the full run
#   PER_FILE=4 TEST_PACKAGES=halfray-core bash scripts/mutants.sh                   # a quick sample
#   FILES="core/src/kdtree/sah.rs core/src/bvh/collide" SHARD=1 bash scripts/mutants.sh # other shards
#   FILES=frontend/src/outputs FIRST_PACKAGE=halfray TEST_PACKAGES=halfray bash scripts/mutants.sh
#   bash scripts/mutants.sh --in-diff DIFF                                          # a branch's lines
#
# FILES: files or folders (every `.rs` under a folder except `tests.rs` and `tests/`; a path that
# is neither, or a file whose `cargo mutants --list` fails, stops the script with exit 1 naming
# it; a file with fewer than SHARD + 1 shards is skipped with a line saying so); default
# the five older critical files, the newer modules and the binary BVH's builder (sah.rs,
# build.rs). SHARD: which of the n shards to sample
# (default 0; a held-out check samples another, e.g. `SHARD=3`). Samples drawn before
# 2026-11-29 used `--shard SHARD/n` per file, which in cargo-mutants 27 is a *slice* (n
# consecutive mutants), not every n-th.
#
# A mutant costs ~5–20 s to build and test here (2 cores, unloaded; ~40 s with eight builds
# sharing them), and the default files held 3 580 mutants (~2 400 sampled at PER_FILE=100)
# before bvh/sah.rs and bvh/build.rs joined them (not recounted since): the full run is a job
# of hours, not a CI stage. Run it per file or shard, in the background.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PER_FILE=${PER_FILE:-100}
TEST_PACKAGES=${TEST_PACKAGES:-halfray-core,halfray-tests}
# The package whose tests run first on every sampled mutant (stage one below): the core's, or
# the frontend's (`FIRST_PACKAGE=halfray`) for a sample of frontend files.
FIRST_PACKAGE=${FIRST_PACKAGE:-halfray-core}
SHARD=${SHARD:-0}
DEFAULT_FILES="core/src/aabb.rs core/src/triangle/watertight.rs core/src/bvh/traverse.rs
    core/src/halfedge/subdivide.rs core/src/halfedge/collapse.rs core/src/bvh/load.rs
    core/src/bvh/collide core/src/volume core/src/grid core/src/kdtree core/src/bvh/wide
    core/src/simd core/src/bvh/sah.rs core/src/bvh/build.rs"
SELECTED=${FILES:-$DEFAULT_FILES}
FILES=()
for f in $SELECTED; do
    if [ -d "$f" ]; then
        while IFS= read -r g; do FILES+=("$g"); done \
            < <(find "$f" -name '*.rs' ! -name tests.rs ! -path '*/tests/*' | sort)
    elif [ -f "$f" ]; then
        FILES+=("$f")
    else
        echo "mutants: FILES names $f, which is neither a file nor a folder (paths are relative to the repository root)" >&2
        exit 1
    fi
done

if ! cargo mutants --version >/dev/null 2>&1; then
    cargo install cargo-mutants --locked
fi
out=target/mutation
mkdir -p "$out"

# mutants_stage NAME LOG ARGS...: one cargo-mutants run; its missed mutants (exit 2) and
# timeouts (exit 3) are verdicts, any other failure (4: the baseline failed) stops the script.
mutants_stage() {
    local name=$1 log=$2 rc=0
    shift 2
    cargo mutants "$@" >"$log" 2>&1 || rc=$?
    case $rc in
        0 | 2 | 3) ;;
        *)
            tail -n 20 "$log" >&2
            echo "mutants: stage $name failed: cargo-mutants exit $rc$([ "$rc" = 4 ] && echo " (the tests fail on the unmutated tree)"); log: $log" >&2
            exit 1 ;;
    esac
}

if [ "${1:-}" = "--in-diff" ]; then
    mutants_stage diff "$out/diff.log" --in-diff "$2" --test-package "$TEST_PACKAGES" -o "$out/diff"
    tail -n 5 "$out/diff.log"
    exit 0
fi

count() { if [ -f "$1" ]; then grep -c . "$1" || true; else echo 0; fi; }
esc() { sed 's/[][\\.^$*+?(){}|]/\\&/g' | paste -sd'|' -; }
# The sample: in each file, the mutants whose index in cargo-mutants' order is SHARD mod n.
files_hash=$(printf '%s\n' "${FILES[@]}" | sha256sum | cut -c1-8)
run="$out/sample.s$SHARD.p$PER_FILE.f$files_hash"; mkdir -p "$run"
exec 9>"$run/.lock"
flock -n 9 || { echo "mutants: another run of this sample is writing $run; wait for it or choose other FILES, SHARD or PER_FILE" >&2; exit 1; }
: >"$run/sample.txt"; : >"$run/files.txt"
args=()
for f in "${FILES[@]}"; do
    rc=0
    cargo mutants --list -f "$f" >"$run/all.tmp" 2>"$run/list.log" || rc=$?
    if [ "$rc" -ne 0 ]; then
        tail -n 20 "$run/list.log" >&2
        echo "mutants: listing the mutants of $f failed: cargo-mutants exit $rc; log: $run/list.log" >&2
        exit 1
    fi
    total=$(count "$run/all.tmp")
    n=$(( (total + PER_FILE - 1) / PER_FILE ))
    if [ "$SHARD" -ge "$n" ]; then
        echo "mutants: $f: $total mutant(s) in $n shard(s); shard $SHARD is past them: none sampled" >&2
        continue
    fi
    awk -v n="$n" -v s="$SHARD" '(NR - 1) % n == s' "$run/all.tmp" >>"$run/sample.txt"
    echo "$f $total" >>"$run/files.txt"
    args+=(-f "$f")
done
rm -f "$run/all.tmp" "$run/list.log"
[ -s "$run/sample.txt" ] || { echo "no mutants sampled"; exit 0; }
# Stage one: every sampled mutant against FIRST_PACKAGE's own tests, in one cargo-mutants run
# (one build of the dependencies); cargo-mutants exits non-zero when a mutant is missed: the
# table says so.
rm -rf "$run/core" "$run/wide" "$run/wide.log"
mutants_stage one "$run/core.log" "${args[@]}" -F "^($(esc <"$run/sample.txt"))\$" \
    --test-package "$FIRST_PACKAGE" --profile mutants -j1 -o "$run/core"
m="$run/core/mutants.out"; w="$run/wide/mutants.out"
survivors=$(cat "$m/missed.txt" "$m/timeout.txt" 2>/dev/null | esc)
if [ "$TEST_PACKAGES" != "$FIRST_PACKAGE" ] && [ -n "$survivors" ]; then
    # Stage two: the survivors, by name, against every test package. Every mutant relinks
    # every test binary here (~2 min): a generous test timeout, so that a slow machine is not
    # read as a mutant's endless loop. Its verdicts replace stage one's for the survivors.
    mutants_stage two "$run/wide.log" "${args[@]}" -F "^($survivors)\$" \
        --test-package "$TEST_PACKAGES" --profile mutants -j1 --minimum-test-timeout 180 \
        -o "$run/wide"
    cat "$m/caught.txt" "$w/caught.txt" >"$run/caught.txt" 2>/dev/null || true
    cat "$m/unviable.txt" "$w/unviable.txt" >"$run/unviable.txt" 2>/dev/null || true
    # A survivor stage two judged takes that verdict; one it did not keeps stage one's.
    cat "$w/caught.txt" "$w/missed.txt" "$w/unviable.txt" "$w/timeout.txt" >"$run/judged.tmp" 2>/dev/null || true
    for k in missed timeout; do
        { cat "$w/$k.txt" 2>/dev/null || true
          grep -Fxv -f "$run/judged.tmp" "$m/$k.txt" 2>/dev/null || true; } >"$run/$k.txt"
    done
    rm -f "$run/judged.tmp"
else
    for k in caught missed unviable timeout; do cp "$m/$k.txt" "$run/$k.txt" 2>/dev/null || : >"$run/$k.txt"; done
fi
per() { grep -c "^$2:" "$run/$1.txt" || true; }
echo "| file | mutants | sampled | caught | missed | unviable | timeout |"
echo "|---|---:|---:|---:|---:|---:|---:|"
while read -r f total; do
    echo "| \`$f\` | $total | $(per sample "$f") |" \
        "$(per caught "$f") | $(per missed "$f") | $(per unviable "$f") | $(per timeout "$f") |"
done <"$run/files.txt"
echo "missed: $run/missed.txt; logs: $run/core.log, $run/wide.log"
