# shellcheck shell=bash
# Sourced by the cross-check scripts (scripts/crosscheck-*.sh): what they share.

# no_threads_arg WHO ARGS...: exits 2 when the cross-check arguments ARGS hold `--threads`:
# the runner gives every run its own `--threads THREADS` (the environment variable), and the
# binary refuses the option twice.
no_threads_arg() {
    local who=$1 a
    shift
    for a in "$@"; do
        case $a in
            --threads | --threads=*)
                echo "$who: the cross-check arguments hold $a; set the threads of each run with THREADS=N in the environment instead" >&2
                exit 2 ;;
        esac
    done
}

# positive_int WHO NAME VALUE: exits 2 (a usage error) unless VALUE is a positive integer.
positive_int() {
    [[ $3 =~ ^[1-9][0-9]*$ ]] || { echo "$1: $2 must be a positive integer, not '$3'" >&2; exit 2; }
}

# halfray_bin: the binary the scripts run: $HALFRAY, else this repository's
# target/release/halfray (built with `--features embree`) when it exists, else `halfray` on PATH.
halfray_bin() {
    local root
    root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
    if [ -n "${HALFRAY:-}" ]; then
        echo "$HALFRAY"
    elif [ -x "$root/target/release/halfray" ]; then
        echo "$root/target/release/halfray"
    else
        echo halfray
    fi
}
