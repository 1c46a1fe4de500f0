#!/usr/bin/env python3
"""Checks that merged cross-check reports equal the unsharded run, row for row.

    python3 scripts/crosscheck-same-run.py WHOLE.json MERGED.json:SHARDS [MERGED.json:SHARDS ...]

WHOLE.json is the `--json` report of an unsharded `halfray crosscheck` run; each MERGED.json is
`halfray crosscheck merge`'s report of the same run split into SHARDS shards. Every row (mesh x
ray set) must hold the same counts and the same recorded disagreements; only the timing fields
(`secs_*`, `mrays_*`) may differ. Prints one line and exits 0, or names the first difference and
exits 1. Used by scripts/crosscheck-verify-shards.sh and the CI cluster stage
(scripts/slurm-ci-crosscheck.sh).
"""
import json
import sys


def rows(path):
    with open(path) as f:
        report = json.load(f)
    return [{k: v for k, v in row.items() if not k.startswith(("secs_", "mrays_"))}
            for row in report["sets"]], report


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    whole, _ = rows(argv[1])
    for spec in argv[2:]:
        path, _, shards = spec.rpartition(":")
        merged, report = rows(path)
        if report.get("merged_shards") != int(shards):
            sys.exit(f"{path}: merged_shards is {report.get('merged_shards')}, expected {shards}")
        if len(merged) != len(whole):
            sys.exit(f"{path}: {len(merged)} rows, the unsharded run {len(whole)}")
        for a, b in zip(whole, merged):
            diff = [k for k in a if a[k] != b.get(k)]
            if diff:
                sys.exit(f"{path}: {a['mesh']} {a['name']}: {', '.join(diff)} differ")
    rays = sum(r["rays"] for r in whole)
    details = sum(len(r["disagreements"]) for r in whole)
    merged = ", ".join(f"{s.rpartition(':')[2]} shards" for s in argv[2:])
    print(f"merged ({merged}) = unsharded: {len(whole)} rows, {rays} rays, "
          f"{details} recorded disagreements")


if __name__ == "__main__":
    main(sys.argv)
