"""What evray leaves in a run folder, and how a run ends: events.h5 byte-identical for the same
inputs however the writers' flushes fell."""
import os
import subprocess

import evrtest as T

RUN = ["--res", "128x96", "--duration", "0.5", "--quiet", "--no-preview"]


def run_env(env, *args, expect=0):
    """evray with extra environment variables (dict)."""
    p = subprocess.run([T.EVRAY, *map(str, args)], capture_output=True, text=True,
                       env={**os.environ, **env})
    if expect is not None and p.returncode != expect:
        print(p.stdout, p.stderr)
        raise SystemExit(f"evray {' '.join(map(str, args))}: exit {p.returncode}, expected {expect}")
    return p


def read(path):
    with open(path, "rb") as f:
        return f.read()


# two identical runs, one flushing after every batch (EVR_FLUSH_SECONDS=0, a hidden test switch),
# the other at the usual interval: the same bytes (no time stamps, the same layout)
root = T.tmpdir()
a, b = os.path.join(root, "a"), os.path.join(root, "b")
run_env({"EVR_FLUSH_SECONDS": "0"}, "-o", a, *RUN)
run_env({}, "-o", b, *RUN)
ha, hb = read(os.path.join(a, "events.h5")), read(os.path.join(b, "events.h5"))
T.check(len(ha) > 100000, f"a run of more than one HDF5 chunk ({len(ha)} bytes)")
T.check(ha == hb, "events.h5 byte-identical for the same inputs, whenever the flushes came")

T.finish("test_run_files")
