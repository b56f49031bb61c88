"""Global illumination in the event pipeline (--gi photon, CPU backend) with a gather at every
sample (--gi-blur 0; the blurred estimate, the default, is tests/test_gi_blur.py's): a still
Cornell box makes no events with GI on (the same photons every segment), with and without change-driven sampling;
the moving box's events are identical with and without skipping; GI changes the intensities;
run.json accounts for the photon passes; GI's events do not cluster at segment boundaries (the
indirect light is interpolated in time); the per-pixel gather memo and the reuse of photon trails
change no event (uniform and adaptive sampling); bad options give one-line errors."""
import os

import evrtest as T

tmp = T.tmpdir()


def render(name, scene, *extra, env=None):
    d = os.path.join(tmp, name)
    T.run_env(env, "demo", "--scene", scene, "-o", d, "--backend", "cpu", "--format", "npy", "--no-preview", "--quiet",
          "--res", "64x48", *extra)
    return open(os.path.join(d, "events.npy"), "rb").read(), T.load_run_json(d)


for mode in ([], ["--no-skip"]):
    ev, js = render("still" + "".join(mode), "cornell-still", "--gi", "photon", "--gi-blur", "0", "--duration", "1", *mode)
    st = js["stats"]
    T.check(st["events"] == 0, f"still Cornell box, GI on {mode}: no events ({st['events']})")
    T.check(js["config"]["gi"] == "photon" and st["photons_traced"] > 0, "GI in run.json")
    # a pass at every segment's end, and one at the first segment's start
    if mode:
        T.check(st["photon_passes"] == st["segments"] + 1, "brute force: a photon pass every segment")
    else:
        T.check(st["photon_passes"] == 2, f"nothing moves: the first segment's two photon passes ({st['photon_passes']})")

ev_s, js = render("moving", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "0.5")
ev_b, jb = render("moving-brute", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "0.5", "--no-skip")
ev_d, jd = render("direct", "cornell", "--duration", "0.5")
print(f"cornell 0.5 s: {js['stats']['events']} events with GI, {jd['stats']['events']} without; traced "
      f"{js['stats']['samples_traced']} of {js['stats']['samples']} samples; {js['stats']['photon_passes']} photon passes")
T.check(js["stats"]["events"] > 0 and ev_s == ev_b, "moving box, GI on: identical events with and without skipping")
T.check(js["stats"]["samples_traced"] < jb["stats"]["samples_traced"], "moving box, GI on: pixels are still skipped")
T.check(ev_s != ev_d, "GI changes the events")


# the indirect light is linear in time between the photon passes at the segment boundaries, so
# GI's events do not cluster there (with one buffer per segment, a step at every boundary: 60% of
# the events within a tenth of a segment of one, against 18% with direct light only)
share_gi = T.boundary_share(ev_s, js["stats"]["segments"], 0.5)
share_direct = T.boundary_share(ev_d, jd["stats"]["segments"], 0.5)
print(f"events within a tenth of a segment of a boundary: GI {share_gi:.3f}, direct light only {share_direct:.3f}")
T.check(share_gi < 0.3 and share_gi < 1.5 * share_direct, "GI's events do not cluster at segment boundaries")
# a pixel reuses its last gather while its hit and its window are unchanged: gathering at every
# sample instead (EVR_GI_NO_MEMO) gives the same events
ev_m, jm = render("no-memo", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "0.5", "--no-skip", env="EVR_GI_NO_MEMO")
T.check(ev_m == ev_b, "GI: the same events without the gather memo")
# the same with adaptive sampling (its tiles must forget a pixel's gather when its window changed)
ev_a, ja = render("adaptive", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "0.5", "--sampling", "adaptive")
ev_am, jam = render("adaptive-no-memo", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "0.5", "--sampling", "adaptive",
                    env="EVR_GI_NO_MEMO")
