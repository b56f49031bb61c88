"""evray plot --flow / --depth (README "Ground truth"): labels.h5 drawn at the label frame nearest
--time. On the square scene with a wide view (its border sees nothing): pixels on the square have
the colour wheel's hue of +x (red; its known motion, 1 m/s along +X), the still background plane
is white and pixels without a surface black; --flow-max sets the saturation (the square at half
of it: half saturated); the default wheel edge is the 99th percentile (the square's speed). A
quad moving down and right has the wheel's colour of its direction, computed here from the
colour wheel's definition. Depth: the square (3.99 m) brighter than the background (4 m),
no-surface pixels teal, and on a tilted view of the plane brightness falls row by row as the
depth grows. Bad input: one error line, non-zero exit. PNGs read by tests/apng_read.py."""
import colorsys
import math
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import apng_read  # noqa: E402
import evrtest as T  # noqa: E402
import gltf_build  # noqa: E402

tmp = T.tmpdir()
FX, FY = 10, 40  # the field's top-left corner (EVR_PLOT_LABEL_X, EVR_PLOT_LABEL_Y)
WHITE, BLACK, TEAL = (255, 255, 255), (0, 0, 0), (0, 128, 128)


def wheel_colour(u, v, edge):
    """The colour wheel of Baker et al. (Middlebury), from its definition: 55 hues, red to
    yellow (15 steps), yellow to green (6), green to cyan (4), cyan to blue (11), blue to
    magenta (13), magenta to red (6); angle atan2(-v, -u) over the wheel; white at rest."""
    hues = []
    for n, f in ((15, lambda k, n: (255, 255 * k // n, 0)),
                 (6, lambda k, n: (255 - 255 * k // n, 255, 0)),
                 (4, lambda k, n: (0, 255, 255 * k // n)),
                 (11, lambda k, n: (0, 255 - 255 * k // n, 255)),
                 (13, lambda k, n: (255 * k // n, 0, 255)),
                 (6, lambda k, n: (255, 0, 255 - 255 * k // n))):
        hues += [f(k, n) for k in range(n)]
    fk = (math.atan2(-v, -u) / math.pi + 1) / 2 * (len(hues) - 1)
    k0 = int(math.floor(fk))
    f = fk - k0
    rad = math.hypot(u, v) / edge
    out = []
    for ch in range(3):
        c = ((1 - f) * hues[k0][ch] + f * hues[(k0 + 1) % len(hues)][ch]) / 255
        c = 1 - rad * (1 - c) if rad <= 1 else c * 0.75
        out.append(int(math.floor(255 * c)))
    return tuple(out)


def hue_distance(a, b):
    ha, hb = colorsys.rgb_to_hsv(*[x / 255 for x in a])[0], colorsys.rgb_to_hsv(*[x / 255 for x in b])[0]
    d = abs(ha - hb)
    return min(d, 1 - d)


class Image:
    def __init__(self, path, scale):
        self.w, self.h, ch, frames, _ = apng_read.read(path)
        T.check(ch == 3, f"{path}: RGB")
        self.px, self.s = frames[0], scale

    def at(self, x, y):
        """The colour of label pixel (x, y): the centre of its square in the image."""
        ix, iy = FX + x * self.s + self.s // 2, FY + y * self.s + self.s // 2
        i = 3 * (iy * self.w + ix)
        return tuple(self.px[i:i + 3])


def plot(labels, *args, expect=0):
    p = T.run("plot", "--labels", labels, *args, expect=expect)
    return p.stdout


def scale_of(out, w):
    s = int(out.split(" drawn at ")[1].split("x")[0])
    T.check(s == 640 // w, f"scale {s} for {w} pixels (the largest within 640)")
    return s


# ---- the square, its view wider than the background plane ----
W = 64
run = os.path.join(tmp, "square")
T.run("demo", "--scene", "square", "--res", f"{W}x{W}", "--duration", "1", "--labels-fps", "4",
      "--fov", "60", "-o", run, "-q", "--no-preview")
labels = os.path.join(run, "labels.h5")
speed = 1.0 / 3.99 * (W / 2) / math.tan(math.radians(30))  # px/s: 1 m/s at 3.99 m
flow_png, depth_png = os.path.join(tmp, "flow.png"), os.path.join(tmp, "depth.png")
out = plot(labels, "--time", "0.55", "--flow", flow_png, "--depth", depth_png)
print(out.strip())
T.check("label frame 2 of 5 (t = 0.5 s, the nearest to 0.55 s)" in out, "frame 2 taken for 0.55 s")
edge = float(out.split("wheel edge ")[1].split(" px/s")[0])
T.check(abs(edge - speed) < 0.005 * speed and "99th percentile" in out,
        f"wheel edge {edge} px/s: the square's speed {speed:.4f} (the 99th percentile)")
s = scale_of(out, W)
img = Image(flow_png, s)
T.check(img.w >= FX + W * s and img.h >= FY + W * s, f"flow image {img.w}x{img.h} holds the field")
# at t = 0.5 the square's centre is at x = -0.5 m: column (1 - 0.5/2.3036)/2 * 64 = 25
sq, bg, none = img.at(25, 31), img.at(45, 20), [img.at(1, 1), img.at(62, 62), img.at(1, 40)]
# +x lies on the wheel's seam (atan2 at +-pi: hue 0 or hue 54, a touch of magenta): either side
T.check(min(hue_distance(sq, wheel_colour(1, e, 1)) for e in (1e-9, -1e-9)) < 0.01 and
        max(sq) >= 190 and sq[1] < 30, f"the square is red, the hue of +x motion: {sq}")
T.check(bg == WHITE, f"the still background is white: {bg}")
T.check(all(c == BLACK for c in none), f"no surface: black {none}")
# --flow-max at twice the speed: the square half saturated
out = plot(labels, "--time", "0.5", "--flow", flow_png, "--flow-max", str(2 * speed))
img = Image(flow_png, s)
sq = img.at(25, 31)
want = [wheel_colour(speed, e, 2 * speed) for e in (1e-9, -1e-9)]
T.check(any(all(abs(a - b) <= 2 for a, b in zip(sq, w)) for w in want) and "--flow-max" in out,
        f"half the edge: {sq}, expected one of {want}")
sat = colorsys.rgb_to_hsv(*[x / 255 for x in sq])[1]
T.check(abs(sat - 0.5) < 0.02, f"saturation {sat:.3f} at half the edge")
# depth: the square nearer, brighter
img = Image(depth_png, s)
sq, bg, none = img.at(25, 31), img.at(45, 20), img.at(1, 1)
T.check(sq == WHITE and bg == (0, 0, 4), f"depth: square (nearest) white {sq}, background (farthest) dark {bg}")
T.check(none == TEAL, f"depth: no surface teal {none}")

# the frame nearest --time, half a frame interval beyond the ends, the middle by default
for t, k in (("0.9", 4), ("1.12", 4), ("-0.12", 0), ("0.1", 0), ("0.13", 1)):
    out = plot(labels, "--time", t, "--depth", depth_png)
    T.check(f"label frame {k} of 5" in out, f"--time {t}: frame {k} ({out.strip()})")
out = plot(labels, "--flow", flow_png)
T.check("label frame 2 of 5 (t = 0.5 s, the middle frame)" in out, f"default: the middle frame ({out.strip()})")
# with the events: the labels beside them
out = T.run("plot", os.path.join(run, "events.h5"), "-o", os.path.join(tmp, "rate.png"),
            "--flow", flow_png, "--time", "0.25").stdout
T.check("rate.png" in out and "label frame 1 of 5" in out, f"events and labels together: {out}")

# ---- a quad moving right and down (world -Y): the wheel's colour of that direction ----
g = gltf_build.Gltf()
g.camera("cam", translation=[0, 0, 4])  # yfov 2 atan(1/2): f = W px
pos, _, _, idx = gltf_build.rect(-3, 3, -3, 3, 0)
g.node("back", mesh=g.mesh("back", [g.primitive(pos, idx)]))
pos, _, _, idx = gltf_build.rect(-0.3, 0.3, -0.3, 0.3, 0)
quad = g.node("quad", mesh=g.mesh("quad", [g.primitive(pos, idx)]), translation=[0, 0, 1])
g.animation([(quad, "translation", [0.0, 1.0], [(0, 0, 1), (1, -0.5, 1)])])
scene = g.write(os.path.join(tmp, "diag.gltf")) or os.path.join(tmp, "diag.gltf")
run2 = os.path.join(tmp, "diag")
T.run("render", scene, "--res", f"{W}x{W}", "--duration", "1", "--labels-fps", "2", "-o", run2,
      "-q", "--no-preview")
u, v = W / 3.0, 0.5 * W / 3.0  # px/s at 3 m: right, and down (world -Y)
out = plot(os.path.join(run2, "labels.h5"), "--time", "0.5", "--flow", flow_png, "--flow-max",
           str(2 * math.hypot(u, v)))
img = Image(flow_png, scale_of(out, W))
# the quad's centre at t = 0.5: (0.5, -0.25) m at 3 m, column (1 + 1/3)/2 * 64, row (1 + 1/6)/2 * 64
got, want = img.at(42, 37), wheel_colour(u, v, 2 * math.hypot(u, v))
T.check(all(abs(a - b) <= 2 for a, b in zip(got, want)), f"moving right and down: {got}, expected {want}")
T.check(hue_distance(got, wheel_colour(u, -v, 1)) > 0.05, "not the colour of right and up")

# ---- depth on a tilted view of the plane: brightness falls as depth grows (upwards) ----
run3 = os.path.join(tmp, "tilted")
T.run("demo", "--scene", "square", "--res", f"{W}x{W}", "--duration", "0.5", "--labels-fps", "2",
      "--look-from", "0,-2.5,4", "--look-at", "0,0,0", "-o", run3, "-q", "--no-preview")
out = plot(os.path.join(run3, "labels.h5"), "--time", "0", "--depth", depth_png)
img = Image(depth_png, scale_of(out, W))
column = [img.at(W // 2, y) for y in range(W)]
lum = [T.luminance(c) for c in column if c != TEAL]
T.check(len(lum) > W // 2, f"the plane fills the column ({len(lum)} rows)")
T.check(all(b >= a for a, b in zip(lum, lum[1:])) and lum[-1] - lum[0] > 150,
        f"brighter row by row downwards, nearer: {[round(x) for x in lum[::8]]}")

# ---- bad input: one line, non-zero exit ----
corrupt = os.path.join(tmp, "corrupt.h5")
with open(labels, "rb") as f:
    data = bytearray(f.read())
for i in range(len(data) // 2, len(data), 97):  # the frames' compressed chunks
    data[i] ^= 0x5A
with open(corrupt, "wb") as f:
    f.write(bytes(data))
nolabels = os.path.join(tmp, "nolabels")
os.makedirs(nolabels)
shutil.copy(os.path.join(run, "events.h5"), nolabels)
flow_png = os.path.join(tmp, "bad.png")
for args, code, what in (
        (["--labels", os.path.join(tmp, "missing.h5"), "--flow", flow_png], 1, "No such file"),
        ([os.path.join(nolabels, "events.h5"), "-o", os.path.join(nolabels, "rate.png"), "--flow",
          flow_png], 1, "labels.h5"),
        (["--labels", labels, "--flow", flow_png, "--time", "1.2"], 1, "outside the label frames"),
        (["--labels", labels, "--flow", flow_png, "--time", "-0.2"], 1, "outside the label frames"),
        (["--labels", corrupt, "--flow", flow_png, "--time", "1"], 1, "corrupt.h5"),
        (["--labels", os.path.join(run, "events.h5"), "--depth", flow_png], 1, "not a labels.h5"),
        (["--labels", labels], 2, "--flow FILE or --depth FILE"),
        (["--labels", labels, "--depth", flow_png, "--flow-max", "3"], 2, "--flow-max"),
        (["--labels", labels, "--flow", flow_png, "--flow-max", "0"], 2, "--flow-max"),
        (["--labels", labels, "--flow", flow_png, "--time", "nan"], 2, "--time"),
        (["--labels", labels, "--flow", flow_png, "-o", "r.png"], 2, "-o draws events"),
        (["--time", "0.5"], 2, "no event file")):
    p = T.run("plot", *args, expect=None)
    lines = p.stderr.strip().splitlines()
    T.check(p.returncode == code and len(lines) == 1 and what in p.stderr,
            f"plot {' '.join(args)}: exit {p.returncode}, {p.stderr!r} (expected {code}, {what!r})")
T.check(not os.path.exists(flow_png), "nothing drawn from bad input")
T.finish("test_plot_labels")
