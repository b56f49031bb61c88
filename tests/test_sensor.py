"""The sensor model end to end through the command line: noise rates over a static scene, hot
pixels, refractory period and timestamp resolution with noise on, determinism across thread
counts, and the --sensor presets (checked against the table in docs/sensors.md) with flags
overriding them."""
import json
import os
import shutil

import numpy as np

import evrtest as T

tmp = T.tmpdir()
static = os.path.join(tmp, "static.gltf")
T.quad_gltf(static)
moving = os.path.join(tmp, "moving.gltf")
T.quad_gltf(moving, animated=True)
runs = 0


def render(scene, *args, fmt="npy"):
    global runs
    runs += 1
    out = os.path.join(tmp, f"run{runs}")
    T.run("render", scene, "-o", out, "--format", fmt, "--no-preview", "--quiet", *args)
    ev = np.load(os.path.join(out, "events.npy")) if fmt == "npy" else None
    return ev, T.load_run_json(out), out


def near(value, expect, rel):
    return abs(value - expect) <= rel * abs(expect)


# leak: a static pixel fires ON events at the leak rate, whatever it sees
R, D, N = 2.0, 3.0, 32 * 32
ev, meta, _ = render(static, "--res", "32x32", "--duration", D, "--samples-per-frame", 2, "--leak-rate-hz", R)
on, off = int(np.sum(ev["p"] == 1)), int(np.sum(ev["p"] == 0))
print(f"leak {R} Hz: {on / (N * D):.3f} ON events/s per pixel, {off} OFF")
T.check(near(on / (N * D), R, 0.1), f"leak rate {on / (N * D):.3f} within 10% of {R}")
T.check(off == 0, "leak makes only ON events")

# shot noise: with full brightness far above the scene every pixel counts as black: rate R
R = 3.0
ev, meta, _ = render(static, "--res", "32x32", "--duration", D, "--samples-per-frame", 2, "--shot-noise-rate-hz", R,
                     "--full-intensity", 1e9)
rate, on_share = len(ev) / (N * D), float(np.mean(ev["p"] == 1))
print(f"shot noise {R} Hz, black: {rate:.3f} events/s per pixel, ON share {on_share:.3f}")
T.check(near(rate, R, 0.1), f"shot noise rate {rate:.3f} within 10% of {R}")
T.check(abs(on_share - 0.5) < 0.03, f"shot noise half ON ({on_share:.3f})")
T.check(meta["config"]["shot_noise_rate_hz"] == R, "shot noise rate in run.json")

# ... and darker pixels are noisier: with full brightness tiny, the lit quad (centre) counts as
# full brightness (R/4) and the black background (border) as black (R)
R = 10.0
ev, meta, _ = render(static, "--res", "32x32", "--duration", D, "--samples-per-frame", 2, "--shot-noise-rate-hz", R,
                     "--full-intensity", 1e-6)
d = np.maximum(np.abs(ev["x"].astype(float) - 15.5), np.abs(ev["y"].astype(float) - 15.5))
cx = np.maximum(np.abs(np.arange(32)[None, :] - 15.5), np.abs(np.arange(32)[:, None] - 15.5))
n_in, n_out = int(np.sum(cx < 11)), int(np.sum(cx > 14))
r_in, r_out = np.sum(d < 11) / (n_in * D), np.sum(d > 14) / (n_out * D)
print(f"shot noise {R} Hz: {r_in:.3f} on the lit quad (expected {R / 4}), {r_out:.3f} on the black background")
T.check(near(r_in, R / 4, 0.1), f"bright pixels: a quarter of the shot noise ({r_in:.3f})")
T.check(near(r_out, R, 0.1), f"black pixels: the full shot noise ({r_out:.3f})")

# hot pixels: the expected fraction fires, at its rate, ON only
F, H, D2, N2 = 0.05, 50.0, 2.0, 64 * 64
ev, meta, _ = render(static, "--res", "64x64", "--duration", D2, "--samples-per-frame", 1, "--hot-pixel-fraction", F,
                     "--hot-pixel-rate-hz", H)