T.check(ja["stats"]["events"] > 0 and ev_a == ev_am, "GI with adaptive sampling: the same events without the gather memo")
# a photon whose last path met nothing that moves keeps its outcome instead of being traced again
# (its trail, core/photon.h): the same events as tracing every photon (EVR_NO_PHOTON_REUSE), most
# photons of the moving box's passes reused, none under brute force
st = js["stats"]
ev_t, jt = render("no-reuse", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "0.5", env="EVR_NO_PHOTON_REUSE")
print(f"photon trails: {st['photons_reused']} reused, {st['photons_traced']} traced in {st['photon_passes']} passes; "
      f"without reuse {jt['stats']['photons_traced']} traced")
T.check(ev_t == ev_s, "GI: the same events with and without reusing photon trails")
T.check(jt["stats"]["photons_reused"] == 0 and st["photons_reused"] > st["photons_traced"],
        "GI: most photons reuse their trails while the box moves")
T.check(st["photons_reused"] + st["photons_traced"] == jt["stats"]["photons_traced"],
        "GI: every photon is either traced or reused")
T.check(jb["stats"]["photons_reused"] == 0, "GI brute force (--no-skip): no photon reuses its trail")

# the photon buffer holds what the pass sends it: 8 layers a pixel for each photon per pixel
# (at most 64) unless --photon-layers says otherwise, and a run whose buffer dropped more than 1%
# of its photons says so in one warning line (run.json counts them)
def layers_run(name, *extra):
    d = os.path.join(tmp, name)
    p = T.run("demo", "--scene", "cornell", "-o", d, "--backend", "cpu", "--format", "npy", "--no-preview", "--quiet",
              "--res", "64x48", "--gi", "photon", "--gi-blur", "0", "--duration", "0.3", *extra)
    return p, T.load_run_json(d)["stats"]


pixels = 64 * 48
p1, s1 = layers_run("layers-default")
p4, s4 = layers_run("layers-4", "--photons", str(4 * pixels))
p16, s16 = layers_run("layers-16", "--photons", str(16 * pixels))
p16c, s16c = layers_run("layers-16-capped", "--photons", str(16 * pixels), "--photon-layers", "8")
for what, st in (("default", s1), ("4 a pixel", s4), ("16 a pixel", s16), ("16 a pixel, 8 layers", s16c)):
    print(f"photon buffer, {what}: {st['photon_layers']} layers, {st['photons_stored']} stored, "
          f"{st['photon_collisions']} dropped")
T.check((s1["photon_layers"], s4["photon_layers"], s16["photon_layers"], s16c["photon_layers"]) == (8, 32, 64, 8),
        "the photon buffer's layers follow the photons per pixel, or --photon-layers")
for p, st in ((p1, s1), (p4, s4), (p16, s16)):
    T.check(st["photon_collisions"] <= 0.01 * (st["photons_stored"] + st["photon_collisions"]) and
            "photon buffer" not in p.stderr, f"{st['photon_layers']} layers keep the photons, no warning ({p.stderr})")
dropped = s16c["photon_collisions"]
T.check(dropped > 0.01 * (s16c["photons_stored"] + dropped), "16 photons a pixel in 8 layers: photons dropped")
warn = [l for l in p16c.stderr.splitlines() if "photon buffer" in l]
T.check(len(warn) == 1 and warn[0].startswith("evray: warning: ") and f"{dropped} of " in warn[0] and
        "--photon-layers 8" in warn[0], f"dropped photons: one warning line with the count ({p16c.stderr})")

# the short box's right face, seen at a grazing angle (cosine 0.3): the gather's normalization
# over what the camera sees takes each cell's footprint as a strip, not its centre point, so the
# face's indirect light does not swing within every segment as the box slides (with centre
# points, 16 photons a pixel made 4.9 times direct light's events there, in ON and OFF bursts at
# the segment rate; 2.2 times now: docs/benchmarks.md, "... fidelity")
def face_events(name, *extra):
    d = os.path.join(tmp, name)
    T.run("demo", "--scene", "cornell", "-o", d, "--backend", "cpu", "--format", "npy", "--no-preview", "--quiet",
          "--res", "173x130", "--duration", "1", *extra)
    xy = T.npy_event_pixels(open(os.path.join(d, "events.npy"), "rb").read())
    return sum(1 for x, y in xy if 110 <= x < 120 and 90 <= y < 110)


