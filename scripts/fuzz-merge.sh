#!/usr/bin/env bash
# The merge after a fuzz run's tasks (scripts/fuzz-task.sh; on a cluster the job of
# docs/cluster/fuzz-merge.sbatch, docs/cluster/fuzz-merge-job.yaml; on one machine the end of
# scripts/fuzz-campaign.sh):
#
#   FUZZ_TARGETS="bvh ray_box" bash scripts/fuzz-merge.sh OUT_DIR
#
# For every target of FUZZ_TARGETS:
#   - merges the corpus its task grew (OUT_DIR/corpus/TARGET) and its seeds into
#     OUT_DIR/merged/TARGET/ with libFuzzer's `-merge=1`: the smallest set of those inputs with
#     their coverage (the seeds are never written);
#   - reports every finding, with its target: each file the task saved (OUT_DIR/artifacts/TARGET/:
#     crashes, timeouts, OOMs) and each input that crashed the merge (libFuzzer's merge survives
#     them; its control file tells which), replayed alone to show what it does. One line each:
#       finding: target TARGET: FILE (how it was found): REPLAYED OUTCOME
# and writes OUT_DIR/summary.md (per target, from the last fork-mode status line of the task's
# last attempt: fuzzing time, executions, coverage, features, corpus, OOMs/timeouts/crashes; then
# the inputs after the merge and the findings). Exit status: 0 no findings, 1 findings, 2 a
# target whose task left no log (named: it never ran, or OUT_DIR is not shared), whose task's
# last attempt did not end with exit 0 (OUT_DIR/logs/TARGET.status, written by
# scripts/fuzz-task.sh: killed, failed at start-up), whose binary is missing, or whose merge
# failed — each named; the other targets are still merged and the summary is whole.
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: FUZZ_TARGETS=\"T0 T1 ...\" $0 OUT_DIR" >&2; exit 2; }
out=$1
source "$(dirname "${BASH_SOURCE[0]}")/fuzz-paths.sh"
rm -rf "$out/merged"
mkdir -p "$out/merged"
# libFuzzer writes a copy of each input that crashes the merge or a replay (`crash-*`); those
# copies go here, not into the working directory, and are deleted.
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

# Inputs libFuzzer's merge started but never finished (a crash or timeout stopped it). The
# control file lists the N input files after its two count lines, then `STARTED i size` and,
# for an input that ran to the end, `FT i ...`.
crashed_in_merge() {
    awk 'NR == 1 { n = $1; next } NR == 2 { next } NR <= n + 2 { file[NR - 3] = $0; next }
         $1 == "STARTED" { started[$2] = 1 } $1 == "FT" { done[$2] = 1 }
         END { for (i in started) if (!(i in done)) print file[i] }' "$1"
}

# What the input does when replayed alone: the panic or libFuzzer's error line, or that it
# passes.
replay() {
    local bin=$1 f=$2 text
    if text=$(timeout 60 "$bin" -timeout=10 -rss_limit_mb=2048 -artifact_prefix="$scratch/" \
        "$f" 2>&1); then
        echo "passes when replayed alone"
        return
    fi
    # A Rust panic: `thread '...' panicked at FILE:LINE:COL:` then the message on the next line.
    grep -m 1 -A 1 'panicked at' <<<"$text" | tr '\n' ' ' | sed 's/^thread .* panicked at/panicked at/; s/ *$//' |
        grep . || grep -m 1 -E 'ERROR: libFuzzer|SUMMARY:' <<<"$text" || echo "fails when replayed (no message)"
}

