"""Adaptive per-pixel sampling (--sampling adaptive, core/adaptive.h): on the moving square its
events match the analytic crossings at least as well as uniform sampling, with fewer samples; a
static scene takes one sample per pixel per --max-dt; sensor noise keeps its set rates; the same
seed gives the same events for any thread count; --no-skip changes nothing; bad option values fail
with one line and exit 2. On the CPU and (where a GPU is usable) on CUDA."""
import json
import math
import os

import numpy as np

import evrtest as T
import gltf_build

tmp = T.tmpdir()
runs = 0
probe = T.run("demo", "--scene", "square", "-o", os.path.join(tmp, "probe"), "--res", "16x16", "--duration", "0.1",
              "--backend", "cuda", "--quiet", "--no-preview", expect=None)
backends = ["cpu"] + (["cuda"] if probe.returncode == 0 else [])
print("backends:", backends)


def run(*args, cmd=("demo",)):
    global runs
    runs += 1
    out = os.path.join(tmp, f"run{runs}")
    T.run(*cmd, *args, "-o", out, "--format", "npy", "--no-preview", "--quiet")
    return np.load(os.path.join(out, "events.npy")), T.load_run_json(out), out


def near(value, expect, rel):
    return abs(value - expect) <= rel * abs(expect)


# ---- the moving square against its analytic crossings (as tests/test_square.py) ----
W = H = 64
C_ON, C_OFF = 0.3, 0.25
FPS, N = 30, 10
count_on = int(math.floor(2.0 / C_ON))
count_off = int(math.floor(count_on * C_ON / C_OFF))


def square_errors(ev):
    """(pixels checked, pixels with the wrong event count, largest |t - analytic| in seconds, silent
    elsewhere)."""
    checked, bad, errors, silent = T.square_crossings(ev, W, H, C_ON, C_OFF)
    return checked, bad, max(errors, default=0.0), silent


sq = ["--scene", "square", "--res", f"{W}x{H}", "--pos-thres", C_ON, "--neg-thres", C_OFF, "--fps", FPS,
      "--log-floor", "1e-4"]
for backend in backends:
    ev_u, js_u, _ = run(*sq, "--samples-per-frame", N, "--backend", backend)
    ev_a, js_a, _ = run(*sq, "--sampling", "adaptive", "--backend", backend)
    cu, bu, wu, su = square_errors(ev_u)
    ca, ba, wa, sa = square_errors(ev_a)
    su_s, sa_s = js_u["stats"], js_a["stats"]
    print(f"{backend} square: uniform {su_s['samples']} samples, worst |dt| {wu * 1e6:.0f} us, {bu} of {cu} pixels "
          f"miscounted; adaptive {sa_s['samples']} samples ({sa_s['samples_per_pixel_per_second']:.1f} per pixel per s), "
          f"worst |dt| {wa * 1e6:.0f} us, {ba} of {ca} miscounted")
    T.check(cu > 500 and ca == cu, f"{backend}: enough pixels crossed")
    T.check(ba == 0, f"{backend} adaptive: every crossed pixel has {count_on} ON and {count_off} OFF events ({ba} differ)")
    T.check(wa <= wu, f"{backend} adaptive: crossings at least as close to the analytic times as uniform "
                      f"({wa * 1e6:.0f} vs {wu * 1e6:.0f} us)")
    T.check(wa <= 2e-4, f"{backend} adaptive: every crossing within 200 us of the analytic time ({wa * 1e6:.0f} us)")
    T.check(sa, f"{backend} adaptive: no events where nothing moves")
    T.check(sa_s["samples"] <= su_s["samples"], f"{backend} adaptive: no more samples than uniform")
    T.check(sa_s["samples_traced"] == sa_s["samples"], f"{backend} adaptive: every sample taken is traced")
    T.check(js_a["config"]["sampling"] == "adaptive" and js_u["config"]["sampling"].startswith("uniform"),
            f"{backend}: sampling in run.json")
    T.check(near(su_s["samples_per_pixel_per_second"], FPS * N, 1e-6), f"{backend}: uniform samples per pixel per s")
    # --samples-per-frame alone selects uniform sampling, the same as --sampling uniform (and equal
    # to brute force: tests/test_skip.py)
    ev_x, _, _ = run(*sq, "--samples-per-frame", N, "--backend", backend, "--sampling", "uniform")
    ev_b, _, _ = run(*sq, "--samples-per-frame", N, "--backend", backend, "--sampling", "uniform", "--no-skip")
    T.check(ev_x.tobytes() == ev_u.tobytes() == ev_b.tobytes(), f"{backend}: --samples-per-frame alone is --sampling uniform")
    # --no-skip does not change adaptive sampling
    ev_n, _, _ = run(*sq, "--sampling", "adaptive", "--backend", backend, "--no-skip")
    T.check(ev_n.tobytes() == ev_a.tobytes(), f"{backend} adaptive: --no-skip changes nothing")

# ---- a static scene samples every --max-dt ----
quad = os.path.join(tmp, "static.gltf")
T.quad_gltf(quad)
for backend in backends:
    for max_dt in (0.01, None):
        extra = ["--max-dt", max_dt] if max_dt else []
        ev, js, _ = run(quad, "--res", "48x32", "--duration", "0.5", "--sampling", "adaptive", "--backend", backend,
                        *extra, cmd=("render",))
        s = js["stats"]
        expect = 1.0 / (max_dt if max_dt else 1.0 / js["config"]["fps"])
        print(f"{backend} static, max-dt {max_dt}: {s['samples_per_pixel_per_second']:.2f} samples per pixel per s "
              f"(expected about {expect:.1f}), {len(ev)} events")
        T.check(near(s["samples_per_pixel_per_second"], expect, 0.05) and
                s["samples_per_pixel_per_second"] <= expect * 1.05,
                f"{backend} static: about one sample per pixel per max-dt")
        T.check(len(ev) == 0, f"{backend} static ideal: no events")
    # segments shorter than --min-dt: every pixel still starts and samples every min-dt
    ev, js, _ = run(quad, "--res", "32x32", "--duration", "0.3", "--fps", "2000", "--min-dt", "0.001", "--sampling",
                    "adaptive", "--backend", backend, cmd=("render",))
    spps = js["stats"]["samples_per_pixel_per_second"]
    T.check(near(spps, 1000.0, 0.01), f"{backend} static, 0.5 ms segments, min-dt 1 ms: {spps} samples per pixel per s")
    T.check(js["config"]["max_dt"] == 0.001, f"{backend}: max_dt raised to min_dt in run.json")

