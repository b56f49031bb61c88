"""The C and CUDA sources are formatted as .clang-format says (clang-format --dry-run finds
nothing to change). Skips when clang-format is not installed (scripts/deps.sh installs it)."""
import os
import shutil
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
tool = shutil.which("clang-format")
if not tool:
    print("SKIP: clang-format is not installed (scripts/deps.sh installs it)")
    sys.exit(77)
files = []
for top in ("src", "cli", "include", "tests", "python"):
    for d, _, names in os.walk(os.path.join(ROOT, top)):
        files += [os.path.join(d, n) for n in sorted(names) if n.endswith((".c", ".h", ".cu", ".cuh"))]
p = subprocess.run([tool, "--dry-run", "--Werror", *files], capture_output=True, text=True, cwd=ROOT)
bad = sorted({line.split(":")[0] for line in p.stderr.splitlines() if ": error:" in line})
for f in bad:
    print("CHECK failed: not formatted (run clang-format -i):", os.path.relpath(f, ROOT), file=sys.stderr)
if p.returncode != 0 and not bad:  # clang-format itself failed (e.g. a bad .clang-format)
    print("CHECK failed: clang-format:", p.stderr.strip()[:500], file=sys.stderr)
print(f"test_format: {len(files)} files, {len(bad)} not formatted")
sys.exit(1 if p.returncode != 0 else 0)
