"""Materials as rendered (issue 21), each against its analytic ground truth, with `evray still`
(the event pipeline's shading through each pixel centre, core/path.h's reflections and
refractions included), linear PFM images. Scenes from tests/material_assets.py (camera at the
origin looking along -Z, yfov 2 atan(0.5), a point lamp at the origin unless moved here):
  - a glass slab (IOR 1.5, 0.2 thick, turned 30 degrees) shifts a straight edge behind it by
    Snell's offset: the edge's image column matches the analytic trace within one pixel;
  - a glint: a smooth black dielectric sphere lit by a small sphere light shows its highlight
    at the analytic half-vector point, within one pixel;
  - an emissive texture shows its checker pattern at radiance 5 (strength 5);
  - a normal-mapped plane shades exactly as a plane whose normals are the mapped normal;
  - an alpha-masked card's cut-out matches its texture."""
import math
import os
import sys

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_build as B  # noqa: E402
import material_assets as MA  # noqa: E402

TMP = T.tmpdir()
HALF = 0.5  # tan(yfov / 2)


def still(scene, name, res):
    pfm = os.path.join(TMP, name + ".pfm")
    T.run("still", scene, "--res", f"{res}x{res}", "--threads", 2, "-o", pfm)
    return [[T.luminance(p) for p in row] for row in T.pfm_rows(pfm)]


def ray_dir(px, py, res):
    """The camera ray through image position (px, py) in pixels (pixel c's centre: c + 0.5)."""
    return (((2 * px / res) - 1) * HALF, (1 - 2 * py / res) * HALF, -1.0)


def norm(v):
    length = math.sqrt(sum(c * c for c in v))
    return tuple(c / length for c in v)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def refract(d, n, eta):
    c = -dot(d, n)
    k = 1 - eta * eta * (1 - c * c)
    return norm(tuple(eta * di + (eta * c - math.sqrt(k)) * ni for di, ni in zip(d, n)))


def slab_landing_x(px, res):
    """Where the ray through column px (image centre row) meets the backdrop z = -3 after the
    slab: front face n.(p - c) = 0.1, back face -0.1, n = (sin 30, 0, cos 30), c = (0, 0, -1.1)."""
    n = (math.sin(math.radians(30)), 0.0, math.cos(math.radians(30)))
    c = (0.0, 0.0, -1.1)
    d = norm(ray_dir(px, res / 2, res))
    t = (0.1 + dot(n, c)) / dot(n, d)
    p = tuple(t * x for x in d)
    d2 = refract(d, n, 1 / 1.5)
    t2 = (-0.1 + dot(n, c) - dot(n, p)) / dot(n, d2)
    p2 = tuple(a + t2 * b for a, b in zip(p, d2))
    d3 = refract(d2, n, 1.5)
    t3 = (-3.0 - p2[2]) / d3[2]
    return p2[0] + t3 * d3[0]


def edge_column(row, lo, hi):
    """The sub-pixel column where the row crosses half way between lo and hi (left to right)."""
    mid = 0.5 * (lo + hi)
    for c in range(len(row) - 1):
        if (row[c] - mid) * (row[c + 1] - mid) <= 0 and row[c] != row[c + 1]:
            return c + 0.5 + (mid - row[c]) / (row[c + 1] - row[c])
    return None


