#!/usr/bin/env python3
"""Module-level import cycles in a Rust crate (issue 49: none in the hosts).

Usage: scripts/import-cycles.py SRC_DIR [SRC_DIR ...]   (e.g. core/src host-cli/src)

For each crate source directory: every `.rs` file is mapped to its module path
(`a/b.rs` and `a/b/mod.rs` are `a::b`; `lib.rs` and `main.rs` are the crate root), and
every module it names in code is collected: `use crate::a::b…` (braces expanded),
`crate::a::b::…` paths, and `super::…` / `self::…` paths resolved against the file's own
module. Comments, strings and `#[cfg(test)]`-only files are read as any other code except
that comments and string literals are blanked first. Each import is then reduced to the
*file-level module* it lands in: the longest module path of a file that prefixes it (an
item `crate::a::b::Thing` of `a/b.rs` counts as `a::b`; `a/mod.rs` counts as `a`). A
child that reaches its own parent's items through `super::` gives the edge child →
parent. Edges from a file to itself, and to the crate root (`lib.rs`: the list of
modules, not code), are left out.

Prints every strongly connected component of more than one module (Tarjan), one per line
as `crate: a -> b -> c`, and exits 1 if there is any; else prints `crate: no import
cycles` and exits 0.
"""

import os
import re
import sys


def strip_comments_and_strings(text):
    """Blank comments and string/char literals (so `crate::x` in a doc is no import)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    out.append("\n" if text[i] == "\n" else "")
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 8]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            end = text.find('"' + m.group(1), i + len(m.group(0)))
            i = n if end < 0 else end + 1 + len(m.group(1))
            out.append('""')
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            i = j + 1
            out.append('""')
        elif c == "'" and re.match(r"'(\\.[^']*|[^\\'])'", text[i:i + 12]):
            m = re.match(r"'(\\.[^']*|[^\\'])'", text[i:])
            i += len(m.group(0))
            out.append("' '")
        else:
            out.append(c)
            i += 1
    return "".join(out)


def module_of(src, path):
    """The module path (a tuple) of the file `path` under `src`."""
    rel = os.path.relpath(path, src)[:-3].split(os.sep)
    if rel[-1] == "mod":
        rel = rel[:-1]
    if rel in (["lib"], ["main"]):
        return ()
    return tuple(rel)


def expand_use(tree):
    """`a::{b, c::{d, e}}` -> ['a::b', 'a::c::d', 'a::c::e'] (aliases and globs dropped)."""
    tree = re.sub(r"\s+", "", tree)
    if "{" not in tree:
        return [re.sub(r"as\w+$", "", tree)] if tree else []
    head = tree[: tree.index("{")]
    depth, parts, start = 0, [], tree.index("{") + 1
    body_end = tree.rindex("}")
    for k in range(start, body_end):
        ch = tree[k]
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(tree[start:k])
            start = k + 1
    parts.append(tree[start:body_end])
    out = []
    for p in parts:
        if p in ("", "self"):
            out.append(head.rstrip(":"))
        else:
            out.extend(head + q for q in expand_use(p))
    return out


def resolve(path, module):
    """A path as written in `module`'s file -> absolute segments, or None if not crate-local."""
    segs = [s for s in path.split("::") if s and s != "*"]
    if not segs:
        return None
    if segs[0] == "crate":
        return tuple(segs[1:])
    if segs[0] in ("super", "self"):
        base = list(module)
        while segs and segs[0] in ("super", "self"):
            if segs[0] == "super":
                if not base:
                    return None
                base.pop()
            segs = segs[1:]
        return tuple(base + segs)
    return None


def imports(text, module):
    """Absolute paths (tuples) the code of `module` names."""
    code = strip_comments_and_strings(text)
    found = []
    for m in re.finditer(r"\buse\s+([^;]+);", code):
        tree = m.group(1).strip()
        if tree.startswith(("crate::", "super::", "self::")):
            for p in expand_use(tree):
                r = resolve(p, module)
                if r is not None:
                    found.append(r)
    # Paths in code (outside `use`): crate::a::b…, super::a…, self::a…
    code_no_use = re.sub(r"\buse\s+[^;]+;", "", code)
    for m in re.finditer(r"\b((?:crate|super|self)(?:::\w+)+)", code_no_use):
        r = resolve(m.group(1), module)
        if r is not None:
            found.append(r)
    return found


def file_module(path, modules):
    """The longest module of a file that prefixes `path`."""
    for k in range(len(path), -1, -1):
        if path[:k] in modules:
            return path[:k]
    return ()


def tarjan(nodes, edges):
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
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
            out.append(comp)

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


def cycle_in(comp, edges):
    """One cycle through the component, for reading: a -> b -> … -> a."""
    members = set(comp)
    start = min(comp)
    path, seen = [start], {start}
    while True:
        nxt = sorted(w for w in edges.get(path[-1], ()) if w in members)
        back = [w for w in nxt if w == start]
        if back and len(path) > 1:
            return path + [start]
        fresh = [w for w in nxt if w not in seen]
        if not fresh:
            return path + [start]
        path.append(fresh[0])
        seen.add(fresh[0])


def check(src):
    files = {}
    for root, _, names in os.walk(src):
        for name in names:
            if name.endswith(".rs"):
                p = os.path.join(root, name)
                files[module_of(src, p)] = p
    modules = set(files)
    edges = {}
    for module, p in files.items():
        with open(p, encoding="utf-8") as f:
            text = f.read()
        for target in imports(text, module):
            to = file_module(target, modules)
            if to != module and to != ():
                edges.setdefault(module, set()).add(to)
    name = os.path.basename(os.path.dirname(os.path.abspath(src))) or src
    fmt = lambda m: "::".join(m) or "crate"
    comps = [c for c in tarjan(modules, edges) if len(c) > 1]
    for comp in sorted(comps, key=lambda c: sorted(c)):
        members = ", ".join(sorted(fmt(m) for m in comp))
        print(f"{name}: cycle of {len(comp)} modules ({members}): {' -> '.join(fmt(m) for m in cycle_in(comp, edges))}")
    if not comps:
        print(f"{name}: no import cycles ({len(modules)} files, {sum(len(v) for v in edges.values())} edges)")
    return bool(comps)


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    found = False
    for src in argv[1:]:
        found |= check(src)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
