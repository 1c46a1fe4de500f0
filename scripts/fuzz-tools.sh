# shellcheck shell=bash
# Sourced by fuzz-ci.sh, fuzz-campaign.sh and fuzz-cmin.sh: installs what fuzzing needs when it is missing
# (the nightly toolchain, cargo-fuzz), builds every target, and sets `targets` to the names
# given as arguments or to every target; exits 1 (the caller with it) when listing the targets
# fails or lists none. Leaves the caller in the repository root with `set -euo pipefail`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if ! cargo +nightly --version >/dev/null 2>&1; then
    rustup toolchain install nightly --profile minimal
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi
cargo +nightly fuzz build
if [ $# -gt 0 ]; then
    targets=("$@")
else
    # The list's own status counts: a failed `fuzz list`, or one naming no target, stops the caller.
    list=$(cargo +nightly fuzz list) || { echo "fuzz: \`cargo +nightly fuzz list\` failed" >&2; exit 1; }
    mapfile -t targets < <(grep -v '^[[:space:]]*$' <<<"$list" || true)
fi
[ "${#targets[@]}" -gt 0 ] || { echo "fuzz: no fuzz target (\`cargo +nightly fuzz list\` listed none)" >&2; exit 1; }
