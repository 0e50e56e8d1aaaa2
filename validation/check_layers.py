#!/usr/bin/env python3
"""The layering rules of baker/src (issue 17), checked from the code's own paths.

Every `crate::a::b` path (in `use` lines and inline), `super::` and `self::` path and
`mod x;` declaration of a file is resolved to the file it names. Then:

1. no file outside baker/src/cli/ names `crate::cli`;
2. files under output/, pipeline/ and math/ name no domain module (skin, transport, fiber,
   spectral, fit, profile, spec, export, bake);
3. no import cycle between files (a module's mod.rs re-exporting its children is not an
   import of theirs: `mod`/`pub mod`/`pub use` lines of a mod.rs are skipped as edges);
4. no function over 120 lines outside tests, in baker/src and formats/src;
5. no `#[allow(clippy::too_many_arguments)]` there (arguments travel in named structs).

    python3 validation/check_layers.py        # exit 1 and a list when a rule is broken
"""
import os
import re
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SRC = os.path.join(ROOT, "baker", "src")
DOMAIN = {"skin", "transport", "fiber", "spectral", "fit", "profile", "spec", "export", "bake"}
GENERIC = ("output", "pipeline", "math")


def module_files():
    """Module path (tuple) -> file, for every .rs file under baker/src."""
    files = {}
    for dp, _, fs in os.walk(SRC):
        for f in fs:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(dp, f), SRC)[:-3].split(os.sep)
            if rel[-1] == "mod":
                rel = rel[:-1]
            if rel in (["lib"], ["main"]):
                rel = []
            files[tuple(rel)] = os.path.join(dp, f)
    return files


def strip(text):
    """The code without comments, strings and test modules."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r'"(\\.|[^"\\])*"', '""', text)
    i = text.find("#[cfg(test)]")
    return text if i < 0 else text[:i]


def resolve(files, path):
    """The longest prefix of `path` that is a module file."""
    for n in range(len(path), -1, -1):
        if tuple(path[:n]) in files:
            return tuple(path[:n])
    return None


def expand(tree):
    """`a::{b, c::{d, e}}` -> ["a::b", "a::c::d", "a::c::e"]."""
    tree = re.sub(r"\s+as\s+", " as ", tree.strip())
    tree = re.sub(r"\s*([{},:])\s*", r"\1", tree)
    i = tree.find("{")
    if i < 0:
        return [tree]
    prefix, body = tree[:i], tree[i + 1:-1]
    parts, depth, cur = [], 0, ""
    for ch in body:
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    parts.append(cur)
    return [prefix + q for part in parts if part for q in expand(part)]


def reexports_of(files):
    """(module, name) -> the module that defines what `module` re-exports as `name`."""
    out = {}
    for m, f in files.items():
        if not (f.endswith("mod.rs") or f.endswith("lib.rs")):
            continue
        code = strip(open(f).read())
        for u in re.finditer(r"^\s*pub\s+use\s+([^;]+);", code, re.M | re.S):
            for path in expand(u.group(1)):
                parts = [p for p in path.split(" as ")[0].split("::") if p]
                alias = path.split(" as ")[-1].split("::")[-1]
                if parts and parts[0] == "crate":
                    src = resolve(files, parts[1:-1])
                elif parts and parts[0] == "super":
                    src = resolve(files, list(m[:-1]) + parts[1:-1])
                else:
                    src = resolve(files, list(m) + [p for p in parts[:-1] if p != "self"])
                if src is not None and src != m:
                    out[(m, alias)] = src
    return out


def edges(files):
    reexports = reexports_of(files)
    out = {m: set() for m in files}
    for m, f in files.items():
        is_mod_rs = f.endswith("mod.rs") or f.endswith("lib.rs")
        here = list(m)
        code = strip(open(f).read())
        paths = []
        for u in re.finditer(r"^\s*(pub(\([^)]*\))?\s+)?use\s+([^;]+);", code, re.M | re.S):
            # A module's face: a mod.rs re-exporting its own children is not an import.
            if is_mod_rs and u.group(1) and not u.group(3).startswith("crate"):
                continue
            paths += expand(u.group(3))
        code_wo_use = re.sub(r"^\s*(pub(\([^)]*\))?\s+)?use\s+[^;]+;", "", code, flags=re.M | re.S)
        paths += [mt.group(0) for mt in re.finditer(r"\b(crate|super|self)(::\w+)+", code_wo_use)]
        # Bare paths into a child module (`skin::bake(…)` in bake/mod.rs) and use lines
        # naming one (`use skin::X;`).
        for mt in re.finditer(r"(?<![:\w])(\w+)((::\w+)+)", code_wo_use):
            if tuple(m) + (mt.group(1),) in files and mt.group(1) not in ("crate", "super", "self"):
                paths.append("self::" + mt.group(0))
        for u in re.finditer(r"^\s*use\s+(\w+)::", code, re.M):
            if tuple(m) + (u.group(1),) in files:
                paths += ["self::" + q for q in expand(re.search(r"use\s+([^;]+);", code[u.start():], re.S).group(1))]
        for path in paths:
            parts = [p for p in path.split(" as ")[0].split("::") if p]
            if not parts or parts[0] not in ("crate", "super", "self"):
                continue
            head, rest = parts[0], parts[1:]
            if head == "crate":
                base = []
            elif head == "self":
                base = list(here)
                rest = [p for p in rest if p != "self"]
            else:
                base = list(here)[:-1]
                while rest and rest[0] == "super":
                    rest = rest[1:]
                    base = base[:-1]
            rest = [p for p in rest if p != "self"]
            full = base + rest
            target = resolve(files, full)
            # A name a module re-exports (`pub use skin::SkinSpec;` in spec/mod.rs) is an
            # import of the module that defines it.
            if target is not None and len(full) > len(target):
                target = reexports.get((target, full[len(target)]), target)
            if target is not None and target != m and target != ():
                out[m].add(target)
    return out


def cycles(graph):
    """Strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, comps, counter = {}, {}, [], set(), [], [0]

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
                comps.append(comp)

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return comps


