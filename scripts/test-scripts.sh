#!/usr/bin/env bash
# Tests of the cluster and campaign scripts' contracts (exit statuses, refusals, what they leave
# in OUT_DIR), with stand-ins for the binaries (scripts/tests/): no build, no Embree, no
# nightly toolchain; a few seconds. Called by test-all.sh (stage lint).
#
#   bash scripts/test-scripts.sh
#
# Covers crosscheck-same-run.py, crosscheck-verify-shards.sh (verdicts, failed runs, its
# OUT_DIR, the binary on PATH), crosscheck-merge.sh, crosscheck-local.sh and crosscheck-shard.sh
# (incomplete and refused shards, reused OUT_DIR, --max-mismatch, --threads, N, arguments as
# given), slurm-ci-crosscheck.sh and slurm-ci-fuzz.sh (their OUT_DIR only), fuzz-tools.sh
# (through fuzz-ci.sh: a failed or empty target list), fuzz-task.sh and fuzz-merge.sh (failed
# tasks, missing binaries), mutants.sh (a failed stage, stage one's verdicts kept, FILES that
# fail, the run folder of each FILES).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export HALFRAY=$root/scripts/tests/fake-halfray.py
failures=0
# expect RC DESCRIPTION COMMAND...: runs COMMAND (output to $tmp/last.out), checks its status.
expect() {
    local want=$1 what=$2 rc=0
    shift 2
    "$@" >"$tmp/last.out" 2>&1 || rc=$?
    if [ "$rc" = "$want" ]; then
        echo "ok: $what (exit $rc)"
    else
        echo "FAILED: $what: exit $rc, expected $want; output:"; sed 's/^/  /' "$tmp/last.out"
        failures=$((failures + 1))
    fi
}
check() { # check DESCRIPTION TEST...
    local what=$1
    shift
    if "$@"; then echo "ok: $what"; else echo "FAILED: $what"; failures=$((failures + 1)); fi
}
s=$root/scripts

# crosscheck-same-run.py on hand-made reports.
python3 - "$tmp" <<'PY'
import json, sys
d = sys.argv[1]
row = {"mesh": "a.obj", "name": "primary", "rays": 10, "ties": 0, "disagreements": [],
       "timed_rays": 10, "secs_halfray": 1.0}
whole = {"rays": 10, "meshes": 1, "failed": [], "sets": [row]}
def merged(**edit):
    r = dict(whole, merged_shards=2, sets=[dict(row, secs_halfray=2.0)])
    for k, v in edit.items():
        if k.startswith("row_"):
            r["sets"][0][k[4:]] = v
        else:
            r[k] = v
    return r
json.dump(whole, open(f"{d}/whole.json", "w"))
for name, r in {"same": merged(), "timed": merged(row_timed_rays=4), "ties": merged(row_ties=1),
                "failed": merged(failed=[{"path": "b.obj"}]), "meshes": merged(meshes=2),
                "extra": merged(row_extra=0)}.items():
    json.dump(r, open(f"{d}/m-{name}.json", "w"))
PY
sr() { python3 "$s/crosscheck-same-run.py" "$tmp/whole.json" "$tmp/m-$1.json:2"; }
expect 0 "same-run: equal reports" sr same
expect 0 "same-run: timed_rays may differ (sharding changes it)" sr timed
expect 1 "same-run: a count differs" sr ties
expect 1 "same-run: top-level failed differs" sr failed
expect 1 "same-run: top-level meshes differs" sr meshes
expect 1 "same-run: a row key on one side only" sr extra

