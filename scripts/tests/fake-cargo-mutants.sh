#!/usr/bin/env bash
# A stand-in for `cargo mutants` (installed as `cargo` on PATH by scripts/test-scripts.sh) for
# scripts/mutants.sh: four mutants in core/src/aabb.rs; stage one (--test-package halfray-core)
# catches f1 and f2 and misses f3 and f4 (exit 2). Stage two, by FAKE_WIDE: `fail` (the baseline
# fails, exit 4), `partial` (catches f3 and judges nothing else, exit 0), `all` (catches f3,
# misses f4, exit 2). FAKE_LIST=fail: `--list` fails (exit 1).
[ "${1:-}" = mutants ] || { echo "fake cargo: unexpected: $*" >&2; exit 1; }
shift
case " $* " in *" --version "*) echo "cargo-mutants 27.0.0"; exit 0 ;; esac
mutant() { echo "core/src/aabb.rs:$1:5: replace f$1 -> bool with true"; }
case " $* " in *" --list "*)
    [ "${FAKE_LIST:-}" != fail ] || { echo "error: failed to parse the package" >&2; exit 1; }
    for i in 1 2 3 4; do mutant "$i"; done; exit 0 ;;
esac
o="" pk="" prev=""
for a in "$@"; do
    [ "$prev" = -o ] && o=$a
    [ "$prev" = --test-package ] && pk=$a
    prev=$a
done
m=$o/mutants.out
mkdir -p "$m"
: >"$m/caught.txt"; : >"$m/missed.txt"; : >"$m/timeout.txt"; : >"$m/unviable.txt"
if [ "$pk" = halfray-core ]; then
    { mutant 1; mutant 2; } >"$m/caught.txt"
    { mutant 3; mutant 4; } >"$m/missed.txt"
    exit 2
fi
case ${FAKE_WIDE:-all} in
    fail) echo "FAILED: the tests fail in an unmutated tree" >&2; exit 4 ;;
    partial) mutant 3 >"$m/caught.txt"; exit 0 ;;
    all) mutant 3 >"$m/caught.txt"; mutant 4 >"$m/missed.txt"; exit 2 ;;
esac
