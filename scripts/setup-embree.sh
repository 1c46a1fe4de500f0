#!/usr/bin/env bash
# Set up Intel Embree 4.4.0 for `cargo ... --features embree` (issue 6). Idempotent.
#
# Debian 12 packages only Embree 3, so the library comes from the PyPI wheel
# `embreex==4.4.0.post1` (manylinux x86-64), whose `embreex.libs/` folder holds
# `libembree4-4aef3270.so.4` (its soname) and `libtbb-dcf63f8c.so.12`. This script:
#   1. installs `libclang-dev` (bindgen in `embree4-sys` needs it) if dpkg says it is missing,
#   2. downloads the pinned wheel into `.embree/wheel/` (git-ignored) unless it is already there,
#      and checks its SHA-256,
#   3. extracts `embreex.libs/*` into `.embree/embreex.libs/`,
#   4. creates the `libembree4.so` symlink that `-lembree4` needs,
#   5. prints the environment to use (`EMBREE_DIR`; frontend/build.rs adds link path and rpath).
#
# Usage (from anywhere; paths are relative to the repository root):
#   bash scripts/setup-embree.sh
#   EMBREE_DIR=$PWD/.embree cargo test -p halfray --features embree embree
# Runs non-interactively (CI=true, no stdin). Needs root (or sudo) only if libclang-dev is missing.
set -euo pipefail

START_NS=$(date +%s%N)
REPO_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
EMBREE_DIR=${EMBREE_SETUP_DIR:-$REPO_ROOT/.embree}

# Pinned artefact. The wheel's Python tag does not matter to us (we only take the shared
# libraries), but pinning the tags makes the download, and so its hash, independent of the
# local interpreter.
WHEEL_VERSION=4.4.0.post1
WHEEL_FILE=embreex-${WHEEL_VERSION}-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl
WHEEL_SHA256=2cd0f7d5c6342e6247e31f700761689cae7829454d8c6de0c41e62124a023e1f
EMBREE_SONAME=libembree4-4aef3270.so.4
TBB_SONAME=libtbb-dcf63f8c.so.12

log() { echo "setup-embree: $*" >&2; }
die() { log "error: $*"; exit 1; }

[ "$(uname -m)" = x86_64 ] || die "the embreex wheel is x86-64 only (this is $(uname -m))"

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null 2>&1; then sudo -n "$@"
    else die "need root to run: $*"; fi
}

# 1. libclang-dev for bindgen (embree4-sys build script).
apt_updated=0
apt_install() {
    export DEBIAN_FRONTEND=noninteractive
    if [ "$apt_updated" -eq 0 ]; then
        as_root apt-get update -q </dev/null >&2
        apt_updated=1
    fi
    as_root apt-get install -y -q --no-install-recommends "$@" </dev/null >&2
}
if dpkg -s libclang-dev >/dev/null 2>&1; then
    log "libclang-dev: already installed"
else
    log "libclang-dev: installing"
    apt_install libclang-dev
fi

# 2. The wheel (only the download needs pip; a fresh Debian 12 may lack it).
WHEEL_PATH=$EMBREE_DIR/wheel/$WHEEL_FILE
sha_ok() { [ -f "$1" ] && echo "$WHEEL_SHA256  $1" | sha256sum -c --status -; }
if sha_ok "$WHEEL_PATH"; then
    log "wheel: already downloaded ($WHEEL_FILE)"
else
    if ! python3 -m pip --version >/dev/null 2>&1; then
        log "python3-pip: installing"
        apt_install python3-pip
    fi
    log "wheel: downloading embreex==$WHEEL_VERSION"
    mkdir -p "$EMBREE_DIR/wheel"
    rm -f "$WHEEL_PATH"
    python3 -m pip download --no-deps --only-binary=:all: --no-input --disable-pip-version-check \
        --python-version 3.11 --implementation cp --abi cp311 --platform manylinux_2_28_x86_64 \
        "embreex==$WHEEL_VERSION" -d "$EMBREE_DIR/wheel" </dev/null >&2
    [ -f "$WHEEL_PATH" ] || die "pip did not produce $WHEEL_PATH"
    sha_ok "$WHEEL_PATH" || { rm -f "$WHEEL_PATH"; die "SHA-256 mismatch for $WHEEL_FILE"; }
fi

# 3. Extract embreex.libs/* (only if missing or older than the wheel). Python's zipfile is used
#    so that `unzip` need not be installed.
LIB_DIR=$EMBREE_DIR/embreex.libs
if [ -f "$LIB_DIR/$EMBREE_SONAME" ] && [ -f "$LIB_DIR/$TBB_SONAME" ] \
        && [ ! "$WHEEL_PATH" -nt "$LIB_DIR/$EMBREE_SONAME" ]; then
    log "libraries: already extracted"
else
    log "libraries: extracting embreex.libs/ into $EMBREE_DIR"
    python3 - "$WHEEL_PATH" "$EMBREE_DIR" <<'EOF'
import os, sys, zipfile
wheel, dest = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(wheel) as z:
    names = [n for n in z.namelist() if n.startswith("embreex.libs/") and not n.endswith("/")]
    if not names:
        sys.exit("no embreex.libs/ in " + wheel)
    for n in names:
        tmp = os.path.join(dest, n + ".tmp")
        os.makedirs(os.path.dirname(tmp), exist_ok=True)
        with z.open(n) as src, open(tmp, "wb") as out:
            out.write(src.read())
        os.chmod(tmp, 0o755)
        os.replace(tmp, os.path.join(dest, n))  # atomic: a concurrent reader never sees half a file
        os.utime(os.path.join(dest, n))
EOF
fi
[ -f "$LIB_DIR/$EMBREE_SONAME" ] || die "missing $LIB_DIR/$EMBREE_SONAME after extraction"

# 4. -lembree4 needs libembree4.so; the run-time loader then asks for the soname.
if [ "$(readlink "$LIB_DIR/libembree4.so" 2>/dev/null)" != "$EMBREE_SONAME" ]; then
    ln -sfn "$EMBREE_SONAME" "$LIB_DIR/libembree4.so"
    log "symlink: libembree4.so -> $EMBREE_SONAME"
else
    log "symlink: already in place"
fi

END_NS=$(date +%s%N)
log "done in $(( (END_NS - START_NS) / 1000000 )) ms"

# 5. The environment to use (stdout, so `eval "$(bash scripts/setup-embree.sh)"` works).
echo "export EMBREE_DIR=$EMBREE_DIR"
log "then: cargo test -p halfray --features embree embree"
log "(frontend/build.rs adds -L and an rpath to $LIB_DIR; no LD_LIBRARY_PATH needed)"
