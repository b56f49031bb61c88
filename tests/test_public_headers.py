"""The program is built against the public headers: cli/ includes only evray.h,
evray_experimental.h and its own headers; and src/ has no include loop, counting a .c and its .h
as one module (so a loop through two modules' headers shows up too)."""
import os
import re

import evrtest as T

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def includes(path):
    with open(path, errors="replace") as f:
        return INCLUDE.findall(f.read())


cli = os.path.join(ROOT, "cli")
own = {n for n in os.listdir(cli) if n.endswith(".h")}
for name in sorted(os.listdir(cli)):
    if name.endswith((".c", ".h")):
        for inc in includes(os.path.join(cli, name)):
            T.check(inc in ("evray.h", "evray_experimental.h") or inc in own,
                    f"cli/{name} includes \"{inc}\": the program sees include/ only")

src = os.path.join(ROOT, "src")
files = {}
for d, _, names in os.walk(src):
    for n in names:
        if n.endswith((".c", ".h", ".cu", ".cuh")):
            files[os.path.relpath(os.path.join(d, n), src)] = includes(os.path.join(d, n))


def module(rel):
    return os.path.splitext(rel)[0]


graph = {}
for rel, incs in files.items():
    for inc in incs:
        for base in (os.path.dirname(rel), ""):
            target = os.path.normpath(os.path.join(base, inc))
            if target in files:
                if module(target) != module(rel):
                    graph.setdefault(module(rel), set()).add(module(target))
                break

state = {}


def visit(node, stack):
    state[node] = 1
    stack.append(node)
    for nxt in sorted(graph.get(node, ())):
        if state.get(nxt) == 1:
            T.check(False, "include loop: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
        elif not state.get(nxt):
            visit(nxt, stack)
    stack.pop()
    state[node] = 2


for node in sorted(graph):
    if not state.get(node):
        visit(node, [])
T.finish("test_public_headers")
