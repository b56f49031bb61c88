"""Deforming meshes end to end against analytic ground truth (assets from tests/deform_assets.py).

morph_slide, skin_slide and skin_slide8: an emissive quad (radiance 1) on a black background whose
right edge moves at x = -0.5 + t on the plane z = -1, by a morph target, by a joint (the skinned
mesh's node, placed far away, must be ignored) and by two joints holding half the weight each
through a second influence set (JOINTS_1/WEIGHTS_1). The camera at the origin sees x in
[-0.5, 0.5] there (tan(yfov/2) = 0.5), so the edge crosses the centre of pixel column c at
t_c = (2c + 1) / (2 W): every pixel fires only ON events, the same number in every pixel, all
within one sample interval of t_c; no OFF events. bend_cylinder: a skinned cylinder whose second
half turns 90 degrees: events only where the turning half sweeps, none on the fixed half.
Change-driven sampling is exact: the same events, bit for bit, with --no-skip."""
import hashlib
import os
import sys

import numpy as np

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import deform_assets  # noqa: E402

tmp = T.tmpdir()
assets = os.path.join(tmp, "assets")
os.makedirs(assets, exist_ok=True)
deform_assets.write_all(assets)

W = H = 48
FPS, N = 30, 8
DT = 1.0 / (FPS * N)


def render(name, extra=()):
    out = os.path.join(tmp, name + "-" + "-".join(a.strip("-") for a in extra))
    T.run("render", os.path.join(assets, name + ".gltf"), "-o", out, "--res", f"{W}x{H}", "--fps", FPS,
          "--samples-per-frame", N, "--sampling", "uniform", "--pos-thres", 0.3, "--neg-thres", 0.3,
          "--duration", 1.0, "--format", "npy", "--no-preview", "--quiet", *extra)
    path = os.path.join(out, "events.npy")
    with open(path, "rb") as f:
        digest = hashlib.md5(f.read()).hexdigest()
    return np.load(path), digest


for name in ("morph_slide", "skin_slide", "skin_slide8"):
    ev, digest = render(name)
    T.check(len(ev) > 0, f"{name}: events")
    T.check(int(np.sum(ev["p"] == 0)) == 0, f"{name}: no OFF events ({int(np.sum(ev['p'] == 0))})")
    counts = np.zeros((H, W), dtype=np.int64)
    np.add.at(counts, (ev["y"].astype(np.int64), ev["x"].astype(np.int64)), 1)
    T.check(int(counts.min()) >= 1 and int(counts.min()) == int(counts.max()),
            f"{name}: every pixel the same number of ON events ({int(counts.min())}..{int(counts.max())})")
    tc = (2.0 * ev["x"].astype(np.float64) + 1.0) / (2.0 * W)
    err = np.abs(ev["t"].astype(np.float64) * 1e-6 - tc)
    late = int(np.sum(err > DT + 2e-6))
    T.check(late == 0, f"{name}: events within one sample interval of the edge ({late} of {len(ev)} off, "
            f"worst {err.max() * 1e6:.1f} us)")
    _, digest_brute = render(name, ("--no-skip",))
    T.check(digest == digest_brute, f"{name}: the same events with --no-skip")

# The cylinder: camera at (1, 0.5, 4) looking along -Z; the fixed half is x in [0, 0.8] (weights
# all on the fixed joint), the turning half sweeps the quarter disc of radius 1.1 about (1, 0).
ev, digest = render("bend_cylinder")
T.check(len(ev) > 1000, f"bend_cylinder: events ({len(ev)})")
# image x of world X on z = 0: W/2 + (X - 1) * fpx, pixels per unit fpx = (H/2) / (tan(yfov/2) * 4)
fpx = (H / 2) / (0.5 * 4.0)
x_img = ev["x"].astype(np.float64) + 0.5
X = 1.0 + (x_img - W / 2) / fpx
fixed = int(np.sum(X < 0.75))
T.check(fixed == 0, f"bend_cylinder: no events left of the bending zone ({fixed})")
_, digest_brute = render("bend_cylinder", ("--no-skip",))
T.check(digest == digest_brute, "bend_cylinder: the same events with --no-skip")
T.finish("test_deform")
