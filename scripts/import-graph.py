#!/usr/bin/env python3
"""Module import graph of halfray-core (core/src) and the halfray library (frontend/src).

Usage: scripts/import-graph.py [--self-test] [--edges] [--at-most=LOOPS,UPWARD] [CRATE_SRC ...]
(default crates: core/src frontend/src, relative to the repository root).

Exits 1 if any import loop or upward import is found, 0 otherwise. --at-most=L,U is the CI
ratchet while issue 38's moves are in flight: every finding is still printed, and the exit is
1 only if there are more than L loops or U upward imports (lower the numbers as they go;
the goal is --at-most=0,0, i.e. no flag). --self-test checks the checker on planted fixture
trees and exits 0 only if it finds exactly what was planted. --edges prints the whole graph.

Modules. One module per file: `lib.rs` is the crate root, `a/mod.rs` and `a.rs` are `a`,
`a/b.rs` is `a::b`. Inline `mod x { ... }` blocks count as part of their file (their own
`super::` is resolved correctly). `main.rs` is a separate binary crate and is skipped.

Edges. Module A depends on module B when A names a path into B: in a `use` tree
(`crate::`, `super::`, `self::`, or a child module's name) or in code (`crate::a::b::f()`,
`super::x::Y`). A path resolves to the deepest module it names; when its next segment is an
item the module re-exports (`pub use b::Y;` in `a/mod.rs`), it follows the re-export to `a::b`,
so `use super::Y` in `a/c.rs` is an edge to the sibling `a::b`, not to the folder.
Paths into other crates (`halfray_core::`, `std::`) are not edges.

Import loop: a strongly connected component of more than one module, inside a folder or
across folders. A folder's `mod.rs` naming its own children (declaring, re-exporting,
calling them) is containment, not a dependency, and is left out; every other edge counts,
including a child using an item the folder's `mod.rs` itself defines (the folder's public
interface): that edge is fine on its own and only a loop through it is reported.

Upward import (the rule of issue 38, "siblings, not floors"): the modules of one folder are
siblings and none is a floor below another. The checked rule is a list of forbidden
(importer, imported) module prefixes, FORBIDDEN below: `grid`, `kdtree`, `volume` and
`collide` must not import from `bvh` (shared mesh and query types live in `mesh`/`query`).
"""

import os
import re
import sys
import tempfile

# (crate folder name, importer prefix, imported prefix): an edge from a module under the
# importer prefix to one under the imported prefix is an upward import.
FORBIDDEN = [
    ("core", ("grid",), ("bvh",)),
    ("core", ("kdtree",), ("bvh",)),
    ("core", ("volume",), ("bvh",)),
    ("core", ("collide",), ("bvh",)),
]

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def strip(text):
    """Source with comments, string and char literals blanked (offsets kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 8]) and (i == 0 or not text[i - 1].isalnum()):
            m = re.match(r'r(#*)"', text[i:])
            end = text.find('"' + m.group(1), i + len(m.group(0)))
            j = n if end < 0 else end + 1 + len(m.group(1))
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "'":
            m = re.match(r"'(\\.[^']*|[^\\'])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def module_of(rel):
    """Module path (tuple) of a file path relative to the crate's src."""
    parts = rel[:-3].split(os.sep)
    if parts[-1] == "mod":
        parts = parts[:-1]
    if parts in (["lib"],):
        return ()
    return tuple(parts)


def expand_use(tree):
    """Flat paths (lists of segments) of a use tree such as `a::{b, c::{d as e}, self}`."""
    tree = re.sub(r"\s+as\s+" + IDENT, "", tree)
    tree = re.sub(r"\s+", "", tree)
    paths = []

    def walk(prefix, s):
        # split s at top-level commas
        depth, start, items = 0, 0, []
        for k, ch in enumerate(s):
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            elif ch == "," and depth == 0:
                items.append(s[start:k])
                start = k + 1
        items.append(s[start:])
        for item in items:
            if not item:
                continue
            if "{" in item:
                head, _, rest = item.partition("{")
                head_segs = [x for x in head.split("::") if x]
                walk(prefix + head_segs, rest[: rest.rfind("}")])
            else:
                segs = [x for x in item.split("::") if x]
                if segs and segs[-1] == "self":
                    segs = segs[:-1]
                paths.append(prefix + segs)

    walk([], tree)
    return paths


