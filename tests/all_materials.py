"""One small moving scene with every material feature of issue 21 at once, for CPU vs CUDA
(tests/test_cuda.py), change-driven sampling's identity (tests/test_skip.py), the region checks
of tests/test_all_materials.py and the pictures in docs/img (scripts/material-pictures.sh).

Standard library only, written through tests/gltf_build.py: `python3 tests/all_materials.py
OUTDIR` writes OUTDIR/all_materials.gltf and prints its path.

The camera at the origin looks along -Z, yfov 2 atan(0.5), aspect 4:3: the plane z = -3 spans
x in [-2, 2], y in [-1.5, 1.5]. A plain grey wall at z = -5 (x in [-5, 5], y in [-4, 4], base
0.6, roughness 0.8). In front of it two rows of three, centres at x = -1.3, 0, 1.3 and
y = +0.7 (top) and -0.7 (bottom), z about -3 (every name a node):
  sphere    a glossy metal sphere (radius 0.4, gold: base (1, 0.8, 0.45), metallic 1,
            roughness 0.05) that rises by 0.2 over t in [0, 1]: it mirrors the scene and shows
            the glint of the lamp, a sphere light (radius 0.05)
  slab      a glass slab (0.6 x 1.2 x 0.1, transmission 1, ior 1.5, volume thickness 0.1,
            attenuation distance 0.3 towards (0.9, 0.7, 0.5)) turned 30 degrees about +Y at
            z = -2.8, in front of "panel", a base-colour checker panel (1 x 1 at z = -3.3, 4 x 4
            cells, white top-left, roughness 1) that is wider than the slab: the checker's edges
            are seen through the glass, shifted and tinted, and beside it directly
  mask      an alpha-MASK card (0.8 x 0.8, cutoff 0.5, double-sided, white, roughness 1) whose
            base-colour texture's alpha is a 4 x 4 checker (opaque top-left): the wall shows
            through the holes; it turns 40 degrees about +Y over t in [0, 1]
  veil      a BLEND card (0.8 x 0.8, base (0.2, 0.4, 0.9, alpha 0.5)) sliding by +0.3 in x
            over t in [0, 1], in front of "post", a dark bar (0.16 x 1.25 at z = -3.5, base
            0.05, behind the card's centre at t = 0 and showing above and below it): the wall and the post show
            through the card, tinted blue
  glow      an emissive panel (0.8 x 0.8, base black, emissive texture the 4 x 4 checker, white
            top-left, strength 2)
  ridges    a normal-mapped plane (0.8 x 0.8, base 0.8, roughness 0.6) whose normal texture
            tilts the normal by 30 degrees to -x and +x in alternate columns (8 columns):
            stripes on flat geometry, which swap brightness as the lamp passes
  culled    a single-sided quad (0.3 x 0.3 at (0, 0, -3.6), between the rows) wound away from
            the camera, emissive red (2, 0, 0): invisible (the camera sees its back), its shadow
            on the wall (shadow rays see both faces)
  lamp      a white point light, intensity 30, extras radius 0.05, at (-0.6, 0.3, -1) until
            t = 0.5, then moving to (0.6, 0.3, -1) at t = 1 (while it holds still, pixels that
            see nothing moving skip their segments)
"""
import math
import os
import sys

import gltf_build as B

YFOV, ASPECT = B.YFOV, 4 / 3
ROW_Y, COL_X, Z = 0.7, 1.3, -3.0
CARD = 0.4            # half size of the cards and panels
SPHERE_R = 0.4
CULLED = (0.0, 0.0, -3.6)
CULLED_HALF = 0.15
POST_Z = -3.5
POST_X = -COL_X * POST_Z / Z  # behind the blended card's centre as the camera sees it
POST_HALF = 0.08
POST_Y = (-1.45, -0.2)       # beyond the card's top and bottom as the camera sees them
LAMP_FROM, LAMP_TO = (-0.6, 0.3, -1.0), (0.6, 0.3, -1.0)
RIDGE_COLUMNS = 8
CELL = 16             # texels per checker cell


