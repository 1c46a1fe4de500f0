#!/usr/bin/env bash
# A stand-in for `cargo` (installed as `cargo` on PATH by scripts/test-scripts.sh) for the fuzz
# scripts' set-up (scripts/fuzz-tools.sh): versions and `fuzz build [ARGS]` succeed; `fuzz list` fails
# (FAKE_LIST=fail), lists nothing (FAKE_LIST=empty) or lists `a` and `b`.
[ "${1:-}" = +nightly ] && shift
case "$*" in
    --version | "fuzz --version") echo "fake 1.0" ;;
    "fuzz build" | "fuzz build "*) ;;
    "fuzz list")
        case ${FAKE_LIST:-} in
            fail) echo "error: no fuzz directory" >&2; exit 1 ;;
            empty) ;;
            *) printf 'a\nb\n' ;;
        esac ;;
    *) echo "fake cargo: unexpected: $*" >&2; exit 1 ;;
esac