# ---- Snell's offset through a glass slab ----
RES = 200
img = still(MA.transmission_slab(TMP), "slab", RES)
row = img[RES // 2]
lo, hi = min(row), max(row)
measured = edge_column(row, lo, hi)
a, b = 0.0, float(RES)  # the column whose ray lands on x = 0 (landing x grows with the column)
for _ in range(60):
    m = 0.5 * (a + b)
    if slab_landing_x(m, RES) < 0:
        a = m
    else:
        b = m
expected = 0.5 * (a + b)
straight = RES / 2  # without the slab the edge would be at the image centre
print(f"slab: edge at column {measured}, Snell {expected:.3f}, without the slab {straight}")
T.check(measured is not None and abs(measured - expected) <= 1.0,
        f"the slab shifts the edge by Snell's offset (column {measured} vs {expected:.2f})")
T.check(abs(expected - straight) > 2.0, "the offset is more than two pixels (the test can tell)")

# ---- a glint at the half-vector point ----
RES = 160
CENTRE, RADIUS, LAMP = MA.GLINT_CENTRE, MA.GLINT_RADIUS, MA.GLINT_LAMP
path = MA.glint_sphere(TMP)
img = still(path, "glint", RES)
gx, gy, peak = T.bright_centroid({(c, r): img[r][c] for r in range(RES) for c in range(RES)})
p = T.glint_point(CENTRE, RADIUS, LAMP)
ex, ey = (p[0] / -p[2] / HALF + 1) * RES / 2, (1 - p[1] / -p[2] / HALF) * RES / 2
print(f"glint: at ({gx:.2f}, {gy:.2f}), analytic ({ex:.2f}, {ey:.2f}), peak {peak:.3g}")
T.check(math.hypot(gx - ex, gy - ey) <= 1.0, "the glint lies at the analytic half-vector point")
T.check(peak > 20 * img[5][5] + 1e-3, "the glint stands out of the dark sphere and background")

# ---- an emissive texture's pattern ----
RES = 64
img = still(MA.emissive_texture(TMP), "emissive", RES)
cell = RES // 4
bright = [img[cell * j + cell // 2][cell * i + cell // 2] for j in range(4) for i in range(4)
          if (i + j) % 2 == 0]
dark = [img[cell * j + cell // 2][cell * i + cell // 2] for j in range(4) for i in range(4)
        if (i + j) % 2 == 1]
print(f"emissive: white cells {min(bright):.4f}-{max(bright):.4f}, black {max(dark):.4f}")
# pixel centres sit off the texel centres: bilinear filtering mixes a few percent of the
# neighbouring cell in, and a white and a black cell sum to the emitted 5 either way
T.check(all(v > 4.5 for v in bright), "white cells emit radiance about 5")
T.check(all(v < 0.5 for v in dark), "black cells emit about nothing")
T.check(abs(sum(bright) / len(bright) + sum(dark) / len(dark) - 5.0) <= 0.05,
        "a white and a black cell together emit 5 (strength 5 times factor 1)")

def plain_quad():
    """The normal-mapped plane's material without its normal texture, normals +Z."""
    g = MA.Gltf()
    m = g.material({"name": "plain", "pbrMetallicRoughness": {"metallicFactor": 0,
                                                              "roughnessFactor": 0.5}})
    MA._quad(g, "quad", m)
    return g.write(TMP, "plain")


# ---- a normal-mapped plane shades as the tilted normal ----
RES = 48
mapped = still(MA.normal_plane_tangents(TMP), "mapped", RES)
g = MA.Gltf()
flat = g.material({"name": "tilted", "pbrMetallicRoughness": {"metallicFactor": 0,
                                                              "roughnessFactor": 0.5}})
n8 = norm(tuple(v / 255 * 2 - 1 for v in (173, 189, 230)))
pos, _, uv, idx = B.rect(-0.5, 0.5, -0.5, 0.5, -1.0)
g.mesh_node("quad", pos, [n8] * 4, uv, idx, flat)
tilted = still(g.write(TMP, "tilted"), "tilted", RES)
worst = max(abs(a - b) / max(b, 1e-6) for ra, rb in zip(mapped, tilted) for a, b in zip(ra, rb))
print(f"normal map: largest relative difference to the tilted plane {worst:.2e}")
T.check(worst <= 1e-3, "the normal-mapped plane shades as a plane with the mapped normal")
untilted = still(plain_quad(), "untilted", RES)
T.check(abs(mapped[RES // 2][RES // 2] - untilted[RES // 2][RES // 2]) >
        0.05 * untilted[RES // 2][RES // 2], "the mapped normal changes the shading (the test can tell)")

# ---- an alpha-masked card ----
RES = 64
img = still(MA.alpha_mask_card(TMP), "mask", RES)
left = [img[r][c] for r in range(8, 56) for c in range(2, 30)]
right = [img[r][c] for r in range(8, 56) for c in range(34, 62)]
print(f"mask: hole half {max(left):.4f}, card half {min(right):.4f}")
T.check(max(left) < 0.01 * min(right), "the card's left half is a hole onto the black backdrop")

T.finish("test_materials_render")