# crosscheck-verify-shards.sh: the comparison's verdict is its exit status.
expect 0 "verify-shards: shards equal the unsharded run" bash "$s/crosscheck-verify-shards.sh" "$tmp/vs" a.obj b.obj --rays 10
expect 0 "verify-shards: its own OUT_DIR is reused" bash "$s/crosscheck-verify-shards.sh" "$tmp/vs" a.obj b.obj --rays 10
expect 1 "verify-shards: a difference fails" env FAKE_SKEW=1 bash "$s/crosscheck-verify-shards.sh" "$tmp/vs" a.obj b.obj --rays 10
expect 1 "verify-shards: an unsharded run with mismatches (exit 3) is a failed run" env FAKE_WHOLE_EXIT=3 bash "$s/crosscheck-verify-shards.sh" "$tmp/vs" a.obj --rays 10
check "verify-shards: ... named" grep -q 'the unsharded run failed (exit 3)' "$tmp/last.out"
expect 1 "verify-shards: an interrupted shard (local exit 2) is a failed run" env FAKE_STOP_SHARD=1 bash "$s/crosscheck-verify-shards.sh" "$tmp/vs" a.obj --rays 10
expect 1 "verify-shards: a missing binary (exit 127) is a failed run" env HALFRAY="$tmp/no-such-halfray" bash "$s/crosscheck-verify-shards.sh" "$tmp/vs" a.obj --rays 10
# Without HALFRAY, in a checkout with no target/release/halfray: `halfray` on PATH.
mkdir -p "$tmp/vrepo/scripts" "$tmp/hbin"
cp "$s"/crosscheck-*.sh "$s"/crosscheck-same-run.py "$s/out-dir.sh" "$tmp/vrepo/scripts/"
cp "$HALFRAY" "$tmp/hbin/halfray"
expect 0 "verify-shards: halfray on PATH" env -u HALFRAY PATH="$tmp/hbin:$PATH" bash "$tmp/vrepo/scripts/crosscheck-verify-shards.sh" "$tmp/vs-path" a.obj --rays 10
mkdir -p "$tmp/other" && touch "$tmp/other/keep"
expect 2 "verify-shards: refuses an OUT_DIR it did not write" bash "$s/crosscheck-verify-shards.sh" "$tmp/other" a.obj --rays 10
check "verify-shards: the refused OUT_DIR is untouched" test -e "$tmp/other/keep"
echo data >"$tmp/a-file"
expect 2 "verify-shards: refuses an OUT_DIR that is a file" bash "$s/crosscheck-verify-shards.sh" "$tmp/a-file" a.obj --rays 10
check "verify-shards: ... and leaves it" grep -qx data "$tmp/a-file"

# crosscheck-local.sh / crosscheck-merge.sh / crosscheck-shard.sh.
o=$tmp/local
expect 0 "local: a complete run" bash "$s/crosscheck-local.sh" 3 "$o" a.obj b.obj --rays 10
check "local: merged.json written" test -s "$o/merged.json"
cp -r "$o" "$tmp/stopped"
rm "$tmp/stopped"/part-*-of-3.json
expect 2 "merge: every shard stopped after the same mesh (no completion markers)" bash "$s/crosscheck-merge.sh" 3 "$tmp/stopped"
check "merge: the incomplete shards are named" grep -q 'shard 2/3 is missing: it did not complete' "$tmp/last.out"
check "merge: no stale merged.json after a refused merge" test ! -e "$tmp/stopped/merged.json"
expect 2 "local: an interrupted shard stops the run before the merge" env FAKE_STOP_SHARD=1 bash "$s/crosscheck-local.sh" 3 "$o" a.obj b.obj --rays 10
check "local: the interrupted shard is named" grep -q 'shard 1/3 did not complete' "$tmp/last.out"
check "local: no merged.json after an interrupted run" test ! -e "$o/merged.json"
expect 0 "local: the same command again resumes and merges" bash "$s/crosscheck-local.sh" 3 "$o" a.obj b.obj --rays 10
cp "$o/merged.json" "$tmp/merged.before"
expect 2 "local: an OUT_DIR of a run with other meshes is refused" bash "$s/crosscheck-local.sh" 3 "$o" a.obj --rays 10
check "local: the refused run left the old reports as they were" cmp -s "$o/merged.json" "$tmp/merged.before"
check "local: ... and the shards' reports" test -s "$o/part-0-of-3.json"
expect 2 "local: an OUT_DIR of a run with another shard count is refused" bash "$s/crosscheck-local.sh" 2 "$o" a.obj b.obj --rays 10
expect 0 "local: --max-mismatch reaches the merge" bash "$s/crosscheck-local.sh" 2 "$tmp/mm" a.obj --rays 10 --max-mismatch 7
check "local: the merge ran with --max-mismatch 7" \
    python3 -c 'import json,sys; sys.exit(json.load(open(sys.argv[1]))["merge_args"]["max_mismatch"] != "7")' "$tmp/mm/merged.json"
