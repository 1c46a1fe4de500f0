#!/usr/bin/env bash
# The README's test command: sets up everything a fresh Debian 12 machine lacks, then runs the
# whole test suite. Idempotent; safe to re-run. `.ci/run` calls exactly this.
#
#   bash scripts/test-all.sh            # everything
#   SKIP_EMBREE=1 SKIP_FUZZ=1 bash scripts/test-all.sh   # quick local run
#
# Stages (each prints a `== stage` header; any failure stops the run with a non-zero exit):
#   toolchain   rustup targets for the embedded builds (+ rustfmt/clippy components)
#   lint        cargo fmt --check; cargo clippy --workspace --all-targets -D warnings; the cluster and
#               campaign scripts' exit statuses and refusals (scripts/test-scripts.sh, stand-in binaries)
#   no_std      halfray-core built for thumbv7em-none-eabihf, thumbv7m-none-eabi, thumbv6m-none-eabi and
#               riscv32imac-unknown-none-elf; the thumb probe for thumbv7em-none-eabihf (no std, no alloc)
#   mcu         the core under QEMU on a Cortex-M4F and a Cortex-M3, results bit-identical to the host
#               (scripts/test-mcu.sh; installs qemu-system-arm), and the C firmware on halfray-ffi
#   ffi         halfray-ffi: lint, generated header matches, sanitized host C test (scripts/test-ffi.sh)
#   crate       halfray-core as crates.io gets it: docs with -D warnings, publish --dry-run,
#               and a build with the rust-version toolchain (MSRV)
#   test        cargo test --workspace (unit, integration, numerical-stability, fuzz-corpus replay)
#   embree      Embree 4.4.0 from the pinned PyPI wheel; Embree tests; crosscheck on every shared mesh;
#               the same as 4 local shards merged equals it unsharded
#   bench       halfray bench accuracy --quick (runs; watertight must show zero leaks); the corpus
#               (scripts/corpus.sh) through bench bvh with few rays; the three charts from the JSON;
#               crosscheck of the corpus's `far` mesh (zero genuine mismatches, zero leaks)
#   fuzz        nightly + cargo-fuzz; every fuzz target for FUZZ_SECONDS (default 30) each
#   cluster     a real one-node Slurm cluster (Debian slurmctld/slurmd/munge, scripts/slurm-local.sh):
#               the crosscheck array + merge (requeued task resumes, merged = unsharded, cancelled
#               task fails the merge naming its shard); the fuzz array + merge reports a planted
#               crash (needs the embree stage; SKIP_CLUSTER=1 skips it)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$PWD
export CARGO_TERM_COLOR=never
MESHES=${HALFRAY_MESHES:-$ROOT/../shared/meshes}
# One full run builds every profile once: incremental caches and full debug info would only cost
# disk (a CI machine ran out of it mid-build), so this run keeps line tables for backtraces only.
export CARGO_INCREMENTAL=0
export CARGO_PROFILE_DEV_DEBUG=line-tables-only CARGO_PROFILE_TEST_DEBUG=line-tables-only
export CARGO_PROFILE_RELEASE_DEBUG=line-tables-only
stage() {
    echo; echo "== $1 ($(date +%H:%M:%S); $(df -h --output=avail . | tail -1 | tr -d ' ') free on disk)"
}
t0=$(date +%s)

stage toolchain
rustup target add thumbv7em-none-eabihf thumbv7m-none-eabi thumbv6m-none-eabi riscv32imac-unknown-none-elf
rustup component add rustfmt clippy >/dev/null 2>&1 || true

stage lint
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
python3 scripts/import-graph.py --self-test && python3 scripts/import-graph.py  # 0 loops, 0 upward imports
bash scripts/test-scripts.sh  # the cluster and campaign scripts' contracts, with stand-in binaries

stage no_std
# Cortex-M4F, Cortex-M3 (soft float), Cortex-M0+ (no FPU, no atomic CAS), RISC-V RV32IMAC.
for target in thumbv7em-none-eabihf thumbv7m-none-eabi thumbv6m-none-eabi riscv32imac-unknown-none-elf; do
    cargo build -p halfray-core --target "$target"
done
cargo build --release --manifest-path examples/thumb-probe/Cargo.toml --target thumbv7em-none-eabihf

stage mcu
# The core on emulated Cortex-M4F and Cortex-M3 (QEMU), bit-identical to the host.
bash scripts/test-mcu.sh

stage ffi
# The C ABI: header check and the sanitized host C test (the firmware ran in the mcu stage).
bash scripts/test-ffi.sh

stage crate
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -p halfray-core
# The frontend library's docs too: no broken or private links.
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -p halfray
cargo publish --dry-run --allow-dirty -p halfray-core
msrv=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml)
rustup toolchain install "$msrv" --profile minimal
cargo "+$msrv" build -p halfray-core

stage test
# Tests that skip part of their checks (a SIMD level this CPU lacks) append a line naming
# themselves and why to $HALFRAY_SKIP_LOG, printed below; on a CPU that lists AVX2 and FMA
# nothing may skip (HALFRAY_REQUIRE_AVX2 makes a skip fail).
export HALFRAY_SKIP_LOG=$ROOT/target/skipped-tests.txt
mkdir -p target && : >"$HALFRAY_SKIP_LOG"
if grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo; then
    export HALFRAY_REQUIRE_AVX2=1
else
    echo "this CPU lacks AVX2 or FMA: the AVX2 comparisons are skipped (listed after the tests)"
