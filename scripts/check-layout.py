#!/usr/bin/env python3
"""The layout's two rules, read from the imports of `src/` file by file:

1. No arrow back up: a folder imports only from the floors below it (FLOORS, lowest first;
   test modules excepted).
2. No circle inside a folder: the files of one folder import each other without a cycle (a
   file's imports resolved to the file that defines the name; `mod.rs`'s module declarations
   and re-exports are the folder's dispatch, not imports). The circles not yet untangled are
   listed in KNOWN (none today): a new circle fails, and so does a listed one that is gone.

Exit 1 with what is wrong; run by `.ci/run`."""

import collections
import os
import re
import sys

FLOORS = ["error", "simd", "geometry", "image", "ffd", "mesh", "materials", "model", "register", "fit", "eval",
          "formats", "report", "study", "bin"]
KNOWN = set()
DEFINES = re.compile(
    r"^\s*pub(?:\([^)]*\))?\s+(?:unsafe\s+)?(?:fn|struct|enum|trait|type|const|static|mod)\s+(\w+)",
    re.M)


def is_test(path):
    name = os.path.basename(path)
    return name == "tests.rs" or name.endswith("_tests.rs")


def flatten(tree):
    """`a::{b, c::{d, e}}` as the paths [a, b], [a, c, d], [a, c, e]."""
    i = tree.find("{")
    if i < 0:
        return [tree.split("::")]
    prefix = [p for p in tree[:i].split("::") if p]
    parts, depth, cur = [], 0, ""
    for ch in tree[i + 1:tree.rfind("}")]:
        depth += ch == "{"
        depth -= ch == "}"
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    parts.append(cur)
    return [prefix + q for p in parts if p for q in flatten(p)]


def paths(text):
    """The module paths a file names: its `use` trees and inline `crate::`/`super::` paths."""
    text = re.sub(r"//[^\n]*", "", text)
    out = []
    for m in re.finditer(r"\buse\s+([^;]+);", text):
        out += flatten(re.sub(r"\s", "", m.group(1)))
    out += [m.group(1).split("::")
            for m in re.finditer(r"(?<![\w:])((?:crate|super)(?:::\w+)+)", text)]
    return out


def sccs(graph, nodes):
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(comp)

    for v in nodes:
        if v not in index:
            visit(v)
    return found


def main(root):
    files = {}
    for d, _, names in os.walk(root):
        for n in names:
            if n.endswith(".rs"):
                p = os.path.join(d, n)
                with open(p, encoding="utf-8") as f:
                    files[os.path.relpath(p, root)] = f.read()
    problems = []
    for p, text in sorted(files.items()):
        floor = p.split(os.sep)[0].removesuffix(".rs")
        if floor not in FLOORS or is_test(p):
            continue
        body = text.split("#[cfg(test)]")[0]
        for path in paths(body):
            if path[0] == "crate" and len(path) > 1 and path[1] in FLOORS:
                if FLOORS.index(path[1]) > FLOORS.index(floor):
                    problems.append(f"{p}: imports crate::{path[1]}, a higher floor than {floor}")
    by_folder = collections.defaultdict(list)
    for p in files:
        parts = p.split(os.sep)
        if len(parts) == 2 and parts[0] != "bin":
            by_folder[parts[0]].append(p)
    circles = set()
    for folder, ps in sorted(by_folder.items()):
        stem = {os.path.basename(p)[:-3]: p for p in ps}
        defined = {}
        for p in ps:
            for m in DEFINES.finditer(files[p]):
                defined.setdefault(m.group(1), p)
        graph = collections.defaultdict(set)
        for p in ps:
            text = files[p].split("#[cfg(test)]")[0]
            if p.endswith("mod.rs"):
                text = re.sub(r"^\s*(pub(\([^)]*\))?\s+)?(mod|use)\s[^;]*;", "", text, flags=re.M)
            for path in paths(text):
                if path[0] == "super" and not p.endswith("mod.rs"):
                    rest = path[1:]
                elif path[0] == "crate" and len(path) > 2 and path[1] == folder:
                    rest = path[2:]
                else:
                    continue
                target = stem.get(rest[0]) or defined.get(rest[0])
                if target and target != p and not is_test(target):
                    graph[p].add(target)
        for comp in sccs(graph, sorted(ps)):
            circles.add((folder, tuple(sorted(os.path.basename(x)[:-3] for x in comp))))
    for c in sorted(circles - KNOWN):
        problems.append(f"a circle in {c[0]}/: {' <-> '.join(c[1])}")
    for c in sorted(KNOWN - circles):
        problems.append(f"the circle in {c[0]}/ of {', '.join(c[1])} is gone: take it off KNOWN")
    for p in problems:
        print(p)
    print(f"layout: {len(files)} files, {len(circles)} known circle(s) left, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "src")))