expect 0 "local: a mesh named with braces" bash "$s/crosscheck-local.sh" 2 "$tmp/braces" 'cube{}.obj' --rays 10
check "local: ... reaches every shard as named" grep -q '"mesh": "cube{}.obj"' "$tmp/braces/merged.json"
check "local: ... in every shard's log" grep -q 'cube{}.obj' "$tmp/braces/part-1-of-2.jsonl"
expect 2 "local: --threads among the arguments is a usage error" bash "$s/crosscheck-local.sh" 2 "$tmp/threads" a.obj --threads 2
check "local: ... naming THREADS" grep -q 'THREADS=N' "$tmp/last.out"
check "local: ... before any shard ran" test ! -e "$tmp/threads"
expect 2 "verify-shards: --threads among the arguments is a usage error" bash "$s/crosscheck-verify-shards.sh" "$tmp/vs-threads" a.obj --threads=2
check "verify-shards: ... before any run" test ! -e "$tmp/vs-threads"
expect 2 "local: N not a number is a usage error" bash "$s/crosscheck-local.sh" abc "$tmp/n-abc" a.obj
check "local: ... naming N" grep -q "N must be a positive integer, not 'abc'" "$tmp/last.out"
expect 2 "local: N = 0 is a usage error" bash "$s/crosscheck-local.sh" 0 "$tmp/n-abc" a.obj
expect 2 "merge: N not a number is a usage error" bash "$s/crosscheck-merge.sh" abc "$o"
rm "$o/part-0-of-3.args"
expect 2 "shard: a results log with no recorded arguments is refused" bash "$s/crosscheck-shard.sh" 0 3 "$o" a.obj b.obj --rays 10
# A scheduler's shards (no --check first) refused in a copy of a finished run, then the merge
# that follows them with afterany: it must not merge the old run's reports as this run's.
r=$tmp/rerun
expect 0 "local: a finished run to run again" bash "$s/crosscheck-local.sh" 2 "$tmp/run-a" a.obj b.obj --rays 10
cp -r "$tmp/run-a" "$r"
for k in 0 1; do
    expect 2 "shard: $k/2 with other rays is refused" bash "$s/crosscheck-shard.sh" "$k" 2 "$r" a.obj b.obj --rays 20
done
check "shard: ... leaving the old run's report as it was" cmp -s "$r/part-0-of-2.json" "$tmp/run-a/part-0-of-2.json"
expect 2 "merge: shards refused at their last start are not merged" bash "$s/crosscheck-merge.sh" 2 "$r"
check "merge: ... naming them" grep -q 'shard 1/2 was refused' "$tmp/last.out"
check "merge: ... with the reason" grep -q 'belongs to a run with other arguments' "$tmp/last.out"
check "merge: ... and no merged.json" test ! -e "$r/merged.json"
expect 0 "shard: 0/2 with the old run's arguments starts" bash "$s/crosscheck-shard.sh" 0 2 "$r" a.obj b.obj --rays 10
expect 2 "merge: shard 1/2 still refused" bash "$s/crosscheck-merge.sh" 2 "$r"
check "merge: ... only shard 1/2 named" test "$(grep -c 'was refused' "$tmp/last.out")" = 1
expect 0 "shard: 1/2 with the old run's arguments starts" bash "$s/crosscheck-shard.sh" 1 2 "$r" a.obj b.obj --rays 10
expect 0 "merge: both shards started again: merged" bash "$s/crosscheck-merge.sh" 2 "$r"