# there the normalization is on (the disk spans more than three pixels): skipping stays exact,
# the cells a changed footprint reaches included (evr_photon_cell_reaches)
big = []
for mode in ([], ["--no-skip"]):
    d = os.path.join(tmp, "big" + "".join(mode))
    T.run("demo", "--scene", "cornell", "-o", d, "--backend", "cpu", "--format", "npy", "--no-preview", "--quiet",
          "--res", "173x130", "--duration", "0.5", "--gi", "photon", "--gi-blur", "0", *mode)
    big.append(open(os.path.join(d, "events.npy"), "rb").read())
T.check(len(big[0]) > 10000 and big[0] == big[1], "GI at 173x130: identical events with and without skipping")
face_direct = face_events("face-direct", "--samples-per-frame", "10")
face_gi = face_events("face-gi", "--gi", "photon", "--gi-blur", "0", "--photons", str(16 * 173 * 130))
print(f"the short box's grazing face (x 110-119, y 90-109): {face_gi} events with GI, {face_direct} without")
T.check(face_direct > 500 and face_gi < 3 * face_direct,
        "GI on a grazing moving face: under 3x direct light's events (no bursts at the segment rate)")


# cornell-bleed: the red short box slides along the white right wall; the wall above the box is
# redder (red / green) beside the box than 0.4 m from it, with GI only, and the tint follows the box
def wall_redness(pfm, z):
    """red / green of the right wall (x = 0.5) at depth z, 0.34-0.46 m up (above the box)"""
    rows = T.pfm_rows(pfm)
    h, w = len(rows), len(rows[0])
    dz, tan_half = 1.9 - z, 0.5 / 1.4  # the camera at (0, 0.5, 1.9), square image
    red = green = 0.0
    for y_wall in (0.34, 0.38, 0.42, 0.46):
        x = int(w / 2 + w / 2 * (0.5 / dz) / tan_half)
        y = int(h / 2 - h / 2 * ((y_wall - 0.5) / dz) / tan_half)
        for dx in (-1, 0):
            red += rows[y][x + dx][0]
            green += rows[y][x + dx][1]
    return red / green


for t, near, far in (("0", 0.2, -0.2), ("1", -0.2, 0.2)):  # the box at z = 0.2, then at -0.2
    lit = {}
    for gi in ("photon", "none"):
        pfm = os.path.join(tmp, f"bleed-{gi}-{t}.pfm")
        T.run("still", "--scene", "cornell-bleed", "--gi", gi, "--time", t, "--res", "128x128", "-q", "-o", pfm)
        lit[gi] = (wall_redness(pfm, near), wall_redness(pfm, far))
    print(f"cornell-bleed at {t} s, the wall's red / green beside the box and away from it: GI {lit['photon']}, "
          f"direct {lit['none']}")
    T.check(abs(lit["none"][0] - lit["none"][1]) < 0.01, "cornell-bleed, direct light: the white wall is as white "
            "beside the box as away from it")
    T.check(lit["photon"][0] > lit["photon"][1] + 0.05, f"cornell-bleed at {t} s: GI bleeds the moving box's red onto "
            "the wall beside it")

bad = [["--gi", "sunlight"], ["--gi", "path"], ["--gi", "photon", "--gi-blur", "0", "--photon-layers", "4097"],
       ["--gi", "photon", "--gi-blur", "0", "--gather-max", "-1"], ["--gi", "photon", "--gi-blur", "0", "--gather-radius", "-1"],
       ["--gi", "photon", "--gi-blur", "0", "--photons", "x"]]
for args in bad:
    p = T.run("demo", "--scene", "cornell", "-o", os.path.join(tmp, "bad"), "--duration", "0.1", "--quiet", *args,
              expect=None)
    T.check(p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, f"{args}: one-line error, exit 2 ({p.stderr})")
    T.check(not os.path.exists(os.path.join(tmp, "bad")), f"{args}: nothing left behind")
T.finish("test_gi")
