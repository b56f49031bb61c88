"""evray still: direct light, photon-mapped and path-traced global illumination on the Cornell
box at a tiny size, PFM output, the comparison, material extras, and bad input."""
import json
import os
import re

import evrtest as T

tmp = T.tmpdir()


def mean_lum(px):
    n = len(px) // 3
    return sum(0.2126 * px[3 * i] + 0.7152 * px[3 * i + 1] + 0.0722 * px[3 * i + 2] for i in range(n)) / n


def expect_error(args, what, code=None):
    p = T.run(*args, expect=None)
    lines = [l for l in p.stderr.splitlines() if l.strip()]
    T.check(p.returncode > 0 and (code is None or p.returncode == code), f"{what}: non-zero exit (got {p.returncode})")
    T.check(len(lines) == 1 and lines[0].startswith("evray: error: "), f"{what}: one error line (got {lines!r})")


T.check("usage: evray still" in T.run("still", "--help").stdout, "still --help")
imgs = {}
for gi in ("none", "photon", "path"):
    png, pfm = os.path.join(tmp, gi + ".png"), os.path.join(tmp, gi + ".pfm")
    p = T.run("still", "--scene", "cornell", "--res", "32x32", "--gi", gi, "--spp", "8", "--threads", "2",
              "-o", png, "--pfm", pfm)
    T.check(os.path.getsize(png) > 100, f"{gi}: PNG written")
    w, h, px = T.read_pfm(pfm)
    T.check((w, h) == (32, 32), f"{gi}: PFM is 32x32")
    imgs[gi] = px
    if gi == "photon":
        T.check(re.search(r"photon: \d+ paths, \d+ stayed", p.stdout) is not None, "photon statistics printed")
d, ph, pa = (mean_lum(imgs[k]) for k in ("none", "photon", "path"))
T.check(ph > 1.1 * d and pa > 1.1 * d, f"indirect light adds (direct {d:.4f}, photon {ph:.4f}, path {pa:.4f})")
T.check(abs(ph - pa) < 0.25 * pa, f"photon and path agree on the mean (photon {ph:.4f}, path {pa:.4f})")
# the direct part is the same code: --gi none is below both everywhere (indirect light is >= 0)
T.check(all(imgs["none"][i] <= imgs["photon"][i] + 1e-6 for i in range(len(imgs["none"]))), "photon adds, never removes")
# colour bleeding: the white floor next to the red wall is redder than next to the green wall
# (rows near the bottom, columns at the two sides)
def rg(px, x, y):
    i = 3 * (y * 32 + x)
    return px[i] / max(px[i + 1], 1e-9)
T.check(rg(imgs["photon"], 4, 30) > rg(imgs["none"], 4, 30) * 1.02 or rg(imgs["photon"], 27, 30) < rg(imgs["none"], 27, 30),
        "colour bleeding from the walls")

# the kernel over the whole disk instead of the surface the camera sees: darker or equal on average
nd = os.path.join(tmp, "nodisk.pfm")
T.run("still", "--scene", "cornell", "--res", "32x32", "--gi", "photon", "--no-gather-area", "-o", nd)
T.check(d < mean_lum(T.read_pfm(nd)[2]) <= ph * 1.001, "--no-gather-area: indirect light, no more than with the view")

# determinism: the same photons twice give the same image
again = os.path.join(tmp, "photon2.pfm")
T.run("still", "--scene", "cornell", "--res", "32x32", "--gi", "photon", "--threads", "1", "-o", again)
T.check(T.read_pfm(again)[2] == imgs["photon"], "photon image identical for 1 and 2 threads")

# the comparison against a reference
p = T.run("still", "--scene", "cornell", "--res", "32x32", "--gi", "photon", "-o", os.path.join(tmp, "c.png"),
          "--reference", os.path.join(tmp, "path.pfm"), "--region", "left_wall,right_wall,back_wall")
m = re.search(r"region \(left_wall,right_wall,back_wall\) (\d+) pixels: relative RMSE ([0-9.]+)", p.stdout)
T.check(m is not None and int(m.group(1)) > 100, f"region comparison printed ({p.stdout!r})")
p = T.run("still", "--scene", "cornell", "--res", "32x32", "--gi", "none", "-o", os.path.join(tmp, "c.pfm"),
          "--reference", os.path.join(tmp, "none.pfm"))
