"""Hits a material rules out (src/core/hit_filter.h) on the CPU, on the scenes of
tests/filter_assets.py whose every pixel is known:
  - an alpha-masked card (a 4x4 checkerboard of alpha 0 and 1) in front of a lit wall: `evray still`
    shows the card where the texture is opaque and the wall through the holes, pixel for pixel
    away from the cells' edges; and the card's shadow on the wall has the same holes (the light is
    directional along the view: the wall at (x, y) is dark where the card at (x, y) is opaque);
  - a single-sided card: seen from the front, invisible from behind, and its shadow cast either
    way (shadow rays see back faces); double-sided, seen from behind too; wound away from the
    camera under a mirroring node (scale -1), seen (glTF: the determinant flips the winding);
  - a card, opaque on its right half only, sliding right: `evray render` makes events only where
    the opaque half's edges move (its transparent left border makes none), and change-driven
    sampling gives exactly the events of brute force (--no-skip), also with GI and davis346."""
import ast
import os
import struct
import sys

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import filter_assets as A  # noqa: E402

tmp = T.tmpdir()
scenes = A.write_all(os.path.join(tmp, "scenes"))
N = 64
WALL_LIT, CARD, WALL_DARK = 0.8 * 1.02, 0.3, 0.8 * 0.02  # radiance (ambient 0.02, sun pi lux)


def render_still(name):
    out = os.path.join(tmp, name + ".pfm")
    T.run("still", scenes[name], "--res", f"{N}x{N}", "--threads", "2", "-q", "-o", out)
    w, h, px = T.read_pfm(out)
    # PFM rows run bottom to top: image row j (from the top) is file row h - 1 - j
    return lambda i, j: px[3 * ((h - 1 - j) * w + i)]


def card_opaque(x, y, alpha):
    """Whether the card (z = -2, [-0.5, 0.5]^2) is opaque at (x, y) with alpha(col, row) of its
    4x4 texture; None outside it."""
    if abs(x) >= 0.5 or abs(y) >= 0.5:
        return None
    u, v = x + 0.5, 0.5 - y
    return alpha(min(int(u * 4), 3), min(int(v * 4), 3)) == 1


def expected(sx, sy, alpha, card_seen):
    """What the ray through (sx, sy) on the plane z = -1 sees: the card's emission where the card
    is opaque (and card_seen), else the wall, lit unless the card at the same (x, y) is opaque."""
    on_card = card_opaque(2 * sx, 2 * sy, alpha)
    if on_card and card_seen:
        return CARD
    return WALL_DARK if card_opaque(4 * sx, 4 * sy, alpha) else WALL_LIT


def compare(name, alpha, card_seen):
    """Pixels off every edge (the four corners of the pixel agree) against expected(); returns
    (pixels checked, wrong)."""
    at = render_still(name)
    checked = wrong = 0
    for j in range(N):
        for i in range(N):
            corners = {expected(((i + a) / N * 2 - 1) * 0.5, (1 - (j + b) / N * 2) * 0.5, alpha, card_seen)
                       for a in (0.02, 0.98) for b in (0.02, 0.98)}
            if len(corners) != 1:
                continue
            want = corners.pop()
            checked += 1
            if abs(at(i, j) - want) > 0.02 * want + 1e-3:
                wrong += 1
                if wrong <= 5:
                    print(f"{name}: pixel ({i}, {j}) {at(i, j):.4f}, expected {want:.4f}", file=sys.stderr)
    print(f"{name}: {checked} pixels checked, {wrong} wrong")
    return checked, wrong


# (a), (b): the cut-out and its shadow match the texture
checked, wrong = compare("mask_checker", A.checker_alpha, True)
T.check(checked > 0.8 * N * N and wrong == 0, f"mask_checker: cut-out and shadow match the texture ({wrong} wrong)")
# both kinds of pixel are there: the card, the wall through a hole, the shadow's holes
at = render_still("mask_checker")
levels = {min((CARD, WALL_LIT, WALL_DARK), key=lambda L: abs(at(i, j) - L)) for i in range(N) for j in range(N)}
T.check(levels == {CARD, WALL_LIT, WALL_DARK}, "mask_checker: card, lit wall and shadow all seen")