hot = len(np.unique(ev["y"].astype(np.int64) * 64 + ev["x"]))
sd = (N2 * F * (1 - F)) ** 0.5
print(f"hot pixels {F} at {H} Hz: {hot} pixels fire (expected {N2 * F:.0f} +- {sd:.0f}), {len(ev) / (hot * D2):.2f} Hz each")
T.check(abs(hot - N2 * F) < 4 * sd, f"hot pixel count {hot} near {N2 * F:.0f}")
T.check(near(len(ev) / (hot * D2), H, 0.1), "hot pixels fire at their rate")
T.check(bool(np.all(ev["p"] == 1)), "hot pixels fire ON events")

# refractory period with every noise on, on a moving scene: no two events of a pixel closer than it
ev, meta, _ = render(moving, "--res", "32x32", "--refractory", 0.002, "--shot-noise-rate-hz", 50, "--hot-pixel-fraction",
                     0.1, "--hot-pixel-rate-hz", 1000, "--leak-rate-hz", 5, "--sigma-thres", 0.03, "--cutoff-hz", 300)
key = ev["y"].astype(np.int64) * 32 + ev["x"]
order = np.lexsort((ev["t"], key))
same = key[order][1:] == key[order][:-1]
gaps = np.diff(ev["t"][order])[same]
print(f"refractory 2 ms, noise on: {len(ev)} events, smallest gap {gaps.min()} us")
T.check(len(ev) > 5000 and gaps.min() >= 2000, f"refractory holds with noise on (smallest gap {gaps.min()} us)")

# timestamps are multiples of the resolution
ev, meta, _ = render(moving, "--res", "32x32", "--time-res", 0.001, "--shot-noise-rate-hz", 20)
T.check(len(ev) > 1000 and bool(np.all(ev["t"] % 1000 == 0)), "timestamps are multiples of --time-res")
T.check(bool(np.all(np.diff(ev["t"]) >= 0)), "quantized events stay sorted")
ev, meta, _ = render(moving, "--res", "32x32", "--time-res", 0.0005, "--time-jitter", 0.002, "--shot-noise-rate-hz", 20)
T.check(len(ev) > 1000 and bool(np.all(ev["t"] % 500 == 0)), "jittered timestamps are multiples of --time-res")
T.check(bool(np.all(np.diff(ev["t"]) >= 0)), "jittered events stay sorted across segments")

# determinism: the same seed gives byte-identical events for any thread count, noise on
noisy = ["--sensor", "davis346", "--res", "64x48", "--duration", "0.3", "--shot-noise-rate-hz", "20",
         "--hot-pixel-fraction", "0.01", "--leak-rate-hz", "2", "--cutoff-hz", "100", "--time-jitter", "2e-5",
         "--format", "npy", "--no-preview", "--quiet", "--backend", "cpu"]
files = []
for th, seed in ((1, 1), (2, 1), (3, 1), (2, 2)):
    out = os.path.join(tmp, f"det{th}-{seed}")
    T.run("demo", "--scene", "eye", "-o", out, "--threads", th, "--seed", seed, *noisy)
    with open(os.path.join(out, "events.npy"), "rb") as f:
        files.append(f.read())
T.check(files[0] == files[1] == files[2], "noise on: identical events for 1, 2 and 3 threads")
T.check(files[0] != files[3], "another seed gives other noise")

# presets: each sets the values of the table in docs/sensors.md; resolution from the preset
keys = {"--pos-thres": "pos_thres", "--neg-thres": "neg_thres", "--sigma-thres": "sigma_thres",
        "--refractory": "refractory", "--cutoff-hz": "cutoff_hz", "--leak-rate-hz": "leak_rate_hz",
        "--leak-jitter": "leak_jitter", "--shot-noise-rate-hz": "shot_noise_rate_hz",
        "--hot-pixel-fraction": "hot_pixel_fraction", "--hot-pixel-rate-hz": "hot_pixel_rate_hz",
        "--time-res": "time_res", "--time-jitter": "time_jitter"}