# ---- sensor noise keeps its rates with long sample spans (as tests/test_sensor.py) ----
R, D, NP = 2.0, 3.0, 32 * 32
ev, _, _ = run(quad, "--res", "32x32", "--duration", D, "--sampling", "adaptive", "--leak-rate-hz", R, cmd=("render",))
on, off = int(np.sum(ev["p"] == 1)), int(np.sum(ev["p"] == 0))
print(f"adaptive, leak {R} Hz: {on / (NP * D):.3f} ON events/s per pixel, {off} OFF")
T.check(near(on / (NP * D), R, 0.1), f"adaptive: leak rate {on / (NP * D):.3f} within 10% of {R}")
T.check(off == 0, "adaptive: leak makes only ON events")
R = 3.0
ev, _, _ = run(quad, "--res", "32x32", "--duration", D, "--sampling", "adaptive", "--shot-noise-rate-hz", R,
               "--full-intensity", 1e9, cmd=("render",))
rate, on_share = len(ev) / (NP * D), float(np.mean(ev["p"] == 1))
print(f"adaptive, shot noise {R} Hz, black: {rate:.3f} events/s per pixel, ON share {on_share:.3f}")
T.check(near(rate, R, 0.1), f"adaptive: shot noise rate {rate:.3f} within 10% of {R}")
T.check(abs(on_share - 0.5) < 0.03, f"adaptive: shot noise half ON ({on_share:.3f})")

# ---- determinism: same seed, same events, any thread count (and a noisy sensor) ----
for backend in backends:
    base = ["--scene", "square", "--sensor", "davis346", "--res", "64x48", "--duration", "0.5", "--seed", "5",
            "--sampling", "adaptive", "--backend", backend]
    ref = run(*base)[0].tobytes()
    T.check(len(ref) > 0, f"{backend} determinism: events")
    for threads in (["--threads", "1"], ["--threads", "2"], ["--threads", "3"], []):
        if backend == "cuda" and threads:
            continue
        T.check(run(*base, *threads)[0].tobytes() == ref, f"{backend} adaptive: identical events {threads or 'again'}")

# ---- seen in a mirror: a sample whose path goes past its primary hit counts every moving thing ----
# An emissive square slides behind the camera, seen only in a flat mirror facing it: its events
# against uniform sampling at 100 per frame (adaptive sampling that bounded motion by the primary
# and shadow rays alone sampled these pixels every --max-dt: F1 0.07 at 1 ms).
mirror = os.path.join(tmp, "mirror.gltf")
g = gltf_build.Gltf()
g.camera("cam", translation=[0, 0, 3])
chrome = g.material({"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1.0,
                                              "roughnessFactor": 0.0}})
dim = g.material({"emissiveFactor": [0.1, 0.1, 0.1], "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}})
bright = g.material({"emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}})
g.mesh_node("mirror", *gltf_build.rect(-3, 3, -3, 3, 0), chrome)
g.mesh_node("wall", *gltf_build.rect(-8, 8, -8, 8, 6.5, facing=-1), dim)
sq = g.mesh_node("square", *gltf_build.rect(-0.4, 0.4, -0.4, 0.4, 6, facing=-1), bright, translation=[-2, 0, 0])
g.animation([(sq, "translation", [0.0, 1.0], [[-2, 0, 0], [2, 0, 0]])])
g.write(mirror)
for backend in backends:
    common = ["--res", "48x48", "--duration", "1", "--backend", backend]
    ref = run(*common, "--samples-per-frame", "100", cmd=("render", mirror))[2]
    ad = run(*common, "--sampling", "adaptive", cmd=("render", mirror))[2]
    r = json.loads(T.run("compare", os.path.join(ref, "events.npy"), os.path.join(ad, "events.npy"),
                         "--tol-us", "1000", "--json").stdout)
    print(f"{backend} adaptive, a square seen in a mirror: F1 {r['f1']:.3f} at 1 ms ({r['ref_on'] + r['ref_off']} events)")
    T.check(r["ref_on"] > 200 and r["f1"] >= 0.95, f"{backend} adaptive through a mirror: {r}")

# ---- bad values: one line, exit 2 ----
for bad in (["--sampling", "sometimes"], ["--adapt-frac", "0"], ["--adapt-frac", "1.5"], ["--adapt-frac", "x"],
            ["--min-dt", "0"], ["--min-dt", "-1"], ["--max-dt", "0"], ["--max-dt", "2"],
            ["--sampling", "adaptive", "--min-dt", "0.01", "--max-dt", "0.001"]):
    p = T.run("demo", "--scene", "square", "--res", "16x16", "--duration", "0.1", "-o", os.path.join(tmp, "bad"),
              "--quiet", "--no-preview", *bad, expect=None)
    lines = p.stderr.strip().splitlines()
    T.check(p.returncode == 2 and len(lines) == 1, f"{' '.join(bad)}: exit {p.returncode}, {len(lines)} lines: {p.stderr!r}")
T.finish("test_adaptive")