# (c) single-sided: front seen, back invisible, the shadow cast both ways; double-sided: seen
solid = lambda col, row: 1  # noqa: E731
for name, seen in (("cull_front", True), ("cull_back", False), ("both_back", True), ("cull_mirrored", True)):
    checked, wrong = compare(name, solid, seen)
    T.check(checked > 0.8 * N * N and wrong == 0, f"{name}: card {'seen' if seen else 'invisible'}, shadow cast")


def events(d):
    """events.npy's (x, y, t, p) records, without numpy."""
    data = open(os.path.join(d, "events.npy"), "rb").read()
    major = data[6]
    hlen = struct.unpack_from("<H" if major == 1 else "<I", data, 8)[0]
    start = 10 + hlen if major == 1 else 12 + hlen
    descr = ast.literal_eval(data[10 if major == 1 else 12:start].decode("latin1"))["descr"]
    fmt = "<" + "".join({"i8": "q", "u8": "Q", "u2": "H", "i2": "h", "i1": "b", "u1": "B", "i4": "i",
                         "u4": "I", "f8": "d", "f4": "f"}[t.lstrip("<>|=")] for _, t in descr)
    size = struct.calcsize(fmt)
    names = [n for n, _ in descr]
    return [dict(zip(names, struct.unpack_from(fmt, data, start + k * size)))
            for k in range((len(data) - start) // size)]


def render(name, d, *extra):
    T.run("render", scenes[name], "-o", d, "--backend", "cpu", "--format", "npy", "--no-preview", "--quiet",
          "--seed", "3", "--res", f"{N}x{N}", "--duration", "1", *extra)
    return open(os.path.join(d, "events.npy"), "rb").read()


# (d) the moving card: events where its opaque half's edges pass, none at its transparent border.
# The card's plane z = -2 spans [-1, 1] over the 64 columns: x -> column (x + 1) * 32. At t = 0 the
# opaque half spans x in [0, 0.5]; it slides to [0.25, 0.75]: its edges sweep columns 32..40 and
# 48..56; the transparent left border sweeps 16..24, rows 16..48.
render("mask_moving", os.path.join(tmp, "moving"))
ev = events(os.path.join(tmp, "moving"))
cols = [e["x"] for e in ev if 18 <= e["y"] < 46]
in_band = lambda a, b: sum(1 for c in cols if a <= c < b)  # noqa: E731
print(f"mask_moving: {len(ev)} events; columns 12-28: {in_band(12, 28)}, 31-42: {in_band(31, 42)}, "
      f"47-58: {in_band(47, 58)}")
T.check(in_band(31, 42) > 100 and in_band(47, 58) > 100, "mask_moving: events where the opaque half's edges move")
T.check(in_band(0, 30) == 0 and in_band(43, 46) == 0 and in_band(59, N) == 0,
        "mask_moving: no events at the transparent border, in the hole or beside the card")
T.check(all(15 <= e["y"] <= 48 for e in ev), "mask_moving: no events above or below the card")

# change-driven sampling stays exact with filtered hits
for name, extras in (("mask_moving", ([], ["--sensor", "davis346"])), ("mixed", ([], ["--gi", "photon"]))):
    for extra in extras:
        tag = "-".join([name] + [a.lstrip("-") for a in extra])
        skip = render(name, os.path.join(tmp, tag + "-skip"), *extra)
        brute = render(name, os.path.join(tmp, tag + "-brute"), "--no-skip", *extra)
        T.check(len(skip) > 200 and skip == brute, f"{tag}: identical events with and without skipping")
T.finish("test_hit_filters")
