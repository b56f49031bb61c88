#!/bin/sh
# Runs a short eye (48x36, 0.5 s, one thread: about 3 minutes) under valgrind's memcheck and fails
# when it reports an error that evray causes. Embree 3.13's packet traversal (rtcIntersect8,
# rtcOccluded8) branches on lanes of its own stack arrays that it never fills: those reports'
# uninitialised values are all created inside libembree3 (with every lane of our packets active
# too), so they are counted apart; every other report fails. Usage: scripts/valgrind-eye.sh
# [build/evray]
set -eu
evray=${1:-build/evray}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
valgrind --track-origins=yes --num-callers=20 "$evray" -o "$out/run" --res 48x36 --duration 0.5 \
    --quiet --no-preview --threads 1 >"$out/log" 2>&1 || { tail -30 "$out/log"; exit 1; }
python3 - "$out/log" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
blocks = re.split(r"\n==\d+== \n", text)
ours, embree = [], 0
for b in blocks:
    if not re.search(r"uninitialised|Invalid|Mismatched|overlap|Syscall param|Use of", b):
        continue
    origin = b.split("was created by", 1)[1] if "was created by" in b else ""
    first = re.search(r"(?:at|by) 0x[0-9A-F]+: .*", origin)
    if "uninitialised" in b and first and "libembree3" in first.group(0):
        embree += 1
    else:
        ours.append(b)
summary = re.search(r"ERROR SUMMARY: .*", text).group(0)
print(f"valgrind: {summary}; contexts with origins inside libembree3: {embree}; others: {len(ours)}")
for b in ours:
    print(b)
sys.exit(1 if ours else 0)
PY
