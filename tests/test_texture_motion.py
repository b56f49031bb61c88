"""A fine texture moving under the camera does not alias into events (textures filtered by the
ray's footprint: mip levels and ray cones, core/material.h).

The scene: a plane z = 0, 6 x 6 units, lit, textured with a 1024 x 1024 checkerboard of checks
`check` texels wide, sliding along +x at 0.1 units/s, seen from z = 4 (yfov 0.8) at 48 x 48: a
pixel spans about 12 texels, a step between samples about a twentieth of a texel.
- fine (checks of 3 texels, a quarter of a pixel): filtered, every pixel sees the checks' mean;
  the image matches the same plane untextured with base colour 0.5 (the analytic mean) within a
  few percent, and the motion makes (almost) no events. Point-sampled (level 0 only: the build
  before mip levels, measured once) every pixel flickers between black and white: 147,811
  events over the 0.5 s.
- coarse (checks of 48 texels, 4 pixels): resolved by the pixels, the same motion makes many
  events: the scene's motion is real, the fine texture's silence is the filtering's."""
import os

import evrtest as T
import gltf_build as B

W = H = 48
TEX = 1024


def png_grey(path, n, value):
    """An 8-bit greyscale n x n PNG with pixel (x, y) = value(x, y)."""
    with open(path, "wb") as f:
        f.write(B.png_bytes(n, n, [value(x, y) for y in range(n) for x in range(n)], channels=1))


def plane_gltf(path, texture):
    """The sliding plane with texture (a PNG beside it) or, texture None, base colour 0.5."""
    g = B.Gltf()
    g.camera("cam", yfov=0.8, translation=[0, 0, 4])
    # a matte dielectric (Lambert: no specular layer), whose intensity is its base colour's
    pbr = {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0.0}
    if texture:
        pbr = {"baseColorTexture": {"index": g.texture(g.image(uri=texture))}, "metallicFactor": 0.0}
    mat = g.material({"pbrMetallicRoughness": pbr,
                      "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}})
    plane = g.mesh_node("plane", *B.rect(-3, 3, -3, 3, 0), mat)
    g.light("sun", "directional", 3.0, rotation=[-0.2588190, 0, 0, 0.9659258])
    g.animation([(plane, "translation", [0.0, 1.0], [(0, 0, 0), (0.1, 0, 0)])])
    g.write(path)


def events(scene, name):
    d = os.path.join(tmp, name)
    T.run("render", scene, "-o", d, "--res", f"{W}x{H}", "--duration", 0.5, "--fps", 30,
          "--samples-per-frame", 10, "--format", "txt", "--no-preview", "--threads", 2, "--quiet")
    with open(os.path.join(d, "events.txt")) as f:
        return sum(1 for line in f if line.strip() and not line.startswith("#"))


def image(scene, name):
    pfm = os.path.join(tmp, name + ".pfm")
    T.run("still", scene, "--res", f"{W}x{H}", "--threads", 2, "-o", pfm)
    return T.read_pfm(pfm)[2]


tmp = T.tmpdir()
for check in (3, 48):
    png_grey(os.path.join(tmp, f"checker{check}.png"), TEX,
             lambda x, y, c=check: 255 if (x // c + y // c) % 2 else 0)
    plane_gltf(os.path.join(tmp, f"checker{check}.gltf"), f"checker{check}.png")
plane_gltf(os.path.join(tmp, "grey.gltf"), None)

fine = image(os.path.join(tmp, "checker3.gltf"), "fine")
grey = image(os.path.join(tmp, "grey.gltf"), "grey")
worst = max(abs(a - b) / b for a, b in zip(fine[1::3], grey[1::3]))
print(f"fine checkerboard vs its mean, untextured: largest relative difference {worst:.4f}")
T.check(min(grey[1::3]) > 0.1, "the plane fills the image, lit")
T.check(worst < 0.05, f"the fine checkerboard looks like its mean (largest difference {worst:.4f})")

n_fine = events(os.path.join(tmp, "checker3.gltf"), "fine")
n_coarse = events(os.path.join(tmp, "checker48.gltf"), "coarse")
print(f"events: fine checkerboard {n_fine}, coarse {n_coarse}")
T.check(n_coarse > 500, f"the resolved checkerboard's motion makes events ({n_coarse})")
T.check(n_fine <= 0.01 * n_coarse, f"the fine checkerboard's motion makes almost none ({n_fine})")
T.finish("test_texture_motion")
