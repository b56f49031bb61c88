"""The GPU BVH cache (--bvh-cache, src/cuda/gpu_bvh_cache.h) end to end on the CUDA backend: a
model of 65,536 triangles (tests/big_asset.py, at the size the cache starts keeping trees) under
an orbiting camera; the first run writes its tree, the second reads it (run.json's
bvh_trees_cached), --bvh-cache off neither reads nor writes, and all three give byte-identical
events; a damaged file is built again with one note and replaced; a tree too small is not kept.
Skipped (exit 77) where this build has no CUDA backend or no GPU is usable."""
import hashlib
import json
import os
import subprocess
import sys

import evrtest as T

tmp = T.tmpdir()
probe = T.run("demo", "--scene", "square", "-o", os.path.join(tmp, "probe"), "--res", "16x16", "--duration", "0.1",
              "--backend", "cuda", "--quiet", "--no-preview", expect=None)
if probe.returncode != 0:
    T.skip("test_cuda_bvh_cache", probe.stderr.strip())

here = os.path.dirname(os.path.abspath(__file__))
model = os.path.join(tmp, "torus.glb")
small = os.path.join(tmp, "small.glb")
subprocess.run([sys.executable, os.path.join(here, "big_asset.py"), model, "--grid", "256", "128",
                "--texture", "64"], check=True, capture_output=True)
subprocess.run([sys.executable, os.path.join(here, "big_asset.py"), small, "--grid", "128", "64",
                "--texture", "64"], check=True, capture_output=True)
cache = os.path.join(tmp, "cache")


def render(name, scene=model, setting=cache):
    """A run; (its run.json's stats, the sha256 of its events.npy, its stderr)."""
    out = os.path.join(tmp, name)
    p = T.run("render", scene, "--backend", "cuda", "--camera-path", "orbit", "--res", "160x120",
              "--duration", "0.2", "--samples-per-frame", "10", "--bvh-cache", setting, "--format", "npy",
              "--no-preview", "-o", out)
    with open(os.path.join(out, "run.json")) as f:
        stats = json.load(f)["stats"]
    with open(os.path.join(out, "events.npy"), "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    return stats, digest, p.stderr


def trees():
    return sorted(n for n in os.listdir(cache) if n.endswith(".evrbvh")) if os.path.isdir(cache) else []


first, events, err1 = render("first")
T.check(first["bvh_trees"] == 1 and first["bvh_trees_cached"] == 0, f"the first run builds its tree ({first})")
T.check(len(trees()) == 1, f"and writes it to the folder ({trees()})")
T.check("BVH cache" not in err1, f"without a note ({err1!r})")
second, events2, _ = render("second")
T.check(second["bvh_trees_cached"] == 1, f"the second run reads it ({second})")
T.check(events2 == events, "with byte-identical events")
off, events3, _ = render("off", setting="off")
T.check(off["bvh_trees_cached"] == 0 and len(trees()) == 1, f"--bvh-cache off neither reads nor writes ({off})")
T.check(events3 == events, "and gives the same events")
print("set-up of the tree: built %.3f s, read %.3f s, off %.3f s" %
      (first["time_setup_bvh_seconds"], second["time_setup_bvh_seconds"], off["time_setup_bvh_seconds"]))

# a damaged file: built again, one note, replaced
path = os.path.join(cache, trees()[0])
with open(path, "r+b") as f:
    f.seek(os.path.getsize(path) // 2)
    b = f.read(1)
    f.seek(-1, os.SEEK_CUR)
    f.write(bytes([b[0] ^ 0x40]))
damaged, events4, err4 = render("damaged")
notes = [l for l in err4.splitlines() if "BVH cache" in l]
T.check(len(notes) == 1 and "damaged" in notes[0] and "checksum" in notes[0], f"a damaged file is said in one note ({err4!r})")
T.check(damaged["bvh_trees_cached"] == 0 and events4 == events, f"and built again, the same events ({damaged})")
again, _, _ = render("again")
T.check(again["bvh_trees_cached"] == 1, f"and replaced: the next run reads it ({again})")

# a model below the size the cache keeps (16,384 triangles) is built every time
render("small", scene=small)
T.check(len(trees()) == 1, f"a small model's tree is not kept ({trees()})")
T.finish("test_cuda_bvh_cache")
