#!/usr/bin/env bash
# A stand-in for a libFuzzer target binary, used by scripts/test-scripts.sh. FAKE_MODE: ok (runs,
# saves one input, prints a status line and `INFO: exiting`), crash (as ok, and saves a crash
# `crash-fake` under -artifact_prefix as fork mode does, exiting 1), killed (prints a status line,
# then SIGKILLs itself), err (fails at start-up). `-merge=1` copies the inputs and writes the control
# file; a single file argument is a replay that passes.
merge=0 control="" prefix="" dirs=()
for a in "$@"; do
    case $a in -merge=1) merge=1 ;; -merge_control_file=*) control=${a#*=} ;; -artifact_prefix=*) prefix=${a#*=} ;; -*) ;; *) dirs+=("$a") ;; esac
done
if [ "$merge" = 1 ]; then
    dst=${dirs[0]} files=()
    for d in "${dirs[@]:1}"; do for f in "$d"/*; do [ -f "$f" ] && files+=("$f"); done; done
    {
        echo "${#files[@]}"; echo 0
        [ "${#files[@]}" -eq 0 ] || printf '%s\n' "${files[@]}"
        i=0
        for f in "${files[@]}"; do echo "STARTED $i 1"; echo "FT $i 1"; cp "$f" "$dst/"; i=$((i + 1)); done
    } >"$control"
    echo "MERGE-OUTER: done"
    exit 0
fi
if [ "${#dirs[@]}" -eq 1 ] && [ -f "${dirs[0]}" ]; then echo "replay ok"; exit 0; fi
case ${FAKE_MODE:-ok} in
    ok) echo "#100: cov: 10 ft: 20 corp: 3 exec/s: 5 oom/timeout/crash: 0/0/0 time: 3s"
        echo x >"${dirs[0]}/new1"; echo "INFO: exiting: 0 time: 3s"; exit 0 ;;
    crash) echo "#100: cov: 10 ft: 20 corp: 3 exec/s: 5 oom/timeout/crash: 0/0/1 time: 3s"
        echo y >"${prefix}crash-fake"; echo "INFO: exiting: 1 time: 3s"; exit 1 ;;
    killed) echo "#50: cov: 5 ft: 9 corp: 2 exec/s: 5 oom/timeout/crash: 0/0/0 time: 1s"; kill -9 $$ ;;
    err) echo "ERROR: something broke at start"; exit 1 ;;
esac
