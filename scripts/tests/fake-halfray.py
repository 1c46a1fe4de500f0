#!/usr/bin/env python3
"""A stand-in for `halfray crosscheck` used by scripts/test-scripts.sh: no Embree, no meshes read.

    crosscheck MESH... [--rays R] [--shard K/N --jsonl LOG --resume] [--json REPORT] [...]
    crosscheck merge PART... --json REPORT [--max-mismatch M]

Each mesh gets one row (`primary`) whose `rays` are the shard's share of R (ray i belongs to
shard i mod N); a merge sums the rows of the parts' results logs and records its own arguments
in the report (`merge_args`). FAKE_STOP_SHARD=K: that shard writes its log, no report, exits
130 (an interrupted task). FAKE_SKEW=1: the unsharded report gets one extra tie. `--threads`
given twice is refused (exit 2), as the binary's argument parser does. FAKE_WHOLE_EXIT=S: an
unsharded run writes its report and exits S (3: mismatches, 1: a mesh not checked).
"""
import json
import os
import sys


def row(mesh, rays, timed):
    return {"mesh": os.path.basename(mesh), "name": "primary", "rays": rays, "ties": 0,
            "disagreements": [], "timed_rays": timed, "secs_halfray": 0.1}


def report(rows, meshes, rays, **extra):
    r = {"rays": rays, "meshes": meshes, "failed": [], "sets": rows}
    r.update(extra)
    return r


def take(args, name, default=None):
    if name in args:
        i = args.index(name)
        value = args[i + 1]
        del args[i:i + 2]
        return value
    return default


def main(argv):
    args = argv[1:]
    assert args[0] == "crosscheck", args
    args = args[1:]
    if args[0] == "merge":
        out = take(args, "--json")
        max_mismatch = take(args, "--max-mismatch")
        parts = args[1:]
        rows, meshes, rays = {}, [], None
        for p in parts:
            with open(p) as f:
                for line in f:
                    entry = json.loads(line)
                    rays = entry["rays"]
                    if entry["path"] not in meshes:
                        meshes.append(entry["path"])
                    s = entry["sets"][0]
                    have = rows.setdefault(s["mesh"], dict(s, rays=0, timed_rays=0))
                    have["rays"] += s["rays"]
                    have["timed_rays"] += s["timed_rays"]
        with open(out, "w") as f:
            json.dump(report(list(rows.values()), len(meshes), rays, merged_shards=len(parts),
                             merge_args={"max_mismatch": max_mismatch}), f)
        return 0
    rays = int(take(args, "--rays", "100"))
    shard = take(args, "--shard", "0/1")
    log = take(args, "--jsonl")
    out = take(args, "--json")
    if sum(a == "--threads" or a.startswith("--threads=") for a in args) > 1:
        print("error: the argument '--threads <THREADS>' cannot be used multiple times",
              file=sys.stderr)
        return 2
    take(args, "--threads")
    take(args, "--max-mismatch")
    meshes = [a for a in args if not a.startswith("--")]
    k, n = map(int, shard.split("/"))
    share = len(range(k, rays, n))
    done = set()
    if log and os.path.exists(log):
        with open(log) as f:
            done = {json.loads(line)["path"] for line in f}
    rows = []
    for m in meshes:
        r = row(m, share, min(share, 10))
        if log and m not in done:
            with open(log, "a") as f:
                f.write(json.dumps({"path": m, "rays": rays, "sets": [r]}) + "\n")
        rows.append(r)
    if os.environ.get("FAKE_STOP_SHARD") == str(k) and n > 1:
        return 130
    if os.environ.get("FAKE_SKEW") == "1" and n == 1 and rows:
        rows[0]["ties"] += 1
    if out:
        with open(out, "w") as f:
            json.dump(report(rows, len(meshes), rays, shard={"index": k, "count": n}), f)
    return int(os.environ.get("FAKE_WHOLE_EXIT", "0")) if n == 1 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