doc = open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "sensors.md")).read()
lines = doc.splitlines()
top = next(i for i, l in enumerate(lines) if l.startswith("| parameter | flag |"))
header = [c.strip() for c in lines[top].strip("|").split("|")]
rows = []
for line in lines[top + 2:]:
    if not line.startswith("|"):
        break
    rows.append([c.strip().strip("`") for c in line.strip().strip("|").split("|")])
sensors = header[2:]
T.check(sensors == ["ideal", "davis346", "dvxplorer", "prophesee-gen4"], f"preset table columns {sensors}")
T.check(len(rows) == 13, f"preset table has 13 rows ({len(rows)})")
for i, name in enumerate(sensors):
    ev, meta, _ = render(static, "--sensor", name, "--duration", 0.02, "--fps", 50, "--samples-per-frame", 1)
    c = meta["config"]
    T.check(c["sensor"] == name, f"{name}: run.json names the sensor")
    for row in rows:
        flag, want = row[1], row[2 + i]
        if flag == "--res":
            w, h = (346, 260) if want == "(unchanged)" else map(int, want.split("x"))
            T.check(c["width"] == w and c["height"] == h, f"{name}: resolution {c['width']}x{c['height']} is {want}")
        else:
            T.check(abs(c[keys[flag]] - float(want)) <= 1e-6 * abs(float(want)) + 1e-12,
                    f"{name}: {flag} is {c[keys[flag]]}, docs say {want}")

# flags override the preset whatever their order; --res keeps its resolution
ev, meta, d = render(static, "--pos-thres", "0.3", "--sensor", "davis346", "--res", "20x10", "--shot-noise-rate-hz", "0",
                     "--duration", 0.05, fmt="h5")
c = meta["config"]
T.check(c["pos_thres"] == 0.3 and c["neg_thres"] == 0.255, "a flag before --sensor still overrides it")
T.check(c["shot_noise_rate_hz"] == 0 and c["leak_rate_hz"] == 0.1, "a flag after --sensor overrides it, the rest stays")
T.check(c["width"] == 20 and c["height"] == 10, "--res wins over the preset's resolution")
_, _, attrs = T.load_h5(os.path.join(d, "events.h5"))
cfg_attr = json.loads(attrs["config"])
T.check(cfg_attr.get("sensor") == "davis346" and cfg_attr.get("leak_rate_hz") == 0.1, "sensor parameters in the HDF5 config")
ev, meta, _ = render(static, "--sensor", "davis346", "--sensor", "ideal", "--res", "16x16")
T.check(meta["config"]["sensor"] == "ideal" and meta["config"]["sigma_thres"] == 0 and len(ev) == 0,
        "the last --sensor wins; the ideal sensor gives no events on a static scene")
ev, meta, _ = render(static, "--res", "16x16")
T.check(meta["config"]["sensor"] is None and meta["config"]["shot_noise_rate_hz"] == 0, "no --sensor: the ideal sensor")


def expect_error(args, what):
    p = T.run(*args, expect=None)
    lines = [l for l in p.stderr.splitlines() if l.strip()]
    T.check(p.returncode == 2 and len(lines) == 1 and lines[0].startswith("evray: error: "),
            f"{what}: one error line, exit 2 (got {p.returncode}, {lines!r})")


noout = os.path.join(tmp, "never")
expect_error(["render", static, "-o", noout, "--sensor", "davis999"], "unknown sensor")
expect_error(["render", static, "-o", noout, "--time-res", "1.5e-6"], "fractional microsecond resolution")
expect_error(["render", static, "-o", noout, "--shot-noise-rate-hz", "-1"], "negative shot noise")
expect_error(["render", static, "-o", noout, "--hot-pixel-fraction", "2"], "hot fraction above 1")
expect_error(["render", static, "-o", noout, "--sigma-thres", "nan"], "NaN mismatch")
T.check(not os.path.exists(noout), "no run folder left by a bad option")
shutil.rmtree(tmp, ignore_errors=True)
T.finish("test_sensor")
