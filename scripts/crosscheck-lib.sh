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