def checker_png(alpha=False):
    """A 4 x 4 checker of CELL x CELL texels (many, so that magnification keeps the cells' edges
    sharp), the top-left cell on: RGB white and black, or (alpha) white with alpha 1 and 0."""
    n = 4 * CELL

    def on(x, y):
        return (x // CELL + y // CELL) % 2 == 0
    if alpha:
        return B.png_bytes(n, n, [(255, 255, 255, 255 if on(x, y) else 0)
                                  for y in range(n) for x in range(n)])
    return B.png_bytes(n, n, [(255,) * 3 if on(x, y) else (0,) * 3
                              for y in range(n) for x in range(n)], 3)


def ridges_png():
    """A tangent-space normal map of RIDGE_COLUMNS columns (CELL texels each), alternately
    tilted 30 degrees towards -x and +x: (-+sin 30, 0, cos 30) to 8 bits."""
    s, c = math.sin(math.radians(30)), math.cos(math.radians(30))

    def enc(v):
        return round((v * 0.5 + 0.5) * 255)
    n = RIDGE_COLUMNS * CELL
    row = [(enc(-s if (x // CELL) % 2 == 0 else s), enc(0.0), enc(c)) for x in range(n)]
    return B.png_bytes(n, 2, row * 2, 3)


def _card(g, name, x, y, material, z=Z, **node):
    """A square card of half size CARD facing +Z centred at (x, y, z) (geometry about its centre,
    the node translated there, so that it turns about its centre)."""
    pos, nrm, uv, idx = B.rect(-CARD, CARD, -CARD, CARD, 0.0)
    return g.mesh_node(name, pos, nrm, uv, idx, material, translation=[x, y, z], **node)


def build():
    g = B.Gltf("evray tests/all_materials.py")
    g.camera(yfov=YFOV, aspect=ASPECT)
    lamp = g.light("lamp", "point", 30.0, radius=0.05, translation=list(LAMP_FROM))
    checker = g.texture(g.image(checker_png(), name="checker"))
    cutout = g.texture(g.image(checker_png(alpha=True), name="checker_alpha"))
    ridges = g.texture(g.image(ridges_png(), name="ridges"))

    def pbr(base, metallic=0.0, roughness=1.0, **extra):
        return {"baseColorFactor": list(base), "metallicFactor": metallic,
                "roughnessFactor": roughness, **extra}

    wall = g.material({"name": "wall", "pbrMetallicRoughness": pbr((0.6, 0.6, 0.6, 1), roughness=0.8)})
    pos, nrm, uv, idx = B.rect(-5, 5, -4, 4, -5.0)
    g.mesh_node("wall", pos, nrm, uv, idx, wall)

    # top row: the metal sphere, the glass slab over the checker panel, the masked card
    gold = g.material({"name": "gold", "pbrMetallicRoughness": pbr((1, 0.8, 0.45, 1), 1.0, 0.05)})
    pos, nrm, uv, idx = B.uv_sphere(SPHERE_R, 64, 32)
    sphere = g.mesh_node("sphere", pos, nrm, uv, idx, gold, translation=[-COL_X, ROW_Y, Z])
    glass = g.material({
        "name": "glass", "pbrMetallicRoughness": pbr((1, 1, 1, 1), roughness=0.0),
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                       "KHR_materials_ior": {"ior": 1.5},
                       "KHR_materials_volume": {"thicknessFactor": 0.1, "attenuationDistance": 0.3,
                                                "attenuationColor": [0.9, 0.7, 0.5]}}})
    pos, nrm, uv, idx = B.box(-0.3, 0.3, -0.6, 0.6, -0.05, 0.05)
    g.mesh_node("slab", pos, nrm, uv, idx, glass, translation=[0, ROW_Y, -2.8],
                rotation=B.quaternion((0, 1, 0), 30))
    board = g.material({"name": "board", "pbrMetallicRoughness": pbr(
        (1, 1, 1, 1), baseColorTexture={"index": checker})})
    pos, nrm, uv, idx = B.rect(-0.5, 0.5, ROW_Y - 0.5, ROW_Y + 0.5, -3.3)
    g.mesh_node("panel", pos, nrm, uv, idx, board)
    card = g.material({"name": "cutout", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
                       "pbrMetallicRoughness": pbr((1, 1, 1, 1), baseColorTexture={"index": cutout})})
    mask = _card(g, "mask", COL_X, ROW_Y, card)

    # bottom row: the blended card, the emissive panel, the normal-mapped plane
    veil_mat = g.material({"name": "veil", "alphaMode": "BLEND",
                           "pbrMetallicRoughness": pbr((0.2, 0.4, 0.9, 0.5))})
    veil = _card(g, "veil", -COL_X, -ROW_Y, veil_mat)
    dark = g.material({"name": "dark", "pbrMetallicRoughness": pbr((0.05, 0.05, 0.05, 1))})
    pos, nrm, uv, idx = B.rect(POST_X - POST_HALF, POST_X + POST_HALF, *POST_Y, POST_Z)
    g.mesh_node("post", pos, nrm, uv, idx, dark)
    glow = g.material({"name": "glow", "emissiveFactor": [1, 1, 1],
                       "emissiveTexture": {"index": checker},
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}},
                       "pbrMetallicRoughness": pbr((0, 0, 0, 1))})
    _card(g, "glow", 0.0, -ROW_Y, glow)
    bumpy = g.material({"name": "bumpy", "normalTexture": {"index": ridges},
                        "pbrMetallicRoughness": pbr((0.8, 0.8, 0.8, 1), roughness=0.6)})
    _card(g, "ridges", COL_X, -ROW_Y, bumpy)

    # between the rows: a single-sided quad seen from behind
    red = g.material({"name": "one_sided_red", "emissiveFactor": [1, 0, 0],
                      "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}},
                      "pbrMetallicRoughness": pbr((0.8, 0.1, 0.1, 1))})
    h = CULLED_HALF
    pos, nrm, uv, idx = B.rect(-h, h, -h, h, 0.0, facing=-1)
    g.mesh_node("culled", pos, nrm, uv, idx, red, translation=list(CULLED))

    g.animation([
        (sphere, "translation", [0.0, 1.0], [(-COL_X, ROW_Y, Z), (-COL_X, ROW_Y + 0.2, Z)]),
        (mask, "rotation", [0.0, 1.0], [B.quaternion((0, 1, 0), 0), B.quaternion((0, 1, 0), 40)]),
        (veil, "translation", [0.0, 1.0], [(-COL_X, -ROW_Y, Z), (-COL_X + 0.3, -ROW_Y, Z)]),
        (lamp, "translation", [0.0, 0.5, 1.0], [LAMP_FROM, LAMP_FROM, LAMP_TO]),
    ], name="all")
    return g


def write(outdir):
    """Writes outdir/all_materials.gltf; returns its path."""
    os.makedirs(outdir, exist_ok=True)
    return build().write(os.path.join(outdir, "all_materials.gltf"))


def project(p, width, height):
    """The image position (column, row from the top, in pixels) of the point p (camera space)
    at width x height."""
    half_h = math.tan(YFOV / 2)
    x, y = p[0] / -p[2] / (half_h * ASPECT), p[1] / -p[2] / half_h
    return (x + 1) * width / 2, (1 - y) * height / 2


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: all_materials.py OUTDIR")
    print(write(sys.argv[1]))
