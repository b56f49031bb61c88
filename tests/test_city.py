"""The city scene (thousands of instances of a dozen shared building meshes), static instances
instanced rather than baked past EVR_STATIC_BAKE_LIMIT (same events as baking), and
evray bench --sweep triangles|instances at tiny sizes (CSV and PNG)."""
import csv
import os
import re
import struct

import evrtest as T

tmp = T.tmpdir()


def png_size(path):
    with open(path, "rb") as f:
        data = f.read(24)
    T.check(data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", f"{path}: a PNG")
    return struct.unpack(">II", data[16:24])


def expect_error(args, what):
    p = T.run(*args, expect=None)
    lines = [l for l in p.stderr.splitlines() if l.strip()]
    T.check(p.returncode > 0, f"{what}: non-zero exit without a crash (got {p.returncode})")
    T.check(len(lines) == 1 and lines[0].startswith("evray: error: "), f"{what}: one error line (got {lines!r})")


def render(args, env=None):
    """Renders into a fresh folder (npy events) with EVR_STATIC_BAKE_LIMIT set to env (None:
    unset); returns the events file's bytes."""
    d = os.path.join(tmp, f"run{len(os.listdir(tmp))}")
    old = os.environ.pop("EVR_STATIC_BAKE_LIMIT", None)
    if env is not None:
        os.environ["EVR_STATIC_BAKE_LIMIT"] = env
    try:
        T.run(*args, "-o", d, "--format", "npy", "--no-preview", "--quiet", "--backend", "cpu")
    finally:
        os.environ.pop("EVR_STATIC_BAKE_LIMIT", None)
        if old is not None:
            os.environ["EVR_STATIC_BAKE_LIMIT"] = old
    return d, open(os.path.join(d, "events.npy"), "rb").read()


# the scene: listed, exported with each building mesh stored once
T.check("city" in T.run("demo", "--list").stdout.split(), "city is listed")
glb = os.path.join(tmp, "city.glb")
T.run("demo", "--scene", "city", "--export", glb)
size = os.path.getsize(glb)
T.check(size < 8 << 20, f"city.glb stores each mesh once ({size} bytes)")
info = T.run("info", glb).stdout
m = re.search(r"instances: (\d+) \((\d+) triangles in the scene\)", info)
T.check(m is not None and int(m.group(1)) > 4000 and int(m.group(2)) > 10_000_000,
        f"city: thousands of instances, millions of triangles ({m.group(0) if m else info})")
m = re.search(r"meshes: (\d+), \d+ vertices, (\d+) triangles", info)
T.check(m is not None and 8 <= int(m.group(1)) <= 17 and int(m.group(2)) < 200_000,
        f"city: a dozen meshes, their triangles stored once ({m.group(0) if m else info})")

# renders on the CPU at a small size (17M instanced triangles: instanced, set up in well under a second)
d, city = render(["demo", "--scene", "city", "--res", "64x48", "--duration", "0.1"])
T.check(T.load_run_json(d)["stats"]["events"] > 0, "city: events in the first 0.1 s")

# instancing the static instances gives the events baking gives: byte-identical where the static
# nodes have no rotation (eye, square, disk: identity transforms), nearly so otherwise
for name in ("eye", "square", "disk"):
    _, baked = render(["demo", "--scene", name, "--res", "48x36", "--duration", "0.3"])
    _, inst = render(["demo", "--scene", name, "--res", "48x36", "--duration", "0.3"], env="0")
    T.check(baked == inst and len(baked) > 128, f"{name}: instanced static meshes give the baked events")
db, _ = render(["demo", "--scene", "cornell", "--res", "48x36", "--duration", "0.3"])
di, _ = render(["demo", "--scene", "cornell", "--res", "48x36", "--duration", "0.3"], env="0")
p = T.run("compare", os.path.join(db, "events.npy"), os.path.join(di, "events.npy"))
m = re.search(r"F1 ([0-9.]+)", p.stdout)
T.check(m is not None and float(m.group(1)) > 0.98, f"cornell: instanced ~ baked (rotated box; {p.stdout.strip()})")
# the city forced the other way (baked: 17M triangles in one tree, slow) is too big for a test;
# the sweep's smallest city (64 buildings, 320k triangles) is baked by default and compared below

# sweeps, tiny: 64x48, 0.05 s (2 frames of 10 samples per pixel)
out = os.path.join(tmp, "sweep")
os.makedirs(out)
T.run("bench", "--sweep", "triangles", "--sweep-max-detail", "2", "--res", "64x48", "--duration", "0.05",
      "--backend", "cpu", "-o", out)
with open(os.path.join(out, "sweep_triangles.csv")) as f:
    rows = list(csv.DictReader(f))
T.check(len(rows) == 2 and [int(r["detail"]) for r in rows] == [1, 2], f"sweep triangles: details 1, 2 ({rows})")
q = [int(r["triangles"]) for r in rows]
T.check(q[1] > 3 * q[0] and q[0] > 10_000_000, f"sweep triangles: the triangles grow as detail^2 ({q})")
T.check(all(int(r["buildings"]) == 4096 and int(r["samples"]) == 64 * 48 * 10 * 2 for r in rows),
        "sweep triangles: 4096 buildings, samples = pixels x 10 x 2")
T.check(all(float(r["ns_per_sample"]) > 0 and float(r["samples_per_s"]) > 0 and float(r["load_s"]) > 0
            for r in rows), "sweep triangles: positive times")
T.check(rows[0]["events"] == rows[1]["events"], "sweep triangles: finer tessellation, same shapes, same events")
T.check(png_size(os.path.join(out, "sweep_triangles.png")) == (800, 480), "sweep triangles: an 800x480 plot")

T.run("bench", "--sweep", "instances", "--sweep-max-buildings", "256", "--res", "64x48", "--duration", "0.05",
      "--backend", "cpu", "-o", out)
with open(os.path.join(out, "sweep_instances.csv")) as f:
    rows = list(csv.DictReader(f))
T.check([int(r["buildings"]) for r in rows] == [64, 256] and [int(r["instances"]) for r in rows] == [65, 257],
        f"sweep instances: 64 and 256 buildings plus the ground ({rows})")
T.check(int(rows[1]["scene_triangles"]) > int(rows[0]["scene_triangles"]) and
        rows[0]["mesh_triangles"] == rows[1]["mesh_triangles"], "sweep instances: more instances of the same meshes")
T.check(all(float(r["ns_per_sample"]) > 0 for r in rows), "sweep instances: positive times")
T.check(png_size(os.path.join(out, "sweep_instances.png")) == (800, 480), "sweep instances: an 800x480 plot")
inst_events = int(rows[0]["events"])

# the 64-building city baked (the sweep instances unless EVR_STATIC_BAKE_LIMIT is set): nearly the same
# events (the quarter-turned buildings differ in float rounding only)
out2 = os.path.join(tmp, "sweep_baked")
os.makedirs(out2)
os.environ["EVR_STATIC_BAKE_LIMIT"] = "100000000"
T.run("bench", "--sweep", "instances", "--sweep-max-buildings", "64", "--res", "64x48", "--duration", "0.05",
      "--backend", "cpu", "-o", out2)
del os.environ["EVR_STATIC_BAKE_LIMIT"]
with open(os.path.join(out2, "sweep_instances.csv")) as f:
    baked_events = int(list(csv.DictReader(f))[0]["events"])
T.check(abs(baked_events - inst_events) <= max(5, inst_events // 200),
        f"city, 64 buildings: baked {baked_events} ~ instanced {inst_events} events")

expect_error(["bench", "--sweep", "triangles", "--scene", "eye"], "sweep triangles grows the city itself")
expect_error(["bench", "--sweep", "instances", "--sweep-max-buildings", "10", "--duration", "0.05"],
             "sweep instances: nothing fits")
T.finish("test_city")