T.check("relative RMSE 0.0000" in p.stdout, "an image against itself: zero error")
p = T.run("still", "--scene", "cornell", "--res", "32x32", "--compare", os.path.join(tmp, "path.pfm"),
          "--reference", os.path.join(tmp, "path.pfm"), "--region", "left_wall")
T.check(p.stdout.count("relative RMSE 0.0000") == 3, f"--compare: an image against itself ({p.stdout!r})")
p = T.run("still", "--scene", "cornell", "--res", "32x32", "--compare", os.path.join(tmp, "photon.pfm"),
          "--reference", os.path.join(tmp, "path.pfm"))
T.check("relative RMSE 0.0000" not in p.stdout.splitlines()[0], "--compare: two different images differ")

# material extras t_diffuse / t_specular (evray's photon thresholds before its BSDF): ignored with
# a warning, whatever their values
def quad_with_extras(path, extras):
    T.quad_gltf(path)
    with open(path) as f:
        g = json.load(f)
    g["materials"][0]["extras"] = extras
    with open(path, "w") as f:
        json.dump(g, f)
old = os.path.join(tmp, "old.gltf")
for extras in ({"t_diffuse": 0.5, "t_specular": 0.7}, {"t_diffuse": 0.8, "t_specular": 0.3}, {"t_specular": 1.5}):
    quad_with_extras(old, extras)
    p = T.run("still", old, "--res", "16x16", "--gi", "photon", "-o", os.path.join(tmp, "old.png"))
    T.check("t_diffuse / t_specular are not read" in p.stderr, f"extras {extras}: one warning ({p.stderr!r})")
# the same scene at two times (the Cornell box's sliding box is back where it started at 2 s):
# the same photons, the same indirect light (as every segment of a static scene will get)
t0, t1, t2 = (os.path.join(tmp, f"t{k}.pfm") for k in range(3))
for t, f in ((0, t0), (2, t1), (1, t2)):
    T.run("still", "--scene", "cornell", "--res", "32x32", "--gi", "photon", "--time", t, "-o", f)
T.check(T.read_pfm(t0)[2] == T.read_pfm(t1)[2], "same scene at two times: identical photon images")
T.check(T.read_pfm(t0)[2] != T.read_pfm(t2)[2], "the box moved: a different image")
out = os.path.join(tmp, "x.png")
expect_error(["still", "--scene", "cornell", "--gi", "photons", "-o", out], "unknown --gi mode", 2)
expect_error(["still", "--scene", "cornell", "--gi", "photon"], "no output", 2)
expect_error(["still", "-o", out], "no scene", 2)
expect_error(["still", "--scene", "nope", "-o", out], "unknown built-in scene", 1)
expect_error(["still", "--scene", "cornell", "-o", os.path.join(tmp, "x.jpg")], "unknown image type", 2)
expect_error(["still", "--scene", "cornell", "--photons", "0", "-o", out], "zero photons", 2)
expect_error(["still", "--scene", "cornell", "--spp", "0", "-o", out], "zero spp", 2)
expect_error(["still", "--scene", "cornell", "--gather-radius", "-1", "-o", out], "negative radius", 2)
expect_error(["still", "--scene", "cornell", "--res", "0x10", "-o", out], "zero resolution", 2)
expect_error(["still", "--scene", "cornell", "--camera", "nope", "-o", out], "unknown camera", 2)
expect_error(["still", "--scene", "cornell", "--bogus", "-o", out], "unknown option", 2)
expect_error(["still", "--scene", "cornell", "-o", out, "--reference", os.path.join(tmp, "missing.pfm")], "missing reference", 1)
expect_error(["still", "--scene", "cornell", "--res", "16x16", "-o", out, "--reference", os.path.join(tmp, "none.pfm")],
             "reference of another size", 2)
expect_error(["still", "--scene", "cornell", "-o", out, "--reference", old], "reference not a PFM", 1)
expect_error(["still", "--scene", "cornell", "--compare", os.path.join(tmp, "none.pfm")], "--compare without --reference", 2)
T.check(not os.path.exists(out), "no image left behind after errors")
T.finish("test_still")
