"""The all-materials scene (tests/all_materials.py) shows every feature it is there for: one
`evray still` at t = 0 (320 x 240, linear PFM), each object's region checked:
  - sphere: the lamp's glint (a sphere light in gold metal) at the analytic half-vector point,
    within 1.5 pixels, far brighter than the rest of the sphere;
  - slab: the checker panel seen through the glass keeps its pattern (transmission) and is
    tinted by the volume's attenuation (red > green > blue), while the panel seen directly beside
    the slab is neutral;
  - mask: the card's opaque cells (its texture's alpha) are the bright white card, its holes the
    darker wall behind;
  - veil: the BLEND card is blue, and the dark post behind it shows through it (darker than the
    card beside the post, brighter than the post seen directly);
  - glow: the emissive checker emits about 2 on its white cells, little on its black ones;
  - ridges: the normal map's alternate columns shade differently on flat geometry of one colour;
  - culled: the single-sided quad seen from behind is invisible (no red where it stands), and
    its shadow on the wall is cast.
The events side (CPU vs CUDA, change-driven sampling's identity) is in tests/test_cuda.py and
tests/test_skip.py."""
import math
import os
import statistics

import evrtest as T
import all_materials as AM

W, H = 320, 240
tmp = T.tmpdir()
pfm = os.path.join(tmp, "t0.pfm")
T.run("still", AM.write(tmp), "--res", f"{W}x{H}", "--threads", 2, "-q", "-o", pfm)
img = T.pfm_rows(pfm)


def at(p):
    """The pixel (r, g, b) that sees camera-space point p (on the object in front)."""
    c, r = AM.project(p, W, H)
    return img[int(r)][int(c)]


def lum(p):
    return T.luminance(at(p))


def lamp_through(p, z):
    """Where the ray from the lamp (at t = 0) through p meets the plane z."""
    lamp = AM.LAMP_FROM
    t = (z - lamp[2]) / (p[2] - lamp[2])
    return tuple(a + t * (b - a) for a, b in zip(lamp, p))


# ---- sphere: the glint at the half-vector point ----
centre = (-AM.COL_X, AM.ROW_Y, AM.Z)
ex, ey = AM.project(T.glint_point(centre, AM.SPHERE_R, AM.LAMP_FROM), W, H)
c0, r0 = AM.project(centre, W, H)
rad = AM.SPHERE_R / -centre[2] / math.tan(AM.YFOV / 2) * H / 2 * 0.9  # inside the disc
lums = {(c, r): T.luminance(img[r][c]) for r in range(H) for c in range(W)
        if math.hypot(c + 0.5 - c0, r + 0.5 - r0) < rad}
gx, gy, peak = T.bright_centroid(lums)
median = statistics.median(lums.values())
print(f"sphere: glint at ({gx:.2f}, {gy:.2f}), analytic ({ex:.2f}, {ey:.2f}); peak {peak:.3g}, "
      f"the sphere's median {median:.3g}")
T.check(math.hypot(gx - ex, gy - ey) <= 1.5, "the metal sphere's glint at the half-vector point")
T.check(peak > 100 * median, "the glint stands out of the sphere")

# ---- slab: the checker through the glass, tinted; beside it, neutral ----
# the panel's cells are 0.25 wide (x in [-0.5, 0.5]); the slab (turned 30 degrees) covers about
# x in [-0.3, 0.2] of the panel's image: the camera rays towards the panel's second column pass
# through it (refracted: which cell each lands on is test_materials_render.py's business), its
# outer columns are seen beside it
panel_z, cell = -3.3, 0.25
through, beside = [], []
for j in range(4):
    y = AM.ROW_Y + 0.5 - cell * (j + 0.5)
    through.append(at((-0.125, y, panel_z)))
    beside += [(at((x, y, panel_z)), (i + j) % 2 == 0) for i, x in ((0, -0.375), (3, 0.375))]
