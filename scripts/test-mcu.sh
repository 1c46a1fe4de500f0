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
# (`-icount`), and the C firmware's lines (examples/mcu-c: halfray-ffi from C on the Cortex-M4F)
#
#   mcu-c: N queries bit-identical to host (MACHINE ...)
#   mcu-c: query image .text BYTES bytes, stack BYTES bytes (... within the 8 KiB / 1 KiB budget)
#
# and exits 0 only if every machine matches and no aimed ray leaked. Installs what it needs
# (qemu-system-arm and gcc-arm-none-eabi from Debian, the rustup targets). Called by
# scripts/test-all.sh.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null 2>&1; then sudo -n "$@"
    else echo "test-mcu: need root (or sudo) to run: $*" >&2; return 1
    fi
}
if ! command -v qemu-system-arm >/dev/null 2>&1 || ! command -v arm-none-eabi-gcc >/dev/null 2>&1; then
    echo "test-mcu: installing qemu-system-arm and gcc-arm-none-eabi" >&2
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        qemu-system-arm gcc-arm-none-eabi >/dev/null
fi
rustup target add thumbv7em-none-eabihf thumbv7m-none-eabi >/dev/null 2>&1

# The baked meshes, and the host's lines ($host) to compare with.
source scripts/mcu-baked.sh

status=0
# run_image MACHINE CPU IMAGE PREFIX [compare-before-stack]: boots IMAGE in qemu, takes its line
# starting `PREFIX: MACHINE ` into $got and the host's into $want; fails (printing both) when
# qemu fails, the line is missing or it differs from the host's (up to " stack ..." when asked).
run_image() {
    local machine=$1 cpu=$2 image=$3 prefix=$4 upto=${5:-}
    local out rc=0
    out=$(timeout 600 qemu-system-arm -machine "$machine" -cpu "$cpu" -nographic -monitor none \
        -serial none -semihosting-config enable=on,target=native -kernel "$image" 2>&1) || rc=$?
    got=$(grep "^$prefix: $machine " <<<"$out" || true)
    want=$(grep "^$prefix: $machine " <<<"$host" || true)
    local cmp=$got
    [ -z "$upto" ] || cmp=${got% stack *}
    if [ "$rc" -ne 0 ] || [ -z "$got" ] || [ -z "$want" ] || [ "$cmp" != "$want" ]; then
        echo "test-mcu: $prefix on $machine differs from the host (qemu exit $rc)" >&2
        echo "  target: ${got:-$out}" >&2
        echo "  host:   $want" >&2
        status=1
        return 1
    fi
}
# budget IMAGE: from IMAGE's .text and $got's "stack N ... traversal M", sets $text, $stack,
# $traversal and $verdict (within or over the 8 KiB / 1 KiB budget).
budget() {
    text=$(readelf -S -W "$1" | sed -n 's/.* \.text *PROGBITS *[0-9a-f]* [0-9a-f]* \([0-9a-f]*\) .*/\1/p')
    text=$((16#${text:-0}))
    # got: ... stack BYTES traversal BYTES: the queries' own stack below their call, and the
    # traversal stack the image hands them; both count against the 1 KiB.
    stack=${got##* stack }
    stack=${stack%% *}
    traversal=${got##* traversal }
    if [ "$text" -le 8192 ] && [ $((stack + traversal)) -le 1024 ]; then verdict="within"; else verdict="over"; fi
}
check() { # machine target cpu baked-source
    local machine=$1 target=$2 cpu=$3
    MCU_BAKED=$4 cargo build -q --release --manifest-path "$manifest" -p mcu-firmware --target "$target"
    local image=$images/$target/release/mcu-firmware
    run_image "$machine" "$cpu" "$image" mcu || return 0
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
    run_image "$machine" "$cpu" "$image" mcu-query upto-stack || return 0
    # What the query path must not link (docs/embedded.md): f64 routines, panics, formatting.
    local linked
    linked=$(readelf -s -W "$image" | awk '{print $8}' | grep -E '^__aeabi_d|panic|fmt' | sort -u || true)
    if [ -n "$linked" ]; then
        echo "test-mcu: the $machine query image links what the query path must not:" $linked >&2
        status=1
    fi
    budget "$image"
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
    # `|| true`: no row is the failure the branch below reports, not a `set -e` exit.
    rows=$(grep "^mcu-bench: $machine " <<<"$out" | grep -v calibration | awk '{printf "%s %s, ", $3, $4}' || true)
    if [ "$rc" -ne 0 ] || [ -z "$rows" ]; then
        echo "test-mcu: the $machine bench image failed (qemu exit $rc): $out" >&2
        status=1
        return
    fi
    echo "mcu: instructions per closest-hit query on $machine ($cpu): ${rows%, }"
}
bench mps2-an386 thumbv7em-none-eabihf cortex-m4 "$MCU_BAKED_M4F"
bench lm3s6965evb thumbv7m-none-eabi cortex-m3 "$MCU_BAKED_M3"

# The C firmware (examples/mcu-c): halfray-ffi's static library for the Cortex-M4F, linked by
# gcc-arm-none-eabi into a C image with the baked torus (`--format bin`) and the query image's
# rays; its answers must be the host's (mcu-host's `mcu-c:` line), and its image is held to
# the same 8 KiB / 1 KiB budget (the whole image's `.text`: start-up, hash and printing
# included; the traversal stack counted as for the Rust image). Linking fails, naming
# `halfray_ffi_error_a_panic_path_is_linked`, if any code the firmware reaches could panic.
mcu_c() {
    local machine=mps2-an386 target=thumbv7em-none-eabihf cpu=cortex-m4
    cargo build -q --release --manifest-path ffi/Cargo.toml --target "$target"
    local lib=${CARGO_TARGET_DIR:-$PWD/ffi/target}/$target/release/libhalfray_ffi.a
    local image=$baked/mcu-c.elf
    make -s -C examples/mcu-c LIB="$lib" BAKED="$MCU_C_BAKED" RAYS="$MCU_C_RAYS" OUT="$image"
    run_image "$machine" "$cpu" "$image" mcu-c upto-stack || return 0
    budget "$image"
    local queries hash hits leaks
    read -r _ _ queries _ _ hash _ hits _ leaks _ <<<"$got"
    echo "mcu-c: $queries queries bit-identical to host ($machine: $cpu, $target; hash $hash, $hits hits, $leaks leaks)"
    echo "mcu-c: query image .text $text bytes, stack $((stack + traversal)) bytes ($stack below the query call + $traversal of traversal stack; $machine: $cpu, $target; $queries queries bit-identical to host, hash $hash; $verdict the 8 KiB / 1 KiB budget)"
    if [ "$verdict" != within ]; then
        echo "test-mcu: the C firmware's image is over the 8 KiB / 1 KiB budget" >&2
        status=1
    fi
}
mcu_c
exit "$status"
