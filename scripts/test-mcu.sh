#!/usr/bin/env bash
# The core on emulated microcontrollers (issue 14, item 1): the `mcu-check` image
# (examples/mcu) runs under QEMU on a Cortex-M4F (`mps2-an386`, thumbv7em-none-eabihf, hardware
# single precision, `f64` in software) and a Cortex-M3 (`lm3s6965evb`, thumbv7m-none-eabi, all
# floating point in software), and its result hash (every closest/any-hit answer's primitive,
# `t` and barycentric bits; the Loop-subdivided mesh's positions) must equal the hash of the
# same code run on the host. Prints one line per machine:
#
#   mcu: N queries bit-identical to host (MACHINE)
#   mcu: query image .text BYTES bytes, stack BYTES bytes (BELOW below the query call + TRAV of traversal stack; MACHINE ...)
#
# then the instructions per closest-hit query of every triangle variant on each machine
# (`-icount`), and exits 0 only if every machine matches and no aimed ray leaked. Installs what it needs
# (qemu-system-arm from Debian, the rustup targets). Called by scripts/test-all.sh.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null 2>&1; then sudo -n "$@"
    else echo "test-mcu: need root (or sudo) to run: $*" >&2; return 1
    fi
}
if ! command -v qemu-system-arm >/dev/null 2>&1; then
    echo "test-mcu: installing qemu-system-arm" >&2
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends qemu-system-arm >/dev/null
fi
rustup target add thumbv7em-none-eabihf thumbv7m-none-eabi >/dev/null 2>&1

manifest=examples/mcu/Cargo.toml
# The meshes each image queries from flash, baked here by `halfray bake`: the torus (4 608
# triangles) for the Cortex-M4F; for the Cortex-M3's 256 KiB of flash, the octahedron
# subdivided three times (512 triangles).
baked=$PWD/examples/mcu/target/baked
mkdir -p "$baked"
cargo build -q --release -p halfray
# Where cargo puts what it builds: CARGO_TARGET_DIR when set (for the workspace and for the
# images alike), else each workspace's own target/.
halfray=${CARGO_TARGET_DIR:-$PWD/target}/release/halfray
images=${CARGO_TARGET_DIR:-$PWD/examples/mcu/target}
"$halfray" bake scenes/meshes/torus.obj -o "$baked/torus.rs" >&2
"$halfray" mesh subdivide scenes/meshes/octahedron.obj --levels 3 -o "$baked/octahedron-3.obj" >/dev/null
"$halfray" bake "$baked/octahedron-3.obj" -o "$baked/octahedron-3.rs" >&2
export MCU_BAKED_M4F=$baked/torus.rs MCU_BAKED_M3=$baked/octahedron-3.rs
host=$(cargo run -q --release --manifest-path "$manifest" -p mcu-host)

status=0
check() { # machine target cpu baked-source
    local machine=$1 target=$2 cpu=$3
    MCU_BAKED=$4 cargo build -q --release --manifest-path "$manifest" -p mcu-firmware --target "$target"
    local image=$images/$target/release/mcu-firmware
    local out rc=0
    out=$(timeout 600 qemu-system-arm -machine "$machine" -cpu "$cpu" -nographic -monitor none \
        -serial none -semihosting-config enable=on,target=native -kernel "$image" 2>&1) || rc=$?
    local got want
    got=$(grep "^mcu: $machine " <<<"$out" || true)
    want=$(grep "^mcu: $machine " <<<"$host" || true)
    if [ "$rc" -ne 0 ] || [ -z "$got" ] || [ "$got" != "$want" ]; then
        echo "test-mcu: $machine differs from the host (qemu exit $rc)" >&2
        echo "  target: ${got:-$out}" >&2
        echo "  host:   $want" >&2
        status=1
        return
    fi
    # got: mcu: MACHINE QUERIES queries hash HEX hits N leaks N
    read -r _ _ queries _ _ hash _ hits _ leaks <<<"$got"
    echo "mcu: $queries queries bit-identical to host ($machine: $cpu, $target; hash $hash, $hits hits, $leaks leaks)"
}
check mps2-an386 thumbv7em-none-eabihf cortex-m4 "$MCU_BAKED_M4F"
check lm3s6965evb thumbv7m-none-eabi cortex-m3 "$MCU_BAKED_M3"

