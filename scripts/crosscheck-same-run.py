#!/usr/bin/env python3
"""Checks that merged cross-check reports equal the unsharded run, row for row.

    python3 scripts/crosscheck-same-run.py WHOLE.json MERGED.json:SHARDS [MERGED.json:SHARDS ...]

WHOLE.json is the `--json` report of an unsharded `halfray crosscheck` run; each MERGED.json is
`halfray crosscheck merge`'s report of the same run split into SHARDS shards. The top-level
`failed`, `meshes` and `rays` must be equal, and every row (mesh x ray set) must hold the same
keys, the same counts and the same recorded disagreements; only the timing fields (`secs_*`,
`mrays_*`, and `timed_rays`, which sharding changes by design: each shard times its own
`--timing-rays` per set, summed by the merge) may differ. Prints one line and exits 0, or names
the first difference and exits 1. Used by scripts/crosscheck-verify-shards.sh and the CI cluster
stage (scripts/slurm-ci-crosscheck.sh).
"""
import json
import sys

TIMING = ("secs_", "mrays_")
TIMING_KEYS = ("timed_rays",)
TOP_LEVEL = ("failed", "meshes", "rays")


def fail(message):
    print(message, file=sys.stderr)
    sys.exit(1)


def rows(path):
    with open(path) as f:
        report = json.load(f)
    return [{k: v for k, v in row.items() if not k.startswith(TIMING) and k not in TIMING_KEYS}
            for row in report["sets"]], report


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    whole, whole_report = rows(argv[1])
    for spec in argv[2:]:
        path, _, shards = spec.rpartition(":")
        merged, report = rows(path)
        if report.get("merged_shards") != int(shards):
            fail(f"{path}: merged_shards is {report.get('merged_shards')}, expected {shards}")
        for k in TOP_LEVEL:
            if k not in whole_report or k not in report:
                fail(f"{path}: top-level `{k}` missing from "
                     f"{'the unsharded run' if k not in whole_report else 'the merged report'}")
            if whole_report[k] != report[k]:
                fail(f"{path}: top-level `{k}` differs: {json.dumps(report[k])[:200]}, "
                     f"the unsharded run {json.dumps(whole_report[k])[:200]}")
        if len(merged) != len(whole):
            fail(f"{path}: {len(merged)} rows, the unsharded run {len(whole)}")
        for a, b in zip(whole, merged):
            where = f"{path}: {a.get('mesh')} {a.get('name')}"
            only = sorted(set(a) ^ set(b))
            if only:
                fail(f"{where}: keys on one side only: "
                     + ", ".join(f"{k} ({'unsharded' if k in a else 'merged'})" for k in only))
            diff = [k for k in a if a[k] != b[k]]
            if diff:
                fail(f"{where}: {', '.join(diff)} differ")
    rays = sum(r["rays"] for r in whole)
    details = sum(len(r["disagreements"]) for r in whole)
    merged = ", ".join(f"{s.rpartition(':')[2]} shards" for s in argv[2:])
    print(f"merged ({merged}) = unsharded: {len(whole)} rows, {rays} rays, "
          f"{details} recorded disagreements")


if __name__ == "__main__":
    main(sys.argv)
