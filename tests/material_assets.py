"""glTF test assets for materials (issue 21): every property evray reads, with known ground truth.

Standard library only (runs with /usr/bin/python3), written through tests/gltf_build.py: PNG
images and the buffer embedded as base64 data: URIs. Each asset is a function NAME(outdir) that writes
OUTDIR/NAME.gltf and returns its path; `python3 tests/material_assets.py OUTDIR` writes them all.

Common to all (unless an asset says otherwise): a camera node "camera" at the origin looking along
-Z, perspective with yfov = 2 atan(0.5) and aspect 1, so the plane z = -1 spans [-0.5, 0.5] in x
and y and fills the view; a point light "lamp" at the origin (KHR_lights_punctual, white, 1 cd:
irradiance 1 lx at the centre of the plane z = -1); one scene listing every root node.
A "quad" is two triangles at z = -1 spanning x, y in [-0.5, 0.5], normal +Z, TEXCOORD_0
u = x + 0.5, v = 0.5 - y: glTF's uv (0, 0) is the image's top-left texel, so every image appears
upright, its left half on the left of the view (x < 0). Pixel values below are 8-bit as written.

  slots              quad, material "slots": every metallic-roughness texture slot, each its own
                     image: baseColorTexture "quadrants" (2x2 RGBA: top-left (255,0,0),
                     top-right (0,255,0), bottom-left (0,0,255), bottom-right (128,128,128), all
                     alpha 255; sRGB, decoded), metallicRoughnessTexture "mr" (2x2, every texel
                     (0,128,64): roughness g = 128/255, metallic b = 64/255, linear),
                     normalTexture "tilt" (every texel (173,189,230), scale 0.5), occlusionTexture
                     "grey" (every texel (128,128,128): 128/255 linear, strength 0.75),
                     emissiveTexture "checker" (4x4, white where (column + row) is even, top-left
                     white; sRGB), KHR_materials_transmission (factor 0.5, texture "t200" every
                     texel (200,200,200): 200/255 linear). Factors: baseColorFactor
                     (0.9, 0.8, 0.7, 1), metallic 0.5, roughness 0.25, emissiveFactor
                     (1, 0.5, 0.25) with KHR_materials_emissive_strength 2 (emissive read as
                     (2, 1, 0.5)). All on TEXCOORD_0.
  colour_spaces      two quads side by side (x in [-0.5, 0] and [0, 0.5]) sharing ONE image "grey"
                     (128,128,128) through ONE texture: "grey_colour" uses it as baseColorTexture
                     (decoded sRGB: 0.2158605), "grey_data" as metallicRoughnessTexture (128/255 =
                     0.5019608 linear). The scene has 2 textures (one image decoded twice).
  texture_transform  quad with TEXCOORD_0 (as above) and TEXCOORD_1 = (u / 2, v / 2); material
                     "xf": baseColorTexture "quadrants" on texCoord 0 with KHR_texture_transform
                     offset (0.25, 0.5), rotation 0.5 rad, scale (2, 3) and texCoord 1 (the
                     override): uv matrix T * R * S = [[2 cos .5, 3 sin .5, .25],
                     [-2 sin .5, 3 cos .5, .5]] and the mesh keeps TEXCOORD_1. A second quad
                     (node "mixed", mesh "mixed", 2 units behind, x in [-1, 1]) with material
                     "mixed_uv": baseColorTexture on texCoord 0, normalTexture on texCoord 1: evray
                     keeps TEXCOORD_0 and warns naming "mixed_uv".
  alpha_mask_card    quad, material "card": MASK, alphaCutoff 0.4, doubleSided, baseColorTexture
                     "half_hole" (8x8 RGBA: columns 0-3 (255,0,0,0): the LEFT half (x < 0) is a
                     hole; columns 4-7 (255,255,255,255): opaque white). Behind it (z = -2,
                     x, y in [-1, 1]) an opaque black backdrop "backdrop" (material "black",
                     emissive 0, base (0,0,0)): through the hole the view is black.
  alpha_blend_card   quad, material "veil": BLEND, baseColorFactor (0.2, 0.4, 0.8, 0.5), untextured;
                     behind it (z = -2, x, y in [-1, 1]) an opaque white emissive backdrop
                     "backdrop" (material "white_glow": base (0,0,0), emissive (1,1,1)).
  transmission_slab  a box "slab" 2 x 2 x 0.2 (x, y in [-1, 1], z in [-1.2, -1.0] before the
                     turn) turned 30 degrees about +Y about its centre (0, 0, -1.1) (node
                     translation and rotation), material "glass": transmission 1,
                     KHR_materials_ior 1.5, KHR_materials_volume thicknessFactor 0.2,
                     attenuationDistance 2, attenuationColor (0.9, 0.8, 0.7),
                     KHR_materials_specular specularFactor 0.5, specularColorFactor
                     (1, 0.9, 0.8), metallic 0, roughness 0, doubleSided false. Behind it at z = -3
                     two quads: "left" (x in [-3, 0], material "dark": black, emissive 0) and
                     "right" (x in [0, 3], material "lit": black base, emissive 1): a vertical edge at x = 0. The slab's normal is
                     (sin 30, 0, cos 30); a ray crossing it at incidence angle a leaves it parallel
                     to itself, shifted perpendicular to itself by t sin(a) (1 - cos(a) /
                     sqrt(n^2 - sin^2(a))), t = 0.2, n = 1.5, towards -x (it bends towards the
                     inner normal). For the central ray (along -Z, a = 30 deg) that is 0.038763:
                     seen through the slab, the edge appears at x = +0.038763 on the backdrop
                     (the ray aimed there lands on x = 0), about 0.74 degrees right of the image
                     centre's column; other rays: the same formula with their own incidence angle.
  glint_sphere       a UV sphere "ball" (radius 0.4, centre (0, 0, -1.5), 160 segments x 80 rings),
                     material "tear_film": a smooth black dielectric (base (0,0,0), metallic 0,
                     roughness 0.05); the lamp at (0.6, 0.35, 0), intensity 10, extras radius
                     0.01 (a sphere light): its highlight lies at the point whose normal halves
                     the directions to the camera and the lamp.
  emissive_texture   quad, material "glow_checker": base (0,0,0,1), emissiveFactor (1, 1, 1),
                     KHR_materials_emissive_strength 5, emissiveTexture "checker" (4x4 cells of
                     0.25 x 0.25: white where (column + row) is even, the top-left cell white):
                     emitted radiance 5 on white cells, 0 on black ones.
  normal_plane_tangents  quad with TANGENT (1, 0, 0, 1) per vertex, material "bumpy":
                     normalTexture "tilt" (every texel (173,189,230): tangent-space normal
                     (0.36, 0.48, 0.8) to 8 bits, +x along +u, +y towards the image's top). The
                     world shading normal is (0.36, 0.48, 0.8) (unnormalized 8-bit decoding:
                     (173/255*2-1, 189/255*2-1, 230/255*2-1)).
  normal_plane       the same without TANGENT: evray generates tangent (1, 0, 0), w = +1.
  normal_plane_mirrored  the same without TANGENT and with u mirrored (u = 0.5 - x): the
                     generated tangent is (-1, 0, 0) with w = -1, the shading normal
                     (-0.36, 0.48, 0.8) (red tilt flips, green keeps pointing up).
  normal_plane_mirrored_tangents  normal_plane_mirrored with TANGENT (-1, 0, 0, -1) given: the
                     same frame read from the file (w = -1).
  normal_sphere      UV sphere "ball" (radius 0.4, centre (0, 0, -1.5), 24 segments x 12 rings;
                     the normal at (u, v) is (sin(th) sin(ph), cos(th), sin(th) cos(ph)) with
                     ph = 2 pi u, th = pi v: u = 0 faces +z (the camera), u = 0.25 faces +x,
                     v = 0 at the north pole +Y) without TANGENT,
                     material "bumpy" as above: generated tangents are unit, orthogonal to the
                     normals, along the direction of increasing u, w = +1.
  normal_warped      normal_sphere's sphere with warped uvs (u + 0.15 sin(2 pi v),
                     v + 0.1 sin(2 pi u)): tangents no longer follow the parallels (the same mesh,
                     warped_sphere(), is what tests/test_tangents_blender.c compares with
                     Blender's MikkTSpace).
  unsupported        quad, material "coated" with KHR_materials_clearcoat and
                     KHR_materials_sheen (not rendered: one warning each), material "volume_tex"
                     (second quad 2 units behind) with KHR_materials_volume thicknessTexture and
                     KHR_materials_specular specularTexture and specularColorTexture (ignored:
                     warnings); material "clamped" (third quad "far", 4 units behind) whose base
                     colour texture's sampler is CLAMP_TO_EDGE (evray repeats: a warning);
                     extensionsUsed also lists KHR_materials_iridescence (unused by any
                     material: one warning for the file).
  bad_ior            quad, material "bad_ior": KHR_materials_ior ior 0.5 (an error: ior must be 0
                     or >= 1).
  bad_factor         quad, material "bad_factor": metallicFactor -0.5 (an error).
  bad_cutoff         quad, material "bad_cutoff": MASK with alphaCutoff -0.1 (an error).
  bad_texture        quad, material "bad_texture": baseColorTexture index 7, the file has one
                     texture (an error).
"""
import math
import os
import sys

