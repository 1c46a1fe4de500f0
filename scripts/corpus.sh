#!/usr/bin/env bash
# Generates the corpus's meshes (scenes/corpus/corpus.txt) into target/corpus/: each kind of
# `halfray mesh generate` with seed 1 and its default size (docs/benchmarks.md). Deterministic:
# the same files on every machine. Takes a few seconds once the binary is built.
#
# Usage (from anywhere):
#   bash scripts/corpus.sh [cargo build flags, e.g. --features embree]
# The binary is taken from where cargo builds it ($CARGO_TARGET_DIR when set, else target/); the
# meshes always go to target/corpus/ (scenes/corpus/corpus.txt names them there). Then, from the
# repository root:
#   halfray bench bvh --mesh-list scenes/corpus/corpus.txt --json target/corpus/bench.json
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
cargo build --release -p halfray "$@"
bin=${CARGO_TARGET_DIR:-target}/release/halfray   # where cargo built it
mkdir -p target/corpus
for kind in sphere terrain beams room scatter far; do
    "$bin" mesh generate "$kind" --seed 1 -o "target/corpus/$kind.obj"
done
