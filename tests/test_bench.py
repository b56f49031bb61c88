"""evray bench --sweep (CSV and PNG), --suite seed (shortened), the GI line of the report, and
evray plot (rate and heat map PNGs; bad input gives one error line)."""
import csv
import json
import os
import struct
import zlib

import evrtest as T

tmp = T.tmpdir()


def png_size(path):
    """Width and height from a PNG's IHDR, after checking the signature and the IHDR's CRC."""
    with open(path, "rb") as f:
        data = f.read()
    T.check(data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: PNG signature")
    length, kind = struct.unpack(">I4s", data[8:16])
    T.check(kind == b"IHDR" and length == 13, f"{path}: IHDR first")
    body = data[16:16 + 13]
    T.check(struct.unpack(">I", data[29:33])[0] == zlib.crc32(b"IHDR" + body), f"{path}: IHDR CRC")
    w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
    T.check(depth == 8 and ctype == 2, f"{path}: RGB8 (got depth {depth}, colour type {ctype})")
    # the image data inflates to the expected size: one filter byte per row + 3 bytes per pixel
    pos, idat = 8, b""
    while pos < len(data):
        n, k = struct.unpack(">I4s", data[pos:pos + 8])
        if k == b"IDAT":
            idat += data[pos + 8:pos + 8 + n]
        pos += 12 + n
    T.check(len(zlib.decompress(idat)) == h * (1 + 3 * w), f"{path}: image data of {w}x{h}")
    return w, h


def expect_error(args, what):
    p = T.run(*args, expect=None)
    lines = [l for l in p.stderr.splitlines() if l.strip()]
    T.check(p.returncode > 0, f"{what}: non-zero exit without a crash (got {p.returncode})")
    T.check(len(lines) == 1 and lines[0].startswith("evray: error: "), f"{what}: one error line (got {lines!r})")


# one row with GI: the text report says how many photon paths were traced and how many reused their
# trail, and those numbers are the JSON's; a row without GI has no such line
p = T.run("bench", "--scene", "cornell", "--backend", "cpu", "--res", "48x36", "--duration", "0.3", "--gi", "photon")
gi_line = [l for l in p.stdout.splitlines() if l.startswith("global illumination:")]
js = json.loads(T.run("bench", "--scene", "cornell", "--backend", "cpu", "--res", "48x36", "--duration", "0.3", "--gi",
                      "photon", "--json").stdout)
T.check(len(gi_line) == 1 and f"{js['photons_traced']} photon paths traced, {js['photons_reused']} reused" in gi_line[0]
        and js["photons_reused"] > 0, f"bench GI: photon paths traced and reused reported ({gi_line})")
p = T.run("bench", "--scene", "cornell", "--backend", "cpu", "--res", "48x36", "--duration", "0.1")
T.check("global illumination:" not in p.stdout, "bench without GI: no photon line")

# the set-up's phases: one line, the JSON's keys; the phases add up to no more than the whole
setup = [l for l in p.stdout.splitlines() if l.startswith("set-up ")]
T.check(len(setup) == 1 and "load" in setup[0] and "BVH" in setup[0] and "first plan" in setup[0],
        f"bench: one set-up line ({setup})")
keys = ("load_seconds", "load_gltf_checks_seconds", "load_assimp_seconds", "load_materials_seconds",
        "load_meshes_seconds", "load_tangents_seconds", "setup_host_seconds", "setup_bvh_seconds",
        "first_plan_seconds")
T.check(all(k in js and js[k] >= 0 for k in keys), "bench --json: the set-up's phases")
T.check(js["load_seconds"] > 0 and js["load_assimp_seconds"] + js["load_gltf_checks_seconds"] +
        js["load_materials_seconds"] + js["load_meshes_seconds"] <= js["load_seconds"] + 1e-3
        and js["load_tangents_seconds"] <= js["load_meshes_seconds"] + 1e-6
        and 0 < js["setup_bvh_seconds"] <= js["setup_seconds"] + 1e-6,
        f"bench --json: the phases inside the whole ({ {k: js[k] for k in keys} })")

# --sweep res, tiny: 80x60 and 160x120 over 0.05 s
out = os.path.join(tmp, "sweep")
os.makedirs(out)
T.run("bench", "--sweep", "res", "--sweep-max-res", "160x120", "--duration", "0.05", "--backend", "cpu", "-o", out)
with open(os.path.join(out, "sweep_res.csv")) as f:
    rows = list(csv.DictReader(f))
T.check(len(rows) == 2, f"sweep res: 2 rows up to 160x120 (got {len(rows)})")
q = [float(r["pixels"]) for r in rows]
T.check(q == sorted(q) and len(set(q)) == len(q), f"sweep res: the quantity grows ({q})")
T.check(all(float(r["wall_s"]) > 0 and float(r["ns_per_sample"]) > 0 and float(r["samples_per_s"]) > 0 for r in rows),
        "sweep res: positive times")
T.check(all(int(r["samples"]) == int(r["width"]) * int(r["height"]) * 10 * 2 for r in rows),
        "sweep res: samples = pixels x 10 per frame x 2 frames (0.05 s at 30 fps)")
T.check(png_size(os.path.join(out, "sweep_res.png")) == (800, 480), "sweep res: an 800x480 plot")
expect_error(["bench", "--sweep", "bogus"], "unknown sweep")
expect_error(["bench", "--sweep", "res", "--sweep-max-res", "10x10", "--duration", "0.05"], "sweep res: nothing fits")

# --suite seed, shortened and small
p = T.run("bench", "--suite", "seed", "--res", "48x32", "--start", "0.27", "--duration", "0.05", "--backend", "cpu", "--json")
suite = [r for r in json.loads(p.stdout) if r["row"] != "end"]
T.check([r["row"] for r in suite] == ["Standard", "Slow", "Extra", "Photon"], f"suite rows {[r['row'] for r in suite]}")
std, slow, extra, photon = suite
T.check(all(abs(r["simulated_seconds"] - 0.05) < 1e-6 for r in suite), "suite: every row simulates --duration")
T.check(abs(std["temporal_resolution_us"] - 1e6 / 300) < 0.1, "suite Standard: 3333 us between a pixel's samples")
T.check(abs(slow["temporal_resolution_us"] - 1e6 / 3000) < 0.1 and abs(extra["temporal_resolution_us"] - 1e6 / 3000) < 0.1,
        "suite Slow and Extra: 333 us")
T.check(all(r["wall_seconds"] > 0 and r["samples_per_second"] > 0 for r in suite[:3]), "suite: positive times")
T.check(photon["events"] > 0 and photon["backend"] == "cpu" and photon["samples_per_second"] > 0,
        "suite Photon: GI on the CPU backend")
p = T.run("bench", "--suite", "seed", "--res", "48x32", "--start", "0.27", "--duration", "0.05", "--backend", "cuda", "--json",
          expect=None)
if p.returncode == 0:   # a GPU: every row, Photon included (the GPU photon pass)
    rows = [r for r in json.loads(p.stdout) if r["row"] != "end"]
    T.check([r["row"] for r in rows] == ["Standard", "Slow", "Extra", "Photon"] and
            all(r.get("backend") == "cuda" for r in rows) and rows[3]["events"] > 0,
            f"suite table on CUDA: every row, Photon on the GPU ({[r['row'] for r in rows]})")
expect_error(["bench", "--suite", "seed", "--samples-per-frame", "5"], "suite with --samples-per-frame")
expect_error(["bench", "--suite", "other"], "unknown suite")

# plot: a small run's events, as HDF5 and text
run = os.path.join(tmp, "run")
T.run("demo", "--scene", "eye", "--res", "64x48", "--duration", "0.5", "--backend", "cpu", "--no-preview", "--format", "h5,txt",
      "-o", run, "-q")
rate, heat = os.path.join(tmp, "rate.png"), os.path.join(tmp, "heat.png")
T.run("plot", os.path.join(run, "events.h5"), "-o", rate, "--bin-ms", "2", "--heatmap", heat)
T.check(png_size(rate) == (1000, 420), "plot: a 1000x420 rate plot")
hw, hh = png_size(heat)
T.check(hw >= 64 and hh >= 48, f"plot: heat map at least the sensor's size (got {hw}x{hh})")
rate2 = os.path.join(tmp, "rate2.png")
T.run("plot", os.path.join(run, "events.txt"), "-o", rate2, "--size", "400x300")
T.check(png_size(rate2) == (400, 300), "plot: text events, --size")
expect_error(["plot", os.path.join(tmp, "missing.h5"), "-o", os.path.join(tmp, "x.png")], "plot: missing file")
T.check(not os.path.exists(os.path.join(tmp, "x.png")), "plot: nothing written for a missing file")
expect_error(["plot"], "plot: no file")
expect_error(["plot", os.path.join(run, "events.h5"), "--bin-ms", "0"], "plot: bad --bin-ms")

T.finish("test_bench")