import gltf_build as B
from gltf_build import png_bytes

YFOV = B.YFOV


def _solid(rgb, n=2):
    return png_bytes(n, n, [rgb] * (n * n), 3)


IMAGES = {
    "quadrants": lambda: png_bytes(2, 2, [(255, 0, 0, 255), (0, 255, 0, 255),
                                          (0, 0, 255, 255), (128, 128, 128, 255)]),
    "mr": lambda: _solid((0, 128, 64)),
    "tilt": lambda: _solid((173, 189, 230)),
    "grey": lambda: _solid((128, 128, 128)),
    "t200": lambda: _solid((200, 200, 200)),
    "checker": lambda: png_bytes(4, 4, [(255, 255, 255) if (x + y) % 2 == 0 else (0, 0, 0)
                                        for y in range(4) for x in range(4)], 3),
    "half_hole": lambda: png_bytes(8, 8, [(255, 0, 0, 0) if x < 4 else (255, 255, 255, 255)
                                          for y in range(8) for x in range(8)]),
}


class Gltf(B.Gltf):
    """A document with the common camera (node 0) and lamp (node 1, a white point light of
    `lamp` cd at lamp_at, radius lamp_radius), the images of IMAGES by name."""

    def __init__(self, lamp=1.0, lamp_at=None, lamp_radius=None):
        super().__init__("evray tests/material_assets.py")
        self.camera()
        self.light("lamp", "point", lamp, radius=lamp_radius,
                   **({"translation": lamp_at} if lamp_at else {}))
        self.image_index = {}

    def texture(self, image):
        """The texture index of a named image of IMAGES (one texture per image)."""
        if image not in self.image_index:
            source = self.image(IMAGES[image](), name=image)
            self.image_index[image] = super().texture(source)
        return self.image_index[image]

    def clamped_texture(self, image):
        """A second texture of a named image, sampled with CLAMP_TO_EDGE in u and v."""
        source = self.textures[self.texture(image)]["source"]
        if not self.samplers:
            self.sampler(wrapS=B.CLAMP_TO_EDGE, wrapT=B.CLAMP_TO_EDGE)
        return super().texture(source, sampler=0)

    def write(self, outdir, name, extra_used=()):
        self.used |= set(extra_used)
        return super().write(os.path.join(outdir, name + ".gltf"), indent=1)