findings=0
missing=0
# fail_target TARGET WHAT: a target that could not be judged; named, summary row, exit 2.
fail_target() {
    echo "fuzz-merge: target $1: $2" >&2
    echo "| \`$1\` | failed: $2 | | | | | | | |" >>"$summary"
    missing=1
}
summary=$out/summary.md
{
    echo "| target | seconds | executions | coverage (edges) | features | corpus | OOMs / timeouts / crashes | merged | findings |"
    echo "|---|---|---|---|---|---|---|---|---|"
} >"$summary"
for t in "${fuzz_targets[@]}"; do
    log=$out/logs/$t.log
    if [ ! -s "$log" ]; then
        echo "fuzz-merge: target $t is missing: its task left no log $log (it never ran, or OUT_DIR is not shared)" >&2
        echo "| \`$t\` | missing | | | | | | | |" >>"$summary"
        missing=1
        continue
    fi
    state=$(cat "$out/logs/$t.status" 2>/dev/null || echo "no status file")
    if [ "$state" != "exit 0" ]; then
        fail_target "$t" "its task's last attempt did not finish ($state; $out/logs/$t.status, log $log)"
        continue
    fi
    if ! bin=$(fuzz_bin "$t"); then
        fail_target "$t" "its binary is missing"
        continue
    fi
    inputs=("$out/corpus/$t")
    if s=$(fuzz_seeds "$t"); then inputs+=("$s"); fi
    mkdir -p "$out/merged/$t" "$out/corpus/$t" "$out/artifacts/$t"
    control=$out/merged/$t.control
    if ! "$bin" -merge=1 -merge_control_file="$control" -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="$scratch/" "$out/merged/$t" "${inputs[@]}" >"$out/logs/$t.merge.log" 2>&1; then
        tail -n 20 "$out/logs/$t.merge.log" >&2
        fail_target "$t" "merging its corpus failed (log: $out/logs/$t.merge.log)"
        continue
    fi
    # Each finding once, by content (the task may have saved an input that also crashed the
    # merge): the first file names it, the others are listed after it.
    declare -A first=() also=()
    order=()
    while IFS=$'\t' read -r how f; do
        [ -f "$f" ] || continue
        sum=$(sha1sum <"$f" | cut -c1-40)
        if [ -z "${first[$sum]:-}" ]; then
            first[$sum]="$f ($how"
            order+=("$sum")
        else
            also[$sum]+="; also $how: $f"
        fi
    done < <(
        crashed_in_merge "$control" | sort | sed 's/^/crashed the merge\t/'
        find "$out/artifacts/$t" -type f | sort | sed 's/^/saved by the fuzz task\t/'
    )
    for sum in "${order[@]}"; do
        f=${first[$sum]%% (*}
        echo "finding: target $t: ${first[$sum]}${also[$sum]:-}): $(replay "$bin" "$f")"
    done
    n=${#order[@]}
    unset first also
    findings=$((findings + n))
    # The last fork-mode status line of the task's last attempt (after its last
    # `fuzz-task TARGET: N s, ...` header line):
    # `#EXECS: cov: C ft: F corp: N exec/s: E oom/timeout/crash: a/b/c time: Ts ...`.
    last=$(awk -v h="fuzz-task $t: " 'index($0, h) == 1 && / s, .* fork\(s\), on / { line = "" }
        /^#[0-9]+: cov:/ { line = $0 } END { print line }' "$log")
    execs=$(sed -n 's/^#\([0-9]*\):.*/\1/p' <<<"$last")
    cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
    ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
    corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<<"$last")
    otc=$(sed -n 's/.* oom\/timeout\/crash: \([0-9/]*\).*/\1/p' <<<"$last")
    secs=$(sed -n 's/.* time: \([0-9]*\)s.*/\1/p' <<<"$last")
    merged=$(find "$out/merged/$t" -type f | wc -l)
    echo "| \`$t\` | ${secs:-?} | ${execs:-?} | ${cov:-?} | ${ft:-?} | ${corp:-?} | ${otc:-?} | $merged | $n |" >>"$summary"
    echo "fuzz-merge: $t: ${execs:-?} executions, coverage ${cov:-?}; corpus ${corp:-?} -> $merged merged; $n finding(s)" >&2
done
cat "$summary"
if [ "$missing" -ne 0 ]; then exit 2; fi
if [ "$findings" -ne 0 ]; then exit 1; fi
