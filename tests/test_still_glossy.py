"""evray still on a glossy Cornell box (tests/cornell_glossy.py: a rough metal tall box, a glossy
dielectric floor): the path tracer and the photon pass, both over the metallic-roughness BSDF,
agree where the photon estimate applies (the diffuse walls, lit through the glossy surfaces
too), and the indirect light each adds is light, never darkness. At 48x48 with 1024 paths per
pixel, the path tracer's own noise is about a quarter of the walls' mean; the photon image at
the defaults (8 photons per pixel) measured 0.37 relative RMSE against it over the walls and
its indirect mean 9% below the path tracer's (the walls' own specular lobe reflects indirect
light the photon gather leaves out, core/photon.h)."""
import os
import re
import sys

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cornell_glossy  # noqa: E402  (standard library only)

tmp = T.tmpdir()
scene = cornell_glossy.make(T.EVRAY, os.path.join(tmp, "cornell_glossy.glb"))
walls = "left_wall,right_wall,back_wall,ceiling"
res = ("--res", "48x48", "--threads", "2")

imgs = {}
for gi, extra in (("none", ()), ("photon", ()), ("path", ("--spp", "1024"))):
    imgs[gi] = os.path.join(tmp, gi + ".pfm")
    T.run("still", scene, *res, "--gi", gi, *extra, "-o", imgs[gi], "-q")
none, photon, path = (T.read_pfm(imgs[k])[2] for k in ("none", "photon", "path"))
T.check(all(none[i] <= path[i] + 1e-6 and none[i] <= photon[i] + 1e-6 for i in range(len(none))),
        "indirect light adds, never removes (both methods)")


def region_stats(image, reference, region):
    """(relative RMSE, reference mean, reference indirect mean) over region, as `still --compare`
    prints them."""
    out = T.run("still", scene, *res, "--compare", image, "--reference", reference, "--region", region).stdout
    m = re.search(r"region \(" + re.escape(region) + r"\) \d+ pixels: relative RMSE ([0-9.]+) "
                  r"\(RMSE [0-9.e-]+, reference mean ([0-9.]+)\)", out)
    i = re.search(r"region indirect only: relative RMSE [0-9.]+ \(reference indirect mean ([0-9.]+)\)", out)
    T.check(m is not None and i is not None, f"region statistics printed ({out!r})")
    return (float(m.group(1)), float(m.group(2)), float(i.group(1))) if m and i else (1e9, 0.0, 0.0)


rmse, path_mean, path_ind = region_stats(imgs["photon"], imgs["path"], walls)
_, photon_mean, photon_ind = region_stats(imgs["path"], imgs["photon"], walls)
print(f"walls: photon vs path relative RMSE {rmse:.3f}; indirect mean photon {photon_ind:.4f}, "
      f"path {path_ind:.4f}")
T.check(rmse <= 0.5, f"walls: photon against path within 0.5 relative RMSE (got {rmse:.3f})")
T.check(abs(photon_ind - path_ind) <= 0.12 * path_ind,
        f"walls: the indirect light's means within 12% (photon {photon_ind:.4f}, path {path_ind:.4f})")
# the path tracer follows the metal's lobe: the box shows the lit room (its indirect light is
# most of what it shows; direct light gives it only the lamp's highlight); the photon gather
# weighs irradiance by the diffuse weight, which a metal has none of
_, tall_mean, tall_ind = region_stats(imgs["photon"], imgs["path"], "tall_box")
_, _, tall_photon_ind = region_stats(imgs["path"], imgs["photon"], "tall_box")
print(f"metal box: indirect mean path {tall_ind:.4f} of {tall_mean:.4f}, photon {tall_photon_ind:.4f}")
T.check(tall_ind > 0.5 * tall_mean, f"metal box: the path tracer's reflections ({tall_ind:.4f} of {tall_mean:.4f})")
T.check(tall_photon_ind == 0.0, f"metal box: no photon estimate ({tall_photon_ind:.4f})")
T.finish("test_still_glossy")