def _quad(g, name, material, **kw):
    mirrored = kw.pop("mirrored", False)
    pos, nrm, uv, idx = B.rect(-0.5, 0.5, -0.5, 0.5, -1.0, mirrored)
    g.mesh_node(name, pos, nrm, uv, idx, material, **kw)


def _tex(g, image, **kw):
    t = {"index": g.texture(image)}
    t.update(kw)
    return t


# ---- assets ----

def slots(outdir):
    g = Gltf()
    m = g.material({
        "name": "slots",
        "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.7, 1.0],
                                 "baseColorTexture": _tex(g, "quadrants"),
                                 "metallicFactor": 0.5, "roughnessFactor": 0.25,
                                 "metallicRoughnessTexture": _tex(g, "mr")},
        "normalTexture": _tex(g, "tilt", scale=0.5),
        "occlusionTexture": _tex(g, "grey", strength=0.75),
        "emissiveTexture": _tex(g, "checker"),
        "emissiveFactor": [1.0, 0.5, 0.25],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0},
                       "KHR_materials_transmission": {"transmissionFactor": 0.5,
                                                      "transmissionTexture": _tex(g, "t200")}}})
    _quad(g, "quad", m)
    return g.write(outdir, "slots")


def colour_spaces(outdir):
    g = Gltf()
    a = g.material({"name": "grey_colour",
                    "pbrMetallicRoughness": {"baseColorTexture": _tex(g, "grey")}})
    b = g.material({"name": "grey_data",
                    "pbrMetallicRoughness": {"metallicRoughnessTexture": _tex(g, "grey")}})
    for name, mat, x0, x1 in (("left", a, -0.5, 0.0), ("right", b, 0.0, 0.5)):
        pos, nrm, uv, idx = B.rect(x0, x1, -0.5, 0.5, -1.0)
        g.mesh_node(name, pos, nrm, uv, idx, mat)
    return g.write(outdir, "colour_spaces")


