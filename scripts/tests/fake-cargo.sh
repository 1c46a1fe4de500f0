#!/usr/bin/env bash
# A stand-in for `cargo` (installed as `cargo` on PATH by scripts/test-scripts.sh) for the fuzz
# scripts (scripts/fuzz-tools.sh, scripts/fuzz-cmin.sh): versions and `fuzz build [ARGS]` succeed;
# `fuzz run TARGET DIR` adds a new input to DIR (`grown`, its content new each time); `fuzz list`
# fails (FAKE_LIST=fail), lists nothing (FAKE_LIST=empty) or lists `a` and `b`; `fuzz cmin
# TARGET DIR` renames every file of DIR to its SHA-1, as libFuzzer's `-merge=1` names the inputs
# it keeps, or (FAKE_CMIN=fail) leaves DIR as it is, prints `Failed to minimize corpus` and exits
# 0, as cargo-fuzz does when the merge fails.
[ "${1:-}" = +nightly ] && shift
case "$*" in
    --version | "fuzz --version") echo "fake 1.0" ;;
    "fuzz build" | "fuzz build "*) ;;
    "fuzz run "*) date +%s%N >"$4/grown" ;;
    "fuzz cmin "*)
        if [ "${FAKE_CMIN:-}" = fail ]; then echo "Failed to minimize corpus: exit status: 1"; exit 0; fi
        for f in "$4"/*; do
            sum=$(sha1sum <"$f" | cut -c1-40)
            [ "$f" = "$4/$sum" ] || mv "$f" "$4/$sum"
        done ;;
    "fuzz list")
        case ${FAKE_LIST:-} in
            fail) echo "error: no fuzz directory" >&2; exit 1 ;;
            empty) ;;
            *) printf 'a\nb\n' ;;
        esac ;;
    *) echo "fake cargo: unexpected: $*" >&2; exit 1 ;;
esac