white_through = [p for p in through if T.luminance(p) > 0.2]
lum_through = sorted(T.luminance(p) for p in through)
white_beside = [p for p, on in beside if on]
print("slab: through the glass", [tuple(round(c, 3) for c in p) for p in through])
print("slab: beside it (white cells)", [tuple(round(c, 3) for c in p) for p in white_beside])
T.check(lum_through[-1] > 5 * lum_through[0], "the checker's pattern shows through the slab")
T.check(white_through and all(p[0] > 1.05 * p[1] > 1.1 * p[2] for p in white_through),
        "the slab's volume tints what is seen through it (red > green > blue)")
T.check(white_beside and all(abs(p[0] - p[2]) < 0.02 * p[0] for p in white_beside),
        "the panel beside the slab is neutral")

# ---- mask: opaque cells are the card, holes show the wall ----
opaque, holes = [], []
for j in range(4):
    for i in range(4):
        q = (AM.COL_X - AM.CARD + (i + 0.5) * AM.CARD / 2, AM.ROW_Y + AM.CARD - (j + 0.5) * AM.CARD / 2, AM.Z)
        (opaque if (i + j) % 2 == 0 else holes).append(lum(q))
print(f"mask: opaque cells {min(opaque):.3f}-{max(opaque):.3f}, holes {min(holes):.3f}-{max(holes):.3f}")
T.check(min(opaque) > 1.5 * max(holes), "the masked card's holes follow its texture's alpha")

# ---- veil: blue, and the post shows through it ----
vx, vy = -AM.COL_X, -AM.ROW_Y
off_post = at((vx + 0.25, vy, AM.Z))
on_post = lum((vx, vy, AM.Z))
post_direct = lum((AM.POST_X, AM.POST_Y[1] - 0.05, AM.POST_Z))  # above the card
print(f"veil: beside the post {off_post}, over the post {on_post:.4f}, the post directly {post_direct:.4f}")
T.check(off_post[2] > 1.5 * off_post[0], "the blended card is blue")
T.check(on_post < 0.8 * T.luminance(off_post), "the post shows through the blended card")
T.check(on_post > 2 * post_direct, "the blended card covers the post half (not opaque, not absent)")

# ---- glow: the emissive checker ----
on, off = [], []
for j in range(4):
    for i in range(4):
        q = (-AM.CARD + (i + 0.5) * AM.CARD / 2, -AM.ROW_Y + AM.CARD - (j + 0.5) * AM.CARD / 2, AM.Z)
        (on if (i + j) % 2 == 0 else off).append(lum(q))
print(f"glow: white cells {min(on):.3f}-{max(on):.3f}, black {min(off):.3f}-{max(off):.3f}")
T.check(all(1.9 < v < 2.3 for v in on), "the emissive texture's white cells emit about 2")
T.check(all(v < 0.2 for v in off), "its black cells emit about nothing")

# ---- ridges: alternate columns of the normal map shade differently ----
stripe = 2 * AM.CARD / AM.RIDGE_COLUMNS
cols = [lum((AM.COL_X - AM.CARD + (k + 0.5) * stripe, -AM.ROW_Y, AM.Z)) for k in range(AM.RIDGE_COLUMNS)]
even, odd = cols[0::2], cols[1::2]
print("ridges: stripes", [round(v, 3) for v in cols])
T.check(min(even) > 1.2 * max(odd) or min(odd) > 1.2 * max(even),
        "the normal map's alternate columns shade differently on the flat plane")

# ---- culled: invisible, its shadow cast ----
q = AM.CULLED
seen = at(q)
shadow = lamp_through(q, -5.0)
lit = (-shadow[0], shadow[1], shadow[2])  # the wall mirrored about x = 0: in the light
print(f"culled: where it stands {seen}; its shadow {lum(shadow):.4f}, the wall beside {lum(lit):.4f}")
T.check(seen[0] < 1.1 * seen[1], "the single-sided quad seen from behind is invisible (no red)")
T.check(lum(shadow) < 0.3 * lum(lit), "the culled quad still casts its shadow")

T.finish("test_all_materials")