def texture_transform(outdir):
    g = Gltf()
    xf = {"KHR_texture_transform": {"offset": [0.25, 0.5], "rotation": 0.5, "scale": [2, 3],
                                    "texCoord": 1}}
    m = g.material({"name": "xf", "pbrMetallicRoughness": {
        "baseColorTexture": _tex(g, "quadrants", texCoord=0, extensions=xf)}})
    mixed = g.material({"name": "mixed_uv",
                        "pbrMetallicRoughness": {"baseColorTexture": _tex(g, "quadrants")},
                        "normalTexture": _tex(g, "tilt", texCoord=1)})
    pos, nrm, uv, idx = B.rect(-0.5, 0.5, -0.5, 0.5, -1.0)
    g.mesh_node("quad", pos, nrm, uv, idx, m, uvs1=[(u / 2, v / 2) for u, v in uv])
    pos, nrm, uv, idx = B.rect(-1, 1, -1, 1, -3.0)
    g.mesh_node("mixed", pos, nrm, uv, idx, mixed, uvs1=[(u / 2, v / 2) for u, v in uv])
    return g.write(outdir, "texture_transform")


def _backdrop(g, material, z=-2.0, half=1.0, name="backdrop"):
    pos, nrm, uv, idx = B.rect(-half, half, -half, half, z)
    g.mesh_node(name, pos, nrm, uv, idx, material)


