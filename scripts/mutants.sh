#!/usr/bin/env bash
# Mutation testing of the core's most critical files with cargo-mutants: a fixed, reproducible
# sample of about PER_FILE mutants per file (every n-th of the file's mutants in cargo-mutants'
# own order, `--shard 0/n`, n = count / PER_FILE), tested by TEST_PACKAGES. Prints one table
# row per file: mutants in the file, sampled, caught / missed / unviable / timeout; the missed
# ones are listed under target/mutants/<file>/mutants.out/missed.txt.
#
#   PER_FILE=100 TEST_PACKAGES=halfray-core,halfray-tests bash scripts/mutants.sh   # the full run
#   PER_FILE=4 TEST_PACKAGES=halfray-core bash scripts/mutants.sh                   # a quick sample
#   bash scripts/mutants.sh --in-diff DIFF                                          # a branch's lines
#
# A mutant costs ~20–40 s to build and test here (2 cores), so the full run (~500 mutants) is
# a job of several hours, not a CI stage.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PER_FILE=${PER_FILE:-100}
TEST_PACKAGES=${TEST_PACKAGES:-halfray-core,halfray-tests}
FILES=(core/src/aabb.rs core/src/triangle/watertight.rs core/src/bvh/traverse.rs
    core/src/halfedge/subdivide.rs core/src/halfedge/collapse.rs)

if ! cargo mutants --version >/dev/null 2>&1; then
    cargo install cargo-mutants --locked
fi
out=target/mutants
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
    n=$(( total / PER_FILE )); [ "$n" -ge 1 ] || n=1
    dir="$out/$(basename "$f" .rs)"
    # cargo-mutants exits non-zero when a mutant is missed: the table says so.
    cargo mutants -f "$f" --shard "0/$n" --test-package "$TEST_PACKAGES" -o "$dir" \
        >"$dir.log" 2>&1 || true
    m="$dir/mutants.out"
    c=$(count "$m/caught.txt"); x=$(count "$m/missed.txt")
    u=$(count "$m/unviable.txt"); t=$(count "$m/timeout.txt")
    echo "| \`$f\` | $total | $((c + x + u + t)) | $c | $x | $u | $t |"
done