USE_RE = re.compile(r"\b(pub(?:\([^)]*\))?\s+)?use\s+([^;]*);")
CODE_PATH_RE = re.compile(r"(?<![A-Za-z0-9_:])((?:crate|super|self)(?:\s*::\s*" + IDENT + r")+)")
MOD_OPEN_RE = re.compile(r"\bmod\s+(" + IDENT + r")\s*\{")
TEST_MOD_RE = re.compile(
    r"#\[cfg\(test\)\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?mod\s+(" + IDENT + r")\s*([;{])"
)


def inline_mods(clean):
    """List of (start, end, name) spans of inline `mod name { ... }` blocks."""
    spans = []
    for m in MOD_OPEN_RE.finditer(clean):
        depth, j = 1, m.end()
        while j < len(clean) and depth:
            if clean[j] == "{":
                depth += 1
            elif clean[j] == "}":
                depth -= 1
            j += 1
        spans.append((m.start(), j, m.group(1)))
    return spans


class Crate:
    def __init__(self, name, src):
        self.name = name
        self.src = src
        self.files = {}  # module -> cleaned text
        for root, _dirs, files in os.walk(src):
            for f in sorted(files):
                if not f.endswith(".rs"):
                    continue
                rel = os.path.relpath(os.path.join(root, f), src)
                if rel == "main.rs":
                    continue
                with open(os.path.join(root, f), encoding="utf-8") as fh:
                    self.files[module_of(rel)] = strip(fh.read())
        # test-only code (`#[cfg(test)] mod x;` files and `#[cfg(test)] mod x { }` blocks)
        # is not part of the layering: a test may use anything.
        test_files = set()
        self.test_spans = {}
        for mod, clean in self.files.items():
            spans = []
            for m in TEST_MOD_RE.finditer(clean):
                if m.group(2) == ";":
                    test_files.add(mod + (m.group(1),))
                else:
                    spans.append(m.start())
            self.test_spans[mod] = spans
        for mod in list(self.files):
            if any(mod[: len(t)] == t for t in test_files):
                del self.files[mod]
        self.modules = set(self.files)
        # re-exports: module -> {name: target path (absolute segments)}
        self.reexports = {}
        self.refs = {}  # module -> list of absolute paths
        for mod, clean in self.files.items():
            spans = inline_mods(clean)
            tests = [(s, e) for s, e, _n in spans if self.is_test_open(clean, s)]
            refs, rex = [], {}
            for m in USE_RE.finditer(clean):
                if any(s <= m.start() < e for s, e in tests):
                    continue
                scope = self.scope(mod, spans, m.start())
                for segs in expand_use(m.group(2)):
                    ab = self.absolute(scope, segs, in_use=True)
                    if ab is None:
                        continue
                    refs.append(ab)
                    if m.group(1) and scope == mod and segs:
                        last = segs[-1]
                        if last != "*":
                            rex[last] = ab
            for m in CODE_PATH_RE.finditer(clean):
                if any(s <= m.start() < e for s, e in tests):
                    continue
                segs = [x.strip() for x in m.group(1).split("::")]
                scope = self.scope(mod, spans, m.start())
                ab = self.absolute(scope, segs, in_use=False)
                if ab is not None:
                    refs.append(ab)
            self.refs[mod] = refs
            self.reexports[mod] = rex

    @staticmethod
    def is_test_open(clean, start):
        """Whether the inline `mod` opening at `start` carries `#[cfg(test)]`."""
        before = clean[max(0, start - 200) : start]
        m = re.search(r"#\[cfg\(test\)\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?$", before)
        return m is not None

    @staticmethod
    def scope(mod, spans, pos):
        inner = [(s, name) for s, e, name in spans if s <= pos < e]
        return mod + tuple(name for _s, name in sorted(inner))

    def absolute(self, scope, segs, in_use):
        """Absolute segment list of a path seen in `scope`, or None if it leaves the crate."""
        if not segs:
            return None
        cur = list(scope)
        head = segs[0]
        if head == "crate":
            return segs[1:]
        if head in ("super", "self"):
            k = 0
            while k < len(segs) and segs[k] in ("super", "self"):
                if segs[k] == "super":
                    if not cur:
                        return None
                    cur.pop()
                k += 1
            return cur + segs[k:]
        if in_use:
            # 2018 uniform paths: a child module of the scope's file module
            child = self.file_module(tuple(cur)) + (head,)
            if child in self.modules:
                return list(child) + segs[1:]
        return None

    def file_module(self, path):
        path = tuple(path)
        while path not in self.modules:
            path = path[:-1]
        return path

    def resolve(self, segs, depth=0):
        """File module a path points into, following re-exports."""
        segs = [s for s in segs if s != "*"]
        mod = ()
        k = 0
        while k < len(segs) and mod + (segs[k],) in self.modules:
            mod = mod + (segs[k],)
            k += 1
        if k < len(segs) and depth < 16:
            target = self.reexports.get(mod, {}).get(segs[k])
            if target is not None and target[: len(mod)] != list(mod) + [segs[k]]:
                return self.resolve(target + segs[k + 1:], depth + 1)
            if target is not None:
                return self.resolve(target, depth + 1) if target != segs[: k + 1] else mod
        return mod

    def edges(self):
        out = {m: set() for m in self.modules}
        for mod, refs in self.refs.items():
            for segs in refs:
                tgt = self.resolve(segs)
                if tgt == mod:
                    continue
                # containment: a folder naming its own descendants
                if tgt[: len(mod)] == mod:
                    continue
                out[mod].add(tgt)
        return out


