"""The fuzz targets' corpora replayed on every run (issue 29): the seeds tests/fuzz/make_seeds.py
writes, and every input that once crashed, leaked or hung a target (tests/fuzz/regress/TARGET/),
each through its target built with a plain main (fuzz_replay_TARGET in the build's tests/
folder; under AddressSanitizer and UBSan in the sanitizer build, where a leak fails too). The
libFuzzer builds of the same targets are scripts/fuzz.sh's (docs/reliability.md)."""
import glob
import os
import subprocess
import sys

import evrtest as T

HERE = os.path.dirname(os.path.abspath(__file__))
build_tests = os.path.join(os.path.dirname(os.path.abspath(T.EVRAY)), "tests")
targets = sorted(os.path.basename(p)[5:-2] for p in glob.glob(os.path.join(HERE, "fuzz", "fuzz_*.c")))
seeds = os.path.join(T.tmpdir(), "seeds")
p = subprocess.run([sys.executable, os.path.join(HERE, "fuzz", "make_seeds.py"), T.EVRAY, seeds],
                   capture_output=True, text=True)
T.check(p.returncode == 0, f"make_seeds.py writes the seeds ({p.stderr.strip()[-300:]})")
T.check(len(targets) >= 5, f"the fuzz targets are found ({targets})")
for t in targets:
    exe = os.path.join(build_tests, "fuzz_replay_" + t)
    if not os.path.exists(exe):
        T.check(False, f"{exe} is built")
        continue
    dirs = [d for d in (os.path.join(seeds, t), os.path.join(HERE, "fuzz", "regress", t)) if os.path.isdir(d)]
    n_inputs = sum(len([f for f in os.listdir(d) if not f.startswith(".")]) for d in dirs)
    try:
        # a file that hangs Assimp is refused after EVR_IMPORT_SECONDS (60 by default)
        r = subprocess.run([exe, *dirs], capture_output=True, text=True, timeout=600,
                           env=dict(os.environ, EVR_IMPORT_SECONDS="5"))
    except subprocess.TimeoutExpired:
        T.check(False, f"{t}: the corpus replays within 600 s (an input hangs)")
        continue
    T.check(r.returncode == 0 and f"replayed {n_inputs} inputs" in r.stdout,
            f"{t}: {n_inputs} inputs replayed without a crash, sanitizer report or leak "
            f"(exit {r.returncode}: {(r.stdout + r.stderr).strip()[-1500:]})")
    print(f"{t}: {n_inputs} inputs replayed")
T.finish("test_fuzz_replay")
