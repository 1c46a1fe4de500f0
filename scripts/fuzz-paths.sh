# shellcheck shell=bash
# Sourced by scripts/fuzz-task.sh and scripts/fuzz-merge.sh: the targets of a fuzz run and where
# their binaries and seeds are.
#
#   FUZZ_TARGETS  space-separated target names; task K of a run fuzzes the K-th (0-based)
#   FUZZ_BIN      folder of the built targets (default: fuzz/target/<host triple>/release, where
#                 `cargo +nightly fuzz build` puts them)
#   FUZZ_SEEDS    folder of per-target seed folders, read only (default: fuzz/corpus)
#
# Sets `fuzz_root` (the repository) and `fuzz_targets` (array); defines fuzz_bin and fuzz_seeds.
fuzz_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
: "${FUZZ_TARGETS:?export FUZZ_TARGETS (space-separated fuzz target names, e.g. \"\$(cargo +nightly fuzz list | xargs)\")}"
read -r -a fuzz_targets <<<"$FUZZ_TARGETS"

# fuzz_bin TARGET: prints the target's binary; fails naming it when it is not built.
fuzz_bin() {
    local b
    if [ -n "${FUZZ_BIN:-}" ]; then
        b=$FUZZ_BIN/$1
    else
        b=$(ls "$fuzz_root"/fuzz/target/*/release/"$1" 2>/dev/null | head -n 1)
    fi
    [ -n "$b" ] && [ -x "$b" ] || {
        echo "fuzz: target $1 is not built (${b:-no fuzz/target/*/release/$1}; run cargo +nightly fuzz build)" >&2
        return 1
    }
    echo "$b"
}

# fuzz_seeds TARGET: prints the target's seed folder, when there is one.
fuzz_seeds() {
    local d=${FUZZ_SEEDS:-$fuzz_root/fuzz/corpus}/$1
    [ -d "$d" ] && echo "$d"
}