# fuzz-tools.sh (through fuzz-ci.sh): the target list's status counts.
mkdir -p "$tmp/cargo-bin"
cp "$s/tests/fake-cargo.sh" "$tmp/cargo-bin/cargo"
expect 1 "fuzz-ci: a failed \`cargo fuzz list\` fails" env PATH="$tmp/cargo-bin:$PATH" FAKE_LIST=fail bash "$s/fuzz-ci.sh"
expect 1 "fuzz-ci: no fuzz target fails" env PATH="$tmp/cargo-bin:$PATH" FAKE_LIST=empty bash "$s/fuzz-ci.sh"

# slurm-ci-*.sh empty their OUT_DIR: only one holding their own files (a stand-in sbatch fails
# the first submission, after the emptying).
mkdir -p "$tmp/user-data" "$tmp/slurm-bin"
printf '#!/bin/sh\necho "fake sbatch: no cluster" >&2; exit 1\n' >"$tmp/slurm-bin/sbatch"
chmod +x "$tmp/slurm-bin/sbatch"
for script in slurm-ci-crosscheck slurm-ci-fuzz; do
    args=(a.obj); [ "$script" = slurm-ci-crosscheck ] || args=()
    echo data >"$tmp/user-data/keep"
    expect 2 "$script: refuses an OUT_DIR holding other files" \
        env PATH="$tmp/slurm-bin:$tmp/cargo-bin:$PATH" bash "$s/$script.sh" "$tmp/user-data" "${args[@]}"
    check "$script: ... and leaves them" grep -qx data "$tmp/user-data/keep"
done
mkdir -p "$tmp/sc-out/requeue" && touch "$tmp/sc-out/whole.json" "$tmp/sc-out/requeue/part-0-of-3.jsonl"
expect 1 "slurm-ci-crosscheck: takes an OUT_DIR of its own (up to the failed sbatch)" \
    env PATH="$tmp/slurm-bin:$PATH" bash "$s/slurm-ci-crosscheck.sh" "$tmp/sc-out" a.obj
check "slurm-ci-crosscheck: ... and empties it" test ! -e "$tmp/sc-out/requeue/part-0-of-3.jsonl"

# fuzz-task.sh / fuzz-merge.sh with stand-in targets `a` and `b`.
mkdir -p "$tmp/fbin" "$tmp/seeds/a" "$tmp/seeds/b"
cp "$s/tests/fake-fuzz-target.sh" "$tmp/fbin/a"
cp "$s/tests/fake-fuzz-target.sh" "$tmp/fbin/b"
export FUZZ_TARGETS="a b" FUZZ_BIN=$tmp/fbin FUZZ_SEEDS=$tmp/seeds FUZZ_SECONDS=1
f=$tmp/fuzz
expect 0 "fuzz-task: target a runs its time" bash "$s/fuzz-task.sh" 0 "$f"
expect 0 "fuzz-task: target b runs its time" bash "$s/fuzz-task.sh" 1 "$f"
expect 0 "fuzz-merge: two clean tasks" bash "$s/fuzz-merge.sh" "$f"
expect 137 "fuzz-task: a killed fuzzer is the task's failure" env FAKE_MODE=killed bash "$s/fuzz-task.sh" 0 "$f"
expect 2 "fuzz-merge: a task whose last attempt was killed fails the merge" bash "$s/fuzz-merge.sh" "$f"
check "fuzz-merge: ... naming it" grep -q "target a: its task's last attempt did not finish (exit 137" "$tmp/last.out"
# shellcheck disable=SC2016 # a literal backquote
check "fuzz-merge: ... and still merges the other target" grep -q '^| `b` | 3 | 100 |' "$f/summary.md"
expect 1 "fuzz-task: a start-up error is the task's failure" env FAKE_MODE=err bash "$s/fuzz-task.sh" 0 "$f"
expect 2 "fuzz-merge: a task that failed at start-up fails the merge" bash "$s/fuzz-merge.sh" "$f"
expect 0 "fuzz-task: target a again" bash "$s/fuzz-task.sh" 0 "$f"
expect 0 "fuzz-merge: clean again" bash "$s/fuzz-merge.sh" "$f"
rm "$tmp/fbin/a"
expect 2 "fuzz-merge: a missing binary fails the merge (exit 2, not 1: no finding)" bash "$s/fuzz-merge.sh" "$f"
check "fuzz-merge: ... naming it, with the whole summary" \
    grep -q 'target a: its binary is missing' "$tmp/last.out"
