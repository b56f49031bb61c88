"""Robust import (issue 22), on the files tests/import_assets.py writes: a texture that is missing,
unreadable or KTX2 is one warning naming it and the material keeps its factors (--strict makes it
an error, leaving nothing behind); quantized meshes (KHR_mesh_quantization) render at their true
size; EXT_mesh_gpu_instancing gives one instance per entry; points and lines left out are named;
the clip length `evray info` prints is accepted by `render --duration` exactly."""
import os
import re
import sys

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import import_assets  # noqa: E402

tmp = T.tmpdir()
A = import_assets.write_all(tmp)


def info(path, *extra, expect=0):
    return T.run("info", path, *extra, expect=expect)


def warnings_of(text):
    """The lines under 'warnings:' of evray info."""
    lines = text.splitlines()
    if "warnings:" not in " ".join(lines):
        return []
    at = next(i for i, l in enumerate(lines) if l.startswith("warnings:"))
    return [l.strip() for l in lines[at + 1:]]


def bounds(text):
    m = re.search(r"bounds \(rest pose\): \(([^)]*)\) to \(([^)]*)\)", text)
    return [float(v) for v in m.group(1).split()], [float(v) for v in m.group(2).split()]


# ---- textures that cannot be used: a warning naming them, the factors kept ----
for name, what in (("missing_texture", "no_such_texture.png"), ("unreadable_texture", "broken.png"),
                   ("missing_texture_obj", "/nonexistent/machine/textures/wood.png"),
                   ("ktx2_texture", "wood.ktx2")):
    p = info(A[name])
    w = warnings_of(p.stdout)
    T.check(len(w) == 1 and what in w[0], f"{name}: one warning naming {what}: {w}")
    T.check(w and ("keeps its factors" in w[0]), f"{name}: the warning says the material keeps its factors")
    want = "base (0.3 0.6 0.9)" if name == "ktx2_texture" else "base (0.8 0.2 0.1)"
    T.check(want in p.stdout, f"{name}: the material keeps its base colour factor ({want})")
    T.check("textures: 0" in p.stdout, f"{name}: no texture loaded")
    if name == "ktx2_texture":
        T.check("KTX2" in w[0], "the KTX2 warning says why (no decoder)")
    # render: the warning on stderr, one line, and the run goes on
    d = os.path.join(tmp, "run_" + name)
    r = T.run("render", A[name], "-o", d, "--res", "32x24", "--duration", "0.1", "--no-preview",
              "--format", "npy", "--quiet")
    lines = [l for l in r.stderr.splitlines() if l.startswith("evray: warning:")]
    T.check(len(lines) == 1 and what in lines[0], f"{name}: render warns once on stderr: {r.stderr.strip()}")
    # --strict: an error naming it, exit non-zero, no run folder
    d = os.path.join(tmp, "strict_" + name)
    r = T.run("render", A[name], "-o", d, "--strict", "--quiet", expect=None)
    T.check(r.returncode != 0 and len(r.stderr.strip().splitlines()) == 1 and what in r.stderr,
            f"{name}: --strict fails with one line naming it ({r.returncode}: {r.stderr.strip()})")
    T.check(not os.path.exists(d), f"{name}: --strict leaves nothing behind")
    r = info(A[name], "--strict", expect=None)
    T.check(r.returncode != 0 and what in r.stderr, f"{name}: info --strict fails too")

