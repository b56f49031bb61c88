"""The blink scene deforms, end to end on the CPU: its lids by morph targets, its finger by
skinning (src/scene/demo_blink.c). Image regions come from the scene's documented geometry: the
camera at (12, 0, 130) mm looking along -Z with yfov 2 atan(27/120) at 16:9; the eye's opening
spans x in [-11.9, 11.9], y in [-7, 7.5] mm around the eye centre (the origin, skin at z ~ 10-15),
and the lids' eyelash cards reach y = 10.8 (upper, z up to 19) and -10.2 (lower, z up to 16);
the finger stands at x ~ 32 (radius 9) in front of the face (z ~ 30, its tip coming towards the
camera as it bends), lit from the upper left so its shadow falls to its right.
  - evray info lists the finger's skin (3 joints) and the lids' morph targets (2 and 1);
  - during the first blink (0.40-0.70 s) the lid region fires many events, and none outside the
    cornea (which mirrors the moving finger) while the lids rest (before 0.40 s and after 0.70 s, give or take one sample interval: an event's time
    is interpolated between the two samples that straddle its crossing), though the finger keeps
    moving beside them;
  - the finger region fires events all along the finger's height while it bends, and nearly every
    event of the run lies in the lid or finger region (nothing else moves);
  - evray bench measures the scene (samples/s)."""
import json
import os

import numpy as np

import evrtest as T

W, H = 320, 180
TAN = 27.0 / 120.0  # tan(yfov / 2)
ASPECT = 16.0 / 9.0


def project(x, y, z):
    """Pixel column and row of a point (mm) seen by the blink camera."""
    d = 130.0 - z
    return ((x - 12.0) / (d * TAN * ASPECT) + 1.0) / 2.0 * W, (1.0 - y / (d * TAN)) / 2.0 * H


glb = os.path.join(T.tmpdir(), "blink.glb")
T.run("demo", "--scene", "blink", "--export", glb)
text = T.run("info", glb).stdout
T.check("skin" in text and "3 joints" in text, "evray info lists the finger's skin of 3 joints")
T.check("morph" in text, "evray info lists the lids' morph targets")

d = os.path.join(T.tmpdir(), "run")
T.run("demo", "--scene", "blink", "-o", d, "--res", f"{W}x{H}", "--duration", "0.85", "--format", "npy",
      "--samples-per-frame", "10", "--no-preview", "--quiet", "--backend", "cpu")
# Uniform sampling at 30 fps x 10 samples per frame: a pixel's sample interval. The first blink starts and
# ends on segment boundaries (0.40 = 12/30, 0.70 = 21/30 s), so the lids' fitted vertex keys hold
# the rest pose exactly on both sides of it (a blink inside a segment may start or settle up to
# a key spacing early or late in the keys, within their tolerance).
dt = 1.0 / (30 * 10)
ev = np.load(os.path.join(d, "events.npy"))
x, y, t = ev["x"].astype(float), ev["y"].astype(float), ev["t"] * 1e-6
T.check(len(ev) > 0, f"events ({len(ev)})")

# the lids and their lashes: the skin's opening and the lash cards (which move with the lids and
# shade the skin around them), with a margin of 2 pixels
lx0, ly0 = project(-12.5, 11.5, 19.0)
lx1, ly1 = project(12.5, -11.0, 16.0)
lid = (x >= lx0 - 2) & (x <= lx1 + 2) & (y >= ly0 - 2) & (y <= ly1 + 2)
blink = (t >= 0.40 - dt) & (t <= 0.70 + dt)
# the cornea (radius 6 mm around the eye's axis, apex at z 14.5) mirrors the bending finger: its
# reflection moves while the lids rest, as in a real eye
cx, cy = project(0.0, 0.0, 14.5)
mm = project(1.0, 0.0, 14.5)[0] - cx
cornea = (x - cx) ** 2 + (y - cy) ** 2 <= (6.0 * mm + 2) ** 2
n_blink, n_rest = int(np.sum(lid & blink)), int(np.sum(lid & ~blink & ~cornea))
T.check(n_blink > 0.2 * (lx1 - lx0) * (ly1 - ly0), f"the lids fire during the blink ({n_blink} events)")
T.check(n_rest == 0, f"no lid events while the lids rest ({n_rest}; first at {t[lid].min() if n_rest else '-'} s)")
T.check(t[lid & blink].min() < 0.45 and t[lid & blink].max() > 0.6, "lid events span the closing and the opening")

# the finger and its shadow: everything right of x = 18 mm at the finger's depth
fx0, _ = project(18.0, 0.0, 30.0)
finger = x >= fx0
T.check(not np.any(lid & finger), "the lid and finger regions do not overlap")
n_finger = int(np.sum(finger))
T.check(n_finger > 0.5 * (W - fx0) * H, f"the finger fires while it bends ({n_finger} events)")
# all along it: each quarter of its visible height (from the image's bottom to its tip) fires
_, tip_row = project(32.0, 20.0, 30.0)
bands = np.linspace(max(tip_row, 0.0), H, 5)
per_band = [int(np.sum(finger & (y >= a) & (y < b))) for a, b in zip(bands[:-1], bands[1:])]
T.check(min(per_band) > 0.05 * n_finger / 4, f"events all along the finger ({per_band} by quarter of its height)")
T.check(np.sum(finger & (t < 0.3)) > 0 and np.sum(finger & (t > 0.75)) > 0, "the finger moves throughout")
elsewhere = int(np.sum(~lid & ~finger))
T.check(elsewhere <= 0.01 * len(ev), f"nearly nothing fires elsewhere ({elsewhere} of {len(ev)})")

# evray bench measures it
js = json.loads(T.run("bench", "--scene", "blink", "--backend", "cpu", "--res", "96x54", "--duration", "0.2",
                      "--json").stdout)
T.check(js["samples_per_second"] > 0 and js["events"] > 0, f"evray bench --scene blink ({js['samples_per_second']:.3g} samples/s)")
T.finish("test_blink")
