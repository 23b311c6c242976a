#!/usr/bin/env python3
"""Fails when the modules of a crate import each other in a circle.

Each crate is meant to be layered (chronolux-render: framework -> kernels -> techniques ->
registry; the CLI: args -> commands -> cli), so that any part can be read and changed with
only what is below it in mind. Rust allows circular `use` between modules of one crate, so
nothing but this check keeps the layers.

A module is a file (`a/b.rs` or `a/b/mod.rs` is `a::b`). Module m depends on module t when
m's non-comment text names `crate::t...` (also inside `crate::{...}`) or `super::...`
resolving to t. A parent's `mod child;` declaration is not a dependency. The strongly
connected components of that graph (Tarjan) of more than one module are the circles.

Usage: scripts/ci/module-layers.py [CRATE_SRC_DIR ...]  (default: every crates/*/src)
Prints each circle and exits 1 when there is one; `--edges` also prints the graph.
"""

import collections
import glob
import os
import re
import sys


def modules(src):
    mods = {}
    for dirpath, _, files in os.walk(src):
        for f in files:
            if f.endswith(".rs"):
                path = os.path.join(dirpath, f)
                rel = os.path.relpath(path, src)[:-3]
                if rel in ("lib", "main"):
                    name = ""
                else:
                    name = re.sub(r"/mod$", "", rel).replace("/", "::")
                mods[name] = path
    return mods


def edges_of(mods):
    def resolve(path):
        parts = path.split("::")
        for i in range(len(parts), 0, -1):
            m = "::".join(parts[:i])
            if m in mods:
                return m
        return None

    edges = collections.defaultdict(set)
    for m, path in mods.items():
        with open(path, encoding="utf-8") as fh:
            text = "\n".join(
                line for line in fh.read().split("\n") if not line.strip().startswith("//")
            )
        targets = [g for g in re.findall(r"crate::((?:[a-z_0-9]+::)*[a-z_0-9]+)", text)]
        for group in re.findall(r"crate::\{([^}]*)\}", text, re.S):
            targets += re.findall(r"([a-z_0-9]+(?:::[a-z_0-9]+)*)", group)
        for t in targets:
            r = resolve(t)
            if r and r != m:
                edges[m].add(r)
        base = m.split("::") if m else []
        if not path.endswith("mod.rs") and base:
            base = base[:-1]
        for t in re.findall(r"super::((?:[a-z_0-9]+::)*[a-z_0-9]+)", text):
            r = resolve("::".join(base + [t])) or ("::".join(base) if "::".join(base) in mods else None)
            if r is not None and r != m:
                edges[m].add(r)
    return edges


def circles(mods, edges):
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                out.append(sorted(scc))

    for v in sorted(mods):
        if v not in index:
            visit(v)
    return out


def main():
    args = [a for a in sys.argv[1:] if a != "--edges"]
    show = "--edges" in sys.argv[1:]
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    srcs = args or sorted(glob.glob(os.path.join(root, "crates", "*", "src")))
    bad = 0
    for src in srcs:
        mods = modules(src)
        edges = edges_of(mods)
        if show:
            for m in sorted(edges):
                print(f"{src}: {m or 'crate'} -> {' '.join(sorted(edges[m]))}")
        for c in circles(mods, edges):
            bad += 1
            print(f"{src}: modules in a circle: {', '.join(x or 'crate' for x in c)}")
    if bad:
        print(f"{bad} circle(s): move what both sides need into a module below them")
        return 1
    print(f"no module circles in {len(srcs)} crate(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
