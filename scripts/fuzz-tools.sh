# Sourced by fuzz-ci.sh, fuzz-campaign.sh and fuzz-cmin.sh: installs what fuzzing needs when it is missing
# (the nightly toolchain, cargo-fuzz), builds every target, and sets `targets` to the names
# given as arguments or to every target. Leaves the caller in the repository root with
# `set -euo pipefail`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if ! cargo +nightly --version >/dev/null 2>&1; then
    rustup toolchain install nightly --profile minimal
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi
cargo +nightly fuzz build
if [ $# -gt 0 ]; then targets=("$@"); else mapfile -t targets < <(cargo +nightly fuzz list); fi
