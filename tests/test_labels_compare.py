"""labels_compare (tests/labels_compare.c), which test_cuda_labels.py uses where h5py is missing
(the GPU machine): two CPU runs of the square scene that differ only in the seed agree on every
pixel; a run with the camera moved 0.1 m closer disagrees as the geometry says (every depth off
by 2.5%, far beyond 1e-3; the background's flow still zero in both, the square's not); the
figures equal those of the same criteria in numpy/h5py where the oracle environment is there;
files that cannot be compared (other sizes, other frame times, missing, corrupt, not labels) give
one error line and exit 1."""
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evrtest as T  # noqa: E402

prog = T.labels_compare_program()
if prog is None:
    T.skip("test_labels_compare", "labels_compare is not built beside " + T.EVRAY)
tmp = T.tmpdir()


def labels(name, *args):
    d = os.path.join(tmp, name)
    T.run("demo", "--scene", "square", "--res", "64x64", "--duration", "1", "--labels-fps", "8",
          "-o", d, "-q", "--no-preview", *args)
    return os.path.join(d, "labels.h5")


a = labels("seed1", "--seed", "1")
b = labels("seed2", "--seed", "2")
near = labels("near", "--look-from", "0,0,3.9", "--look-at", "0,0,0")
other_size = labels("size", "--res", "32x32")
other_times = labels("times", "--start", "0.05")

r = T.compare_labels(a, b)
print("seeds 1 and 2:", r)
T.check(r["frames"] == 9 and r["width"] == 64 and r["height"] == 64, f"shape {r}")
T.check(r["seen"] == 9 * 64 * 64, f"every pixel sees a surface (seen {r['seen']})")
T.check(r["same"] == 1.0 and r["depth"] == 1.0 and r["flow"] == 1.0, f"identical labels {r}")

r = T.compare_labels(a, near)
print("camera 0.1 m closer:", r)
T.check(r["seen"] > 0.9 * 9 * 64 * 64, f"most pixels compared {r}")
T.check(0.95 < r["same"] < 1.0, f"the square covers other pixels {r}")
T.check(r["depth"] == 0.0, f"no depth within 1e-3 {r}")
T.check(0.8 < r["flow"] < 1.0, f"the background's flow agrees, the square's not {r}")

COMPARE = r"""
import h5py, json, sys, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
ia, ib = a["instance"][()], b["instance"][()]
same = ia == ib
both = same & (ia > 0)
da, db = a["depth"][()][both].astype(np.float64), b["depth"][()][both].astype(np.float64)
fa, fb = a["flow"][()][both].astype(np.float64), b["flow"][()][both].astype(np.float64)
dok = np.abs(da - db) <= 1e-3 * np.abs(da)
fok = np.all(np.abs(fa - fb) <= 1e-2 + 1e-3 * np.abs(fa), axis=-1)
print(json.dumps({"same": float(same.mean()), "depth": float(dok.mean()) if dok.size else 1.0,
                  "flow": float(fok.mean()) if fok.size else 1.0, "seen": int(both.sum())}))
"""
python = T.oracle_python(["numpy", "h5py"], optional=True)
if python:
    import json
    for x, y in ((a, b), (a, near)):
        p = subprocess.run([python, "-c", COMPARE, x, y], capture_output=True, text=True)
        T.check(p.returncode == 0, "h5py reads both: " + p.stderr)
        if p.returncode == 0:
            o, r = json.loads(p.stdout), T.compare_labels(x, y)
            T.check(o["seen"] == r["seen"] and all(abs(o[k] - r[k]) < 1e-12 for k in
                                                   ("same", "depth", "flow")),
                    f"labels_compare {r} equals numpy {o}")
    print("labels_compare's figures equal numpy's")

# what cannot be compared: one line, exit 1
corrupt = os.path.join(tmp, "corrupt.h5")
with open(a, "rb") as f:
    data = f.read()
with open(corrupt, "wb") as f:
    f.write(data[:len(data) // 2])
events = os.path.join(tmp, "seed1", "events.h5")
for x, y, what in ((a, other_size, "9 frames of 64x64"), (a, other_times, "frame 0 is at"),
                   (a, os.path.join(tmp, "missing.h5"), "No such file"),
                   (corrupt, a, "corrupt.h5"), (events, a, "not a labels.h5 file"),
                   (a, tmp, "not a file")):
    p = subprocess.run([prog, x, y], capture_output=True, text=True)
    lines = p.stderr.strip().splitlines()
    T.check(p.returncode == 1 and p.stdout == "" and len(lines) == 1 and what in p.stderr,
            f"labels_compare {os.path.basename(x)} {os.path.basename(y)}: exit {p.returncode}, "
            f"{p.stderr!r} (expected one line with {what!r})")
p = subprocess.run([prog, a], capture_output=True, text=True)
T.check(p.returncode == 2 and "usage" in p.stderr, "one file: usage, exit 2")
T.finish("test_labels_compare")