fi
cargo test --workspace
report_skips() {
    if [ -s "$HALFRAY_SKIP_LOG" ]; then
        echo "skipped tests ($(sort -u "$HALFRAY_SKIP_LOG" | wc -l)):"; sort -u "$HALFRAY_SKIP_LOG"
    else
        echo "skipped tests: none"
    fi
}
report_skips

[ "${SKIP_EMBREE:-0}" = 1 ] && echo "SKIPPED stage embree (SKIP_EMBREE=1): Embree tests, crosscheck_scale.rs, crosscheck_meshes.rs, charts_cli.rs's Embree tests, crosscheck runs" | tee -a "$HALFRAY_SKIP_LOG"
if [ "${SKIP_EMBREE:-0}" != 1 ]; then
    stage embree
    bash scripts/setup-embree.sh
    export EMBREE_DIR=$ROOT/.embree
    cargo clippy -p halfray --features embree --all-targets -- -D warnings
    cargo test -p halfray --features embree
    # These test files compile (wholly or partly) to nothing without the feature: make sure
    # this run had their Embree tests, and count them.
    for t in crosscheck_scale crosscheck_meshes charts_cli; do
        with=$(cargo test -q -p halfray --features embree --test "$t" -- --list 2>/dev/null | grep -c ': test$' || true)
        without=$(cargo test -q -p halfray --test "$t" -- --list 2>/dev/null | grep -c ': test$' || true)
        [ "$with" -gt "$without" ] || { echo "$t.rs: no Embree tests under --features embree ($with with, $without without)"; exit 1; }
        echo "$t.rs: $with tests ran under --features embree ($((with - without)) of them need Embree)"
    done
    # Every shared mesh, 100 000 rays per set: zero genuine mismatches and zero watertight
    # leaks, or a non-zero exit.
    mkdir -p target/ci
    cargo run --release -p halfray --features embree -- crosscheck "$MESHES"/*.obj \
        --rays "${CROSSCHECK_RAYS:-100000}" --json target/ci/crosscheck.json \
        --depth-image target/ci/crosscheck-depth.png
    # The same meshes as 4 shards through the local runner (crosscheck-local.sh) merge to the
    # unsharded run, count for count (the Slurm array: stage cluster).
    bash scripts/crosscheck-verify-shards.sh target/ci/shards "$MESHES"/*.obj --rays 10000
fi

stage bench
mkdir -p target/ci
features=""
[ "${SKIP_EMBREE:-0}" != 1 ] && features="--features embree"   # adds the Embree rows
cargo run --release -p halfray $features -- bench accuracy --quick --json target/ci/accuracy.json --chart target/ci/accuracy.png
python3 - target/ci/accuracy.json <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
rows = {v["name"]: v for v in report["variants"]}
for name in ("watertight", "watertight-f32", "f64-reference"):
    leaks = rows[name]["leaks_per_million"]
    assert leaks == 0, f"{name}: {leaks} leaks per million edge/vertex rays"
    assert rows[name]["leak_rays"] > 0, f"{name}: no edge/vertex rays were tested"
print("bench accuracy --quick: watertight variants have zero leaks")
PY
# The corpus benchmark as docs/benchmarks.md runs it, with few rays (figures are not checked
# here: speed belongs to benchmarks), then each chart from its run's JSON.
bash scripts/corpus.sh $features
cargo run --release -p halfray $features -- bench bvh --mesh-list scenes/corpus/corpus.txt \
    --width 64 --rays 10000 --json target/ci/bench-bvh.json > target/ci/bench-bvh.txt
tail -n 12 target/ci/bench-bvh.txt
if [ "${SKIP_EMBREE:-0}" != 1 ]; then
    # The corpus's mesh far from the coordinate origin (its node boxes, padding and edge rays
    # are what such a mesh tests): zero genuine mismatches and zero leaks, or a non-zero exit.
    # (Its per-set lines go to stderr, the table to the file.)
    target/release/halfray crosscheck target/corpus/far.obj --rays "${CROSSCHECK_RAYS:-100000}" \
        --json target/ci/crosscheck-far.json > target/ci/crosscheck-far.txt
    tail -n 2 target/ci/crosscheck-far.txt
fi
target/release/halfray chart accuracy target/ci/accuracy.json -o target/ci/accuracy.svg
if [ "${SKIP_EMBREE:-0}" != 1 ]; then
    target/release/halfray chart corpus target/ci/bench-bvh.json -o target/ci/corpus.svg
    target/release/halfray chart corpus target/ci/bench-bvh.json -o target/ci/corpus.png
    target/release/halfray chart disagreements target/ci/crosscheck.json -o target/ci/disagreements.svg
fi

if [ "${SKIP_FUZZ:-0}" != 1 ]; then
    stage fuzz
    FUZZ_SECONDS=${FUZZ_SECONDS:-30} bash scripts/fuzz-ci.sh
else
    echo "SKIPPED stage fuzz (SKIP_FUZZ=1)" | tee -a "$HALFRAY_SKIP_LOG"
fi
if [ "${SKIP_EMBREE:-0}" != 1 ] && [ "${SKIP_CLUSTER:-0}" != 1 ]; then
    stage cluster
    # The docs/cluster Slurm files on a real Slurm cluster, torn down when the checks end.
    bash scripts/slurm-local.sh bash -c 'bash scripts/slurm-ci-crosscheck.sh target/ci/cluster/crosscheck "$@" &&
        bash scripts/slurm-ci-fuzz.sh target/ci/cluster/fuzz' _ "$MESHES"/*.obj
else
    echo "SKIPPED stage cluster (SKIP_EMBREE=1 or SKIP_CLUSTER=1)" | tee -a "$HALFRAY_SKIP_LOG"
fi
echo; report_skips

echo
echo "== all stages passed in $(( $(date +%s) - t0 )) s"