def sccs(graph):
    """Tarjan's strongly connected components (iterative)."""
    index, low, on, stack, comps = {}, {}, set(), [], []
    counter = [0]
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            node, it = work[-1]
            advanced = False
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter[0]
                    counter[0] += 1
                    stack.append(nxt)
                    on.add(nxt)
                    work.append((nxt, iter(sorted(graph.get(nxt, ())))))
                    advanced = True
                    break
                if nxt in on:
                    low[node] = min(low[node], index[nxt])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                comps.append(sorted(comp))
    return comps


def name(crate, mod):
    return crate + ":" + ("::".join(mod) if mod else "crate")


def check(crate_dirs, show_edges=False, out=sys.stdout):
    """Print loops and upward imports; return (loops, upward) lists."""
    loops, upward = [], []
    for src in crate_dirs:
        cname = os.path.basename(os.path.dirname(os.path.abspath(src)))
        crate = Crate(cname, src)
        graph = crate.edges()
        if show_edges:
            for m in sorted(graph):
                for t in sorted(graph[m]):
                    print("edge %s -> %s" % (name(cname, m), name(cname, t)), file=out)
        for comp in sccs(graph):
            if len(comp) > 1:
                members = set(comp)
                arrows = [
                    "%s -> %s" % ("::".join(a) or "crate", "::".join(b) or "crate")
                    for a in comp
                    for b in sorted(graph[a])
                    if b in members
                ]
                loops.append((cname, comp))
                print(
                    "LOOP %s: %s\n    %s"
                    % (cname, ", ".join("::".join(m) or "crate" for m in comp), "\n    ".join(arrows)),
                    file=out,
                )
        for fc, imp, dep in FORBIDDEN:
            if fc != cname:
                continue
            for m in sorted(graph):
                if m[: len(imp)] != imp:
                    continue
                for t in sorted(graph[m]):
                    if t[: len(dep)] == dep:
                        upward.append((cname, m, t))
                        print("UPWARD %s: %s -> %s" % (cname, "::".join(m), "::".join(t)), file=out)
    print("%d import loop(s), %d upward import(s)" % (len(loops), len(upward)), file=out)
    return loops, upward


