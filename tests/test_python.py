"""The Python package (pyproject.toml, python/): scripts/python-venv.sh makes a fresh virtual
environment beside the program and installs evray into it from the source tree (pip wheel ., the
wheel installed; without CUDA), then tests/python's pytest tests run in it. Skips when the
environment cannot be made (no network for the pinned packages), and in the sanitizer build (the
package is built and tested once, in the release build)."""
import os
import subprocess
import sys
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
build = os.path.dirname(os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "build/evray"))
cache = os.path.join(build, "CMakeCache.txt")
if os.path.exists(cache) and "EVR_SANITIZE:BOOL=ON" in open(cache).read():
    print("SKIP: the Python package is built and tested in the release build, not the sanitizer one")
    sys.exit(77)
venv = os.path.join(build, "pyvenv")
t0 = time.time()
p = subprocess.run([os.path.join(ROOT, "scripts", "python-venv.sh"), venv, os.path.join(build, "python-pkg")])
if p.returncode != 0:
    print("CHECK failed: scripts/python-venv.sh could not install the package", file=sys.stderr)
    sys.exit(1)
python = os.path.join(venv, "bin", "python")
if not os.path.exists(python):
    print("SKIP: no virtual environment for the package (scripts/python-venv.sh says why: it needs "
          "the package registry)")
    sys.exit(77)
t1 = time.time()
print(f"test_python: environment and package in {t1 - t0:.1f} s")
env = dict(os.environ, PATH=os.path.join(venv, "bin") + os.pathsep + os.environ.get("PATH", ""))
# from outside the source tree, so that `import evray` is the installed package
p = subprocess.run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider", os.path.join(ROOT, "tests", "python")],
                   cwd=build, env=env)
print(f"test_python: pytest in {time.time() - t1:.1f} s")
sys.exit(p.returncode)
