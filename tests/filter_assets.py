"""glTF test scenes for the hit filters (src/core/hit_filter.h): alpha MASK cut-outs and
single-sided surfaces, with geometry simple enough that the tests know every pixel.

Standard library only, written through tests/gltf_build.py. `python3 tests/filter_assets.py OUTDIR` writes
every scene as OUTDIR/NAME.gltf.

Common to all: a camera node at the origin looking along -Z, perspective with yfov = 2 atan(0.5)
(the plane z = -d spans [-d/2, d/2] in x and y), aspect 1; a wall at z = -4 (x, y in [-4, 4],
white, base colour 0.8, facing the camera); a directional light travelling along -Z (intensity
pi: a surface facing it reflects radiance = base colour); a card at z = -2 spanning [-0.5, 0.5]
in x and y, black with emission 0.3 (brighter than the wall in shadow, darker than the lit wall),
uv (0, 0) at its top-left corner (u = x + 0.5, v = 0.5 - y).

  mask_checker   the card is alpha MASK (cutoff 0.5) with a 4x4 checkerboard base texture of alpha
                 1 (texel column + row even) and 0: through the holes the camera sees the wall,
                 and the light reaches the wall through them (the shadow has holes)
  cull_front     the card opaque and single-sided, its front (counter-clockwise) towards the
                 camera: seen; its shadow (shadow rays meet its back face) is on the wall
  cull_back      the same card wound the other way: the camera sees its back, so it is invisible,
                 but its shadow is still on the wall
  both_back      cull_back's card made double-sided: seen
  cull_mirrored  cull_back's card under a node of scale (-1, 1, 1): the mirroring flips its
                 winding (glTF: a negative determinant), so its front faces the camera: seen
  mask_moving    the card alpha MASK with an 8x1 texture, alpha 0 on its left half (u < 0.5) and
                 1 on its right half, translating by +0.25 in x over t in [0, 1] (LINEAR): only
                 the opaque half's edges (at x = 0 and x = 0.5 at t = 0) make events
  mixed          mask_checker's card, mask_moving's card's translation, and cull_back's card
                 behind it at z = -3 offset by (0.6, 0.4): the CPU-vs-CUDA scene
"""
import math
import os
import sys

import gltf_build as B


def checker_alpha(col, row):
    """mask_checker's texture: 1 where texel column + row is even."""
    return 1 if (col + row) % 2 == 0 else 0


def checker_png():
    return B.png_bytes(4, 4, [(255, 255, 255, 255 * checker_alpha(c, r))
                              for r in range(4) for c in range(4)])


def half_png():
    return B.png_bytes(8, 1, [(255, 255, 255, 255 if c >= 4 else 0) for c in range(8)])


class _Doc(B.Gltf):
    """A scene with the common camera and sun; textures sampled linearly."""

    def __init__(self):
        super().__init__()
        self.linear = self.sampler(magFilter=B.LINEAR, minFilter=B.LINEAR)
        self.camera()
        self.light("sun", "directional", math.pi)

    def texture(self, png):
        return super().texture(self.image(png), sampler=self.linear)

    def material(self, name, base=(0, 0, 0, 1), emissive=(0, 0, 0), texture=None, mask=False,
                 double_sided=False):
        pbr = {"baseColorFactor": list(base), "metallicFactor": 0.0, "roughnessFactor": 1.0}
        if texture is not None:
            pbr["baseColorTexture"] = {"index": texture}
        # Lambert (no specular layer: KHR_materials_specular factor 0), so that the expected
        # intensities are albedo / pi times the irradiance
        m = {"name": name, "pbrMetallicRoughness": pbr, "emissiveFactor": list(emissive),
             "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}
        if mask:
            m["alphaMode"] = "MASK"
            m["alphaCutoff"] = 0.5
        if double_sided:
            m["doubleSided"] = True
        return super().material(m)

    def quad(self, name, x0, x1, y0, y1, z, material, towards_camera=True, **node):
        """A quad in the plane z, uv (0, 0) at its top-left corner; its front (counter-clockwise)
        faces +Z (the camera) or, with towards_camera False, -Z."""
        pos, nrm, uv, idx = B.rect(x0, x1, y0, y1, z, facing=1 if towards_camera else -1)
        return self.mesh_node(name, pos, nrm, uv, idx, material, index_type=B.UINT, **node)

    def translate_x(self, node, dx):
        """Animates node's translation from its own to +dx in x over t in [0, 1], LINEAR."""
        t0 = self.nodes[node].setdefault("translation", [0, 0, 0])
        self.animation([(node, "translation", [0.0, 1.0], [tuple(t0), (t0[0] + dx, t0[1], t0[2])])],
                       name="slide")


def _base():
    d = _Doc()
    d.quad("wall", -4, 4, -4, 4, -4, d.material("white", base=(0.8, 0.8, 0.8, 1)))
    return d


def mask_checker():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
           d.material("cutout", emissive=(0.3, 0.3, 0.3), texture=d.texture(checker_png()), mask=True))
    return d


def cull_front():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2, d.material("one_sided", emissive=(0.3, 0.3, 0.3)))
    return d


def cull_back():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2, d.material("one_sided", emissive=(0.3, 0.3, 0.3)),
           towards_camera=False)
    return d


def both_back():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
           d.material("two_sided", emissive=(0.3, 0.3, 0.3), double_sided=True), towards_camera=False)
    return d


def cull_mirrored():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2, d.material("one_sided", emissive=(0.3, 0.3, 0.3)),
           towards_camera=False, scale=[-1, 1, 1])
    return d


def mask_moving():
    d = _base()
    card = d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
                  d.material("cutout", emissive=(0.3, 0.3, 0.3), texture=d.texture(half_png()), mask=True))
    d.translate_x(card, 0.25)
    return d


def mixed():
    d = _base()
    card = d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
                  d.material("cutout", emissive=(0.3, 0.3, 0.3), texture=d.texture(checker_png()), mask=True))
    # raised off the pixel grid: unshifted, a row of wall pixels sees the card's shadow along a
    # texel boundary, where the bilinear alpha is the cutoff exactly for the whole slide and
    # rounding alone (different on the two backends) decides each sample
    d.nodes[card]["translation"] = [0.0, 0.0137, 0.0]
    d.translate_x(card, 0.25)
    d.quad("back", -0.5, 0.5, -0.5, 0.5, 0, d.material("one_sided", emissive=(0.3, 0.3, 0.3)),
           towards_camera=False, translation=[0.6, 0.4, -3])
    return d


ASSETS = {f.__name__: f for f in (mask_checker, cull_front, cull_back, both_back, cull_mirrored, mask_moving,
                                   mixed)}


def write_all(outdir):
    """Writes every scene as outdir/NAME.gltf; returns {name: path}."""
    os.makedirs(outdir, exist_ok=True)
    return {name: f().write(os.path.join(outdir, name + ".gltf")) for name, f in ASSETS.items()}


if __name__ == "__main__":
    write_all(sys.argv[1] if len(sys.argv) > 1 else ".")