def alpha_mask_card(outdir):
    g = Gltf()
    m = g.material({"name": "card", "alphaMode": "MASK", "alphaCutoff": 0.4, "doubleSided": True,
                    "pbrMetallicRoughness": {"baseColorTexture": _tex(g, "half_hole"),
                                             "metallicFactor": 0}})
    black = g.material({"name": "black", "pbrMetallicRoughness": {
        "baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}})
    _quad(g, "quad", m)
    _backdrop(g, black)
    return g.write(outdir, "alpha_mask_card")


def alpha_blend_card(outdir):
    g = Gltf()
    m = g.material({"name": "veil", "alphaMode": "BLEND", "pbrMetallicRoughness": {
        "baseColorFactor": [0.2, 0.4, 0.8, 0.5], "metallicFactor": 0}})
    white = g.material({"name": "white_glow", "emissiveFactor": [1, 1, 1],
                        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1],
                                                 "metallicFactor": 0}})
    _quad(g, "quad", m)
    _backdrop(g, white)
    return g.write(outdir, "alpha_blend_card")


def transmission_slab(outdir):
    g = Gltf()
    glass = g.material({
        "name": "glass",
        "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0,
                                 "roughnessFactor": 0},
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_ior": {"ior": 1.5},
            "KHR_materials_volume": {"thicknessFactor": 0.2, "attenuationDistance": 2.0,
                                     "attenuationColor": [0.9, 0.8, 0.7]},
            "KHR_materials_specular": {"specularFactor": 0.5,
                                       "specularColorFactor": [1.0, 0.9, 0.8]}}})
    dark = g.material({"name": "dark", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1],
                                                                "metallicFactor": 0}})
    lit = g.material({"name": "lit", "emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {
        "baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}})
    pos, nrm, uv, idx = B.box(-1, 1, -1, 1, -0.1, 0.1)
    g.mesh_node("slab", pos, nrm, uv, idx, glass, translation=(0, 0, -1.1),
                rotation=B.quaternion((0, 1, 0), 30))
    for name, mat, x0, x1 in (("left", dark, -3, 0), ("right", lit, 0, 3)):
        pos, nrm, uv, idx = B.rect(x0, x1, -3, 3, -3.0)
        g.mesh_node(name, pos, nrm, uv, idx, mat)
    return g.write(outdir, "transmission_slab")


def emissive_texture(outdir):
    g = Gltf()
    m = g.material({"name": "glow_checker", "emissiveFactor": [1, 1, 1],
                    "emissiveTexture": _tex(g, "checker"),
                    "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1],
                                             "metallicFactor": 0},
                    "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5}}})
    _quad(g, "quad", m)
    return g.write(outdir, "emissive_texture")


def _bumpy(g):
    return g.material({"name": "bumpy", "normalTexture": _tex(g, "tilt"),
                       "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.5}})


def normal_plane_tangents(outdir):
    g = Gltf()
    _quad(g, "quad", _bumpy(g), tangents=[(1, 0, 0, 1)] * 4)
    return g.write(outdir, "normal_plane_tangents")


def normal_plane(outdir):
    g = Gltf()
    _quad(g, "quad", _bumpy(g))
    return g.write(outdir, "normal_plane")


def normal_plane_mirrored(outdir):
    g = Gltf()
    _quad(g, "quad", _bumpy(g), mirrored=True)
    return g.write(outdir, "normal_plane_mirrored")


def normal_plane_mirrored_tangents(outdir):
    g = Gltf()
    _quad(g, "quad", _bumpy(g), mirrored=True, tangents=[(-1, 0, 0, -1)] * 4)
    return g.write(outdir, "normal_plane_mirrored_tangents")


GLINT_CENTRE, GLINT_RADIUS, GLINT_LAMP = (0.0, 0.0, -1.5), 0.4, (0.6, 0.35, 0.0)


def glint_sphere(outdir):
    g = Gltf(lamp=10.0, lamp_at=GLINT_LAMP, lamp_radius=0.01)
    black = g.material({"name": "tear_film", "pbrMetallicRoughness": {
        "baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 0.05}})
    pos, nrm, uv, idx = B.uv_sphere(radius=GLINT_RADIUS, segments=160, rings=80)
    g.mesh_node("ball", pos, nrm, uv, idx, black, translation=GLINT_CENTRE)
    return g.write(outdir, "glint_sphere")


def normal_sphere(outdir):
    g = Gltf()
    pos, nrm, uv, idx = B.uv_sphere()
    g.mesh_node("ball", pos, nrm, uv, idx, _bumpy(g), translation=(0, 0, -1.5))
    return g.write(outdir, "normal_sphere")


def warped_sphere():
    """B.uv_sphere() with its uvs warped: (u + 0.15 sin(2 pi v), v + 0.1 sin(2 pi u))."""
    pos, nrm, uv, idx = B.uv_sphere()
    uv = [(u + 0.15 * math.sin(2 * math.pi * v), v + 0.1 * math.sin(2 * math.pi * u))
          for u, v in uv]
    return pos, nrm, uv, idx


def normal_warped(outdir):
    g = Gltf()
    pos, nrm, uv, idx = warped_sphere()
    g.mesh_node("ball", pos, nrm, uv, idx, _bumpy(g), translation=(0, 0, -1.5))
    return g.write(outdir, "normal_warped")


def unsupported(outdir):
    g = Gltf()
    coated = g.material({"name": "coated", "extensions": {
        "KHR_materials_clearcoat": {"clearcoatFactor": 1.0},
        "KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1]}}})
    vol = g.material({"name": "volume_tex", "extensions": {
        "KHR_materials_transmission": {"transmissionFactor": 1.0},
        "KHR_materials_volume": {"thicknessFactor": 0.1, "thicknessTexture": _tex(g, "grey")},
        "KHR_materials_specular": {"specularTexture": _tex(g, "grey"),
                                   "specularColorTexture": _tex(g, "quadrants")}}})
    clamped = g.material({"name": "clamped", "pbrMetallicRoughness": {
        "baseColorTexture": {"index": g.clamped_texture("quadrants")}}})
    _quad(g, "quad", coated)
    pos, nrm, uv, idx = B.rect(-1, 1, -1, 1, -3.0)
    g.mesh_node("back", pos, nrm, uv, idx, vol)
    pos, nrm, uv, idx = B.rect(-2, 2, -2, 2, -5.0)
    g.mesh_node("far", pos, nrm, uv, idx, clamped)
    return g.write(outdir, "unsupported", extra_used=["KHR_materials_iridescence"])


def _bad(outdir, name, mat, needs_texture=False):
    g = Gltf()
    if needs_texture:
        g.texture("grey")
    mat["name"] = name
    _quad(g, "quad", g.material(mat))
    return g.write(outdir, name)


def bad_ior(outdir):
    return _bad(outdir, "bad_ior", {"extensions": {"KHR_materials_ior": {"ior": 0.5}}})


def bad_factor(outdir):
    return _bad(outdir, "bad_factor", {"pbrMetallicRoughness": {"metallicFactor": -0.5}})


def bad_cutoff(outdir):
    return _bad(outdir, "bad_cutoff", {"alphaMode": "MASK", "alphaCutoff": -0.1})


def bad_texture(outdir):
    return _bad(outdir, "bad_texture", {"pbrMetallicRoughness": {"baseColorTexture": {"index": 7}}},
                needs_texture=True)


ASSETS = [slots, colour_spaces, texture_transform, alpha_mask_card, alpha_blend_card,
          transmission_slab, glint_sphere, emissive_texture, normal_plane_tangents, normal_plane,
          normal_plane_mirrored, normal_plane_mirrored_tangents, normal_sphere,
          normal_warped, unsupported, bad_ior, bad_factor, bad_cutoff,
          bad_texture]


def write_all(outdir):
    """Writes every asset into outdir; returns {name: path}."""
    os.makedirs(outdir, exist_ok=True)
    return {f.__name__: f(outdir) for f in ASSETS}


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: material_assets.py OUTDIR")
    for path in write_all(sys.argv[1]).values():
        print(path)