# ---- quantized meshes at their true size ----
for name in ("quantized_short", "quantized_short_glb", "quantized_byte"):
    p = info(A[name])
    lo, hi = bounds(p.stdout)
    T.check(all(abs(a - b) < 1e-4 for a, b in zip(lo + hi, [-0.5, -0.5, 0, 0.5, 0.5, 0])),
            f"{name}: world bounds (-0.5 -0.5 0) to (0.5 0.5 0) (got {lo} to {hi})")
    T.check(not warnings_of(p.stdout), f"{name}: no warning")
    pfm = os.path.join(tmp, name + ".pfm")
    T.run("still", A[name], "-o", pfm, "--res", "64x64", "--quiet")
    w, h, px = T.read_pfm(pfm)
    on = [i for i in range(w * h) if px[3 * i] > 0.5]
    xs, ys = [i % w for i in on], [i // w for i in on]
    # the quad spans the middle half of the view: columns and rows 16 .. 47
    T.check(len(on) == 32 * 32 and (min(xs), max(xs), min(ys), max(ys)) == (16, 47, 16, 47),
            f"{name}: renders as the middle 32x32 pixels ({len(on)} lit, x {min(xs, default=-1)}..{max(xs, default=-1)})")

# ---- GPU instancing: one instance per entry ----
for name in ("instanced", "instanced_glb"):
    p = info(A[name])
    m = re.search(r"instances: (\d+)", p.stdout)
    T.check(m and int(m.group(1)) == 125, f"{name}: 125 instances ({m.group(0) if m else p.stdout})")
    lo, hi = bounds(p.stdout)
    T.check(all(abs(a - b) < 1e-4 for a, b in zip(lo + hi, [-0.65, -0.65, -1.65, 0.65, 0.65, -0.35])),
            f"{name}: the grid's bounds (got {lo} to {hi})")
    T.check(not warnings_of(p.stdout), f"{name}: no warning (the extension is read)")

# ---- points and lines: named ----
lines = os.path.join(tmp, "lines.gltf")
import json  # noqa: E402
with open(A["quantized_byte"]) as f:
    doc = json.load(f)
prim = dict(doc["meshes"][0]["primitives"][0], mode=1)
doc["meshes"][0]["primitives"].append(prim)
with open(lines, "w") as f:
    json.dump(doc, f)
w = warnings_of(info(lines).stdout)
T.check(len(w) == 1 and "3 lines" in w[0] and "not rendered" in w[0], f"lines left out are named: {w}")

# ---- vertex colours: named (a normalized UNSIGNED_BYTE COLOR_0, dequantized on the way) ----
g = import_assets.Doc()
m = g.mesh("painted", {"POSITION": g.accessor(import_assets.FLOAT, import_assets.QUAD, minmax=True),
                       "COLOR_0": g.accessor(import_assets.UBYTE, [(255, 0, 0, 255)] * 4, normalized=True)},
           import_assets.QUAD_TRIS, g.material(import_assets.WHITE))
g.nodes.append({"name": "painted", "mesh": m})
w = warnings_of(info(g.write(tmp, "colours")).stdout)
T.check(len(w) == 1 and "vertex colours" in w[0] and "painted" in w[0], f"vertex colours are named: {w}")

# ---- exact durations ----
p = info(A["odd_clip"])
m = re.search(r"animation: \S+ s to (\S+) s", p.stdout)
c = re.search(r"duration (\S+) s", p.stdout)
T.check(m is not None and c is not None, "info prints the animation's range and the clip's duration")
if m and c:
    import struct  # noqa: E402
    # the file's float32 key; Assimp keeps times in milliseconds, so evray's end may differ from it
    # in the last bits: what matters is that the print gives back evray's end exactly, which the
    # render's check (start + duration <= end) then accepts, and a longer duration does not
    end = struct.unpack("<f", struct.pack("<f", 41 / 12))[0]
    T.check(m.group(1) == c.group(1) and abs(float(m.group(1)) - end) < 1e-6,
            f"printed {m.group(1)} and {c.group(1)} are the clip's end {end!r}")
    for k, printed in enumerate((m.group(1), c.group(1))):
        d = os.path.join(tmp, f"duration{k}")
        r = T.run("render", A["odd_clip"], "-o", d, "--duration", printed, "--res", "16x12", "--fps", "4",
                  "--samples-per-frame", "1", "--no-preview", "--format", "npy", "--quiet", expect=None)
        T.check(r.returncode == 0, f"render --duration {printed} (as info prints it) is accepted: {r.stderr.strip()}")
    longer = repr(float(m.group(1)) + 1e-4)
    r = T.run("render", A["odd_clip"], "-o", os.path.join(tmp, "longer"), "--duration", longer, "--quiet",
              expect=None)
    T.check(r.returncode != 0 and "beyond the end" in r.stderr, f"--duration {longer} is past the end: refused")
T.finish("test_import_robust")
