"""The layout rules of src/ (docs: DESIGN.md, "Layout"), read from the source tree alone:
- src/cpu and src/cuda are siblings: no file of one pulls in a header of the other, directly or
  through other headers; src/prep, which both use, pulls in neither;
- src/core is self-contained: its quoted includes stay inside src/core;
- no include loop: modules (the files of one stem, x.c x.h x.cu x.cuh, with x_internal.h counted
  as x's) whose quoted includes lead back to themselves;
- the program is built against the public headers: cli/ includes evray.h, evray_experimental.h
  and its own headers only.
Quoted includes resolve as the compiler resolves them: the includer's folder, then src/, then
include/; angle-bracket (system) includes are not followed."""
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SRC = os.path.join(ROOT, "src")
SEARCH = [SRC, os.path.join(ROOT, "include")]
EXTS = (".c", ".h", ".cu", ".cuh")
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def rel(path):
    return os.path.relpath(path, SRC).replace(os.sep, "/")


def source_files():
    for top, _, names in os.walk(SRC):
        for name in sorted(names):
            if name.endswith(EXTS):
                yield rel(os.path.join(top, name))


def strip_comments(text):
    return re.sub(r"/\*.*?\*/|//[^\n]*", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)


def includes_of(f):
    """Quoted includes of src/f: (as written, resolved src/-relative path or None outside src/)."""
    with open(os.path.join(SRC, f), encoding="utf-8", errors="replace") as fh:
        text = strip_comments(fh.read())
    out = []
    for name in INCLUDE.findall(text):
        found = None
        for base in [os.path.dirname(os.path.join(SRC, f))] + SEARCH:
            p = os.path.normpath(os.path.join(base, name))
            if os.path.isfile(p):
                found = p
                break
        inside = found is not None and os.path.commonpath([found, SRC]) == SRC
        out.append((name, rel(found) if inside else None, found))
    return out


files = list(source_files())
graph = {f: includes_of(f) for f in files}
failures = []


def area(f):
    return f.split("/", 1)[0] if "/" in f else ""


def reach(start):
    """Every src/ file the compile of start reads, each with the chain of includes that got there."""
    seen = {start: [start]}
    todo = [start]
    while todo:
        f = todo.pop()
        for _, g, _ in graph[f]:
            if g is not None and g not in seen:
                seen[g] = seen[f] + [g]
                todo.append(g)
    return seen


# cpu/ and cuda/ never include each other; prep/ includes neither
FORBIDDEN = {"cpu": ("cuda",), "cuda": ("cpu",), "prep": ("cpu", "cuda")}
for f in files:
    for other in FORBIDDEN.get(area(f), ()):
        for g, chain in sorted(reach(f).items()):
            if area(g) == other:
                failures.append(f"{f} includes {other}/: {' -> '.join(chain)}")
                break

# core/ includes nothing outside core/
for f in files:
    if area(f) != "core":
        continue
    for name, g, found in graph[f]:
        if g is None or area(g) != "core":
            where = g or (os.path.relpath(found, ROOT) if found else "not found")
            failures.append(f'{f} includes "{name}" ({where}), outside src/core')


# no include loop among modules
def module(f):
    stem = os.path.splitext(f)[0]
    return stem[: -len("_internal")] if stem.endswith("_internal") else stem


deps = {}
for f in files:
    for _, g, _ in graph[f]:
        if g is not None and module(g) != module(f):
            deps.setdefault(module(f), {}).setdefault(module(g), (f, g))

state, stack, loops = {}, [], []


def visit(m):
    state[m] = 1
    stack.append(m)
    for n in sorted(deps.get(m, {})):
        if state.get(n) == 1:
            cycle = stack[stack.index(n):] + [n]
            how = ", ".join(f"{deps[a][b][0]} includes {deps[a][b][1]}" for a, b in zip(cycle, cycle[1:]))
            loops.append(f"{' -> '.join(cycle)} ({how})")
        elif n not in state:
            visit(n)
    stack.pop()
    state[m] = 2


sys.setrecursionlimit(10000)
for m in sorted({module(f) for f in files}):
    if m not in state:
        visit(m)
failures += [f"include loop: {loop}" for loop in loops]

# cli/ sees include/ only
CLI = os.path.join(ROOT, "cli")
own = {n for n in os.listdir(CLI) if n.endswith(".h")}
for name in sorted(os.listdir(CLI)):
    if name.endswith((".c", ".h")):
        with open(os.path.join(CLI, name), encoding="utf-8", errors="replace") as fh:
            for inc in INCLUDE.findall(strip_comments(fh.read())):
                if inc not in ("evray.h", "evray_experimental.h") and inc not in own:
                    failures.append(f'cli/{name} includes "{inc}": the program sees include/ only')

for what in failures:
    print("CHECK failed:", what, file=sys.stderr)
print(f"{len(files)} files under src/, {len(failures)} layout problems")
sys.exit(1 if failures else 0)