def long_functions(roots, limit=120):
    found = []
    for root in roots:
        for dp, _, fs in os.walk(root):
            for f in fs:
                if not f.endswith(".rs"):
                    continue
                p = os.path.join(dp, f)
                lines = open(p).read().split("\n")
                stop = next((i for i, l in enumerate(lines) if l.strip() == "#[cfg(test)]"), len(lines))
                i = 0
                while i < stop:
                    m = re.match(r"\s*(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?fn\s+(\w+)", lines[i])
                    if m:
                        depth, started, j = 0, False, i
                        while j < len(lines):
                            t = re.sub(r'"(\\.|[^"\\])*"', '""', lines[j])
                            t = re.sub(r"'(\\.|[^'\\])'", "''", t).split("//")[0]
                            depth += t.count("{") - t.count("}")
                            started = started or "{" in t
                            if started and depth <= 0:
                                break
                            if not started and t.rstrip().endswith(";"):
                                break
                            j += 1
                        if j - i + 1 > limit:
                            found.append(f"{os.path.relpath(p, ROOT)}:{i + 1} {m.group(5)} ({j - i + 1} lines)")
                        i = j
                    i += 1
    return found


def main():
    files = module_files()
    graph = edges(files)
    name = lambda m: "::".join(m) or "lib"
    problems = []
    for m, targets in graph.items():
        for t in targets:
            if t[:1] == ("cli",) and m[:1] != ("cli",):
                problems.append(f"{name(m)} imports {name(t)} (nothing outside cli/ may)")
            if m[:1] and m[0] in GENERIC and t[:1] and t[0] in DOMAIN:
                problems.append(f"{name(m)} imports the domain module {name(t)}")
    for comp in cycles(graph):
        problems.append("import cycle: " + " -> ".join(sorted(name(m) for m in comp)))
    roots = [SRC, os.path.join(ROOT, "formats", "src")]
    problems += [f"function over 120 lines: {f}" for f in long_functions(roots)]
    for root in roots:
        for dp, _, fs in os.walk(root):
            for f in fs:
                p = os.path.join(dp, f)
                if f.endswith(".rs") and "too_many_arguments" in open(p).read():
                    problems.append(f"{os.path.relpath(p, ROOT)}: allows clippy::too_many_arguments")
    for p in sorted(problems):
        print(p)
    n_edges = sum(len(t) for t in graph.values())
    print(f"{len(files)} files, {n_edges} imports between them: "
          + ("every rule holds" if not problems else f"{len(problems)} problem(s)"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