# shellcheck disable=SC2016 # a literal backquote
check "fuzz-merge: ... the summary has every target" grep -q '^| `b` |' "$f/summary.md"
unset FUZZ_TARGETS FUZZ_BIN FUZZ_SEEDS FUZZ_SECONDS

# mutants.sh in a copy of its layout, with a stand-in cargo-mutants.
mr=$tmp/mrepo
mkdir -p "$mr/scripts" "$mr/core/src" "$tmp/mutants-bin"
cp "$s/mutants.sh" "$mr/scripts/"
: >"$mr/core/src/aabb.rs"
cp "$s/tests/fake-cargo-mutants.sh" "$tmp/mutants-bin/cargo"
mutants() { env PATH="$tmp/mutants-bin:$PATH" FILES=core/src/aabb.rs TEST_PACKAGES=halfray-core,halfray-tests "$@" bash "$mr/scripts/mutants.sh"; }
# The last run's folder, as it names it.
sample_dir() { echo "$mr/$(sed -n 's|^missed: \(.*\)/missed.txt;.*|\1|p' "$tmp/last.out")"; }
missed() { grep -c . "$(sample_dir)/missed.txt" || true; }
expect 1 "mutants: a failed stage-two baseline fails the run" mutants FAKE_WIDE=fail
check "mutants: ... naming the stage" grep -q 'stage two failed: cargo-mutants exit 4' "$tmp/last.out"
expect 0 "mutants: stage two judges every survivor" mutants FAKE_WIDE=all
check "mutants: ... f4 missed" test "$(missed)" = 1
expect 0 "mutants: stage two judges one survivor of two" mutants FAKE_WIDE=partial
check "mutants: ... the other keeps stage one's verdict (missed)" \
    grep -qx 'core/src/aabb.rs:4:5: replace f4 -> bool with true' "$(sample_dir)/missed.txt"
: >"$mr/core/src/other.rs"
expect 0 "mutants: a run of other FILES" mutants FILES=core/src/other.rs
other=$(sample_dir)
expect 0 "mutants: ... and of the first FILES again" mutants
check "mutants: ... write to two folders" test "$other" != "$(sample_dir)"
check "mutants: ... the first keeps its own file list" grep -q '^core/src/other.rs ' "$other/files.txt"
expect 1 "mutants: a FILES entry that does not exist fails" mutants FILES="core/src/aabb.rs core/src/gone.rs"
check "mutants: ... naming it" grep -q 'FILES names core/src/gone.rs' "$tmp/last.out"
expect 1 "mutants: a failed listing fails" mutants FAKE_LIST=fail
check "mutants: ... naming the file" grep -q 'listing the mutants of core/src/aabb.rs failed' "$tmp/last.out"
expect 0 "mutants: a shard past a file's mutants" mutants SHARD=1
check "mutants: ... is skipped with a line" grep -q 'core/src/aabb.rs: 4 mutant(s) in 1 shard(s); shard 1 is past them' "$tmp/last.out"
expect 1 "mutants: a second run of a sample under way is refused" \
    flock "$other/.lock" env PATH="$tmp/mutants-bin:$PATH" FILES=core/src/other.rs bash "$mr/scripts/mutants.sh"
source "$s/tests/fuzz-scripts.sh"

echo
if [ "$failures" -ne 0 ]; then echo "test-scripts: $failures check(s) failed"; exit 1; fi
echo "test-scripts: every check passed"