def write(root, files):
    for rel, body in files.items():
        path = os.path.join(root, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(body)


def self_test():
    """Planted trees: a loop through a re-export, a clean tree, an upward import."""
    import io

    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        looped = os.path.join(tmp, "core", "src")
        write(
            looped,
            {
                "lib.rs": "pub mod grid;\npub mod bvh;\npub mod mesh;\n",
                "mesh.rs": "pub struct Mesh; // crate::grid::Plan in a comment is no edge\n",
                # grid/mod.rs re-exports; plan uses overlap through `super::Overlap`.
                "grid/mod.rs": "mod overlap;\nmod plan;\npub use overlap::Overlap;\npub use plan::Plan;\n",
                "grid/plan.rs": "use super::Overlap;\npub struct Plan;\n",
                "grid/overlap.rs": (
                    "pub struct Overlap;\n"
                    "fn f() { let _ = crate::grid::plan::Plan; let s = \"super::nothing\"; }\n"
                    "#[cfg(test)]\nmod tests {\n    use super::Overlap;\n}\n"
                ),
                "bvh/mod.rs": "pub mod build;\npub struct Bvh;\n",
                "bvh/build.rs": "use crate::mesh::Mesh;\n",
            },
        )
        buf = io.StringIO()
        loops, upward = check([looped], out=buf)
        got = [(c, comp) for c, comp in loops]
        want = [("core", [("grid", "overlap"), ("grid", "plan")])]
        if got != want or upward:
            failures.append("planted two-file loop: got %r %r\n%s" % (got, upward, buf.getvalue()))

        # Fix the loop by moving the shared piece: no loop, and a grid -> bvh import is upward.
        write(
            looped,
            {
                "grid/overlap.rs": (
                    "pub struct Overlap;\nuse crate::bvh::Bvh;\n"
                    "#[cfg(test)]\nmod tests {\n    use crate::grid::plan::Plan;\n}\n"
                ),
            },
        )
        buf = io.StringIO()
        loops, upward = check([looped], out=buf)
        if loops or upward != [("core", ("grid", "overlap"), ("bvh",))]:
            failures.append("planted upward import: got %r %r\n%s" % (loops, upward, buf.getvalue()))

        # Cross-folder three-module cycle with nested use trees and `self`.
        cyc = os.path.join(tmp, "frontend", "src")
        write(
            cyc,
            {
                "lib.rs": "pub mod a;\npub mod b;\npub mod c;\n",
                "a.rs": "use crate::{b::{self, B}, c as _};\n",
                "b.rs": "pub struct B;\npub fn g() { crate::c::h(); }\n",
                "c.rs": "pub fn h() {}\nuse super::a;\n",
            },
        )
        buf = io.StringIO()
        loops, upward = check([cyc], out=buf)
        if [comp for _c, comp in loops] != [[("a",), ("b",), ("c",)]]:
            failures.append("planted 3-cycle: got %r\n%s" % (loops, buf.getvalue()))
    for f in failures:
        print("SELF-TEST FAILED: " + f)
    if not failures:
        print("self-test: planted loops and upward import found, clean tree passes")
    return 1 if failures else 0


def main(argv):
    if "--self-test" in argv:
        return self_test()
    show = "--edges" in argv
    max_loops, max_upward = 0, 0
    for a in argv:
        if a.startswith("--at-most="):
            max_loops, max_upward = (int(x) for x in a.split("=", 1)[1].split(","))
    dirs = [a for a in argv if not a.startswith("--")]
    if not dirs:
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        dirs = [os.path.join(root, "core", "src"), os.path.join(root, "frontend", "src")]
    loops, upward = check(dirs, show_edges=show)
    if len(loops) > max_loops or len(upward) > max_upward:
        print("FAIL: more than %d loop(s) or %d upward import(s)" % (max_loops, max_upward))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
