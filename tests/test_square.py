"""End to end against analytic ground truth: the built-in 'square' scene, a bright square
(albedo 0.1 e^2) crossing a dark background (albedo 0.1) at 1 m/s. Its centre is at x = -1 + t;
the camera at (0, 0, 4) sees x in [-1, 1] on the background plane (yfov = 2 atan(1/4)), so a pixel
whose centre looks at X on the square's plane (z = 0.01) sees the leading edge at t = X + 0.75 and
the trailing edge at t = X + 1.25. ln(bright/dark) = 2, so with threshold C every pixel the square
crosses fires floor(2/C_on) ON events within one sample interval of the leading edge; the reference
is then floor(2/C_on)*C_on above the dark level, so the trailing edge gives floor(that/C_off) OFF
events (thresholds chosen so that no level falls exactly on the dark or bright value)."""
import math
import os

import numpy as np

import evrtest as T

W = H = 64
C_ON, C_OFF = 0.3, 0.25
FPS, N = 30, 10
d = os.path.join(T.tmpdir(), "square")
T.run("demo", "--scene", "square", "-o", d, "--res", f"{W}x{H}", "--pos-thres", C_ON, "--neg-thres", C_OFF, "--fps", FPS,
      "--samples-per-frame", N, "--log-floor", "1e-4", "--format", "npy", "--no-preview", "--quiet")
ev = np.load(os.path.join(d, "events.npy"))
T.check(len(ev) > 0, "events")
T.check(bool(np.all(np.diff(ev["t"]) >= 0)), "time ordered")
dt = 1.0 / (FPS * N)               # sample interval
count_on = int(math.floor(2.0 / C_ON))
count_off = int(math.floor(count_on * C_ON / C_OFF))
checked, bad_count, errors, silent = T.square_crossings(ev, W, H, C_ON, C_OFF)
bad_time = sum(1 for e in errors if e > dt + 2e-6)
T.check(checked > 500, f"enough pixels crossed by the square ({checked})")
T.check(bad_count == 0, f"every crossed pixel has {count_on} ON and {count_off} OFF events ({bad_count} of {checked} differ)")
T.check(bad_time == 0, f"events within one sample interval of the edge ({bad_time} of {checked} late/early)")
# pixels the square never reaches stay silent (rows well above and below it)
T.check(silent, "no events where nothing moves")
T.finish("test_square")