# The query path alone: the `mcu-query` image links only the baked BVH's loader and closest/any
# hit with the f64-free watertight test (WatertightF32Exact) and a lean ray loop; its answers
# must equal the host's, its `.text` is the query path's size and the stack its queries used
# is measured by painting. Budget (issue 14): 8 KiB of .text, 1 KiB of stack; printed, with
# whether it holds. The budget is the Cortex-M4F's (the target with the FPU the core is made
# for): over it, the script fails; the soft-float Cortex-M3 image is reported, not held to it.
query() { # machine target cpu baked-source held-to-budget
    local machine=$1 target=$2 cpu=$3 held=$5
    MCU_BAKED=$4 cargo build -q --release --manifest-path "$manifest" -p mcu-firmware \
        --bin mcu-query --target "$target"
    local image=$images/$target/release/mcu-query
    local out rc=0
    out=$(timeout 600 qemu-system-arm -machine "$machine" -cpu "$cpu" -nographic -monitor none \
        -serial none -semihosting-config enable=on,target=native -kernel "$image" 2>&1) || rc=$?
    local got want
    got=$(grep "^mcu-query: $machine " <<<"$out" || true)
    want=$(grep "^mcu-query: $machine " <<<"$host" || true)
    if [ "$rc" -ne 0 ] || [ -z "$got" ] || [ "${got% stack *}" != "$want" ]; then
        echo "test-mcu: the $machine query image differs from the host (qemu exit $rc)" >&2
        echo "  target: ${got:-$out}" >&2
        echo "  host:   $want" >&2
        status=1
        return
    fi
    local text stack verdict
    text=$(readelf -S -W "$image" | sed -n 's/.* \.text *PROGBITS *[0-9a-f]* [0-9a-f]* \([0-9a-f]*\) .*/\1/p')
    text=$((16#${text:-0}))
    # got: ... stack BYTES traversal BYTES: the queries' own stack below their call, and the
    # traversal stack the image hands them; both count against the 1 KiB.
    stack=${got##* stack }
    stack=${stack%% *}
    traversal=${got##* traversal }
    if [ "$text" -le 8192 ] && [ $((stack + traversal)) -le 1024 ]; then verdict="within"; else verdict="over"; fi
    read -r _ _ queries _ _ hash _ <<<"$got"
    echo "mcu: query image .text $text bytes, stack $((stack + traversal)) bytes ($stack below the query call + $traversal of traversal stack; $machine: $cpu, $target; $queries queries bit-identical to host, hash $hash; $verdict the 8 KiB / 1 KiB budget)"
    if [ "$held" = budget ] && [ "$verdict" != within ]; then
        echo "test-mcu: the $machine query image is over the 8 KiB / 1 KiB budget" >&2
        status=1
    fi
}
query mps2-an386 thumbv7em-none-eabihf cortex-m4 "$MCU_BAKED_M4F" budget
query lm3s6965evb thumbv7m-none-eabi cortex-m3 "$MCU_BAKED_M3" report

# What a ray costs there: instructions per closest-hit query for each triangle variant, on
# the baked BVH, counted under `-icount shift=0` (1 ns of virtual time per instruction,
# SysTick calibrated in the image). Deterministic: the same numbers on every run.
bench() { # machine target cpu baked-source
    local machine=$1 target=$2 cpu=$3
    MCU_BAKED=$4 cargo build -q --release --manifest-path "$manifest" -p mcu-firmware \
        --features bench --target "$target" --target-dir examples/mcu/target/bench
    local out rc=0
    out=$(timeout 600 qemu-system-arm -machine "$machine" -cpu "$cpu" -nographic -monitor none \
        -serial none -icount shift=0 -semihosting-config enable=on,target=native \
        -kernel "examples/mcu/target/bench/$target/release/mcu-firmware" 2>&1) || rc=$?
    local rows
    rows=$(grep "^mcu-bench: $machine " <<<"$out" | grep -v calibration | awk '{printf "%s %s, ", $3, $4}')
    if [ "$rc" -ne 0 ] || [ -z "$rows" ]; then
        echo "test-mcu: the $machine bench image failed (qemu exit $rc): $out" >&2
        status=1
        return
    fi
    echo "mcu: instructions per closest-hit query on $machine ($cpu): ${rows%, }"
}
bench mps2-an386 thumbv7em-none-eabihf cortex-m4 "$MCU_BAKED_M4F"
bench lm3s6965evb thumbv7m-none-eabi cortex-m3 "$MCU_BAKED_M3"
exit "$status"
