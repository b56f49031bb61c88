"""A skinned arm and a morph-target face made by Blender and written by Blender's own glTF exporter
(tests/blender_assets.py, run by Debian's blender 3.4 headless; scripts/test-blender.sh installs
it) render with events where and when the mesh moves, and nowhere else.

Blender evaluates each deformed mesh at every frame and projects it with the file's camera; its
sidecar NAME.json gives per phase of motion the time span, the pixel box of the faces that move
in it and the box of the vertices that stay, and the box the object covers over the whole
animation. evray renders each file on the CPU (160x120, 2 s, segments on Blender's 24 frames per
second) and, with an ideal sensor:
  - events occur (each phase has plenty, spread over the phase: the motion is continuous);
  - when: none before the first phase or after the last (a frame's margin);
  - where: inside a phase, its events lie in the moving box, none in the part of the still box
    that the moving box does not reach (the arm's root and, while the forearm bends, its upper
    arm; the face's left half while its right side bulges, its lower part while its top rises),
    and none in the background outside the object's box.
Skips (77) when there is no Blender."""
import json
import os
import shutil
import subprocess
import time

import numpy as np

import evrtest as T

NAME = "test_blender"
FRAME = 1.0 / 24.0      # time margin: one of Blender's frames (the file's keys are per frame)
PAD = 2                 # pixels around a box: projection vs. pixel footprint, antialiasing
MIN_EVENTS_PHASE = 100
OUTSIDE_SHARE = 0.002   # ideal sensor, nothing changes there: the tolerance is for stray samples


def blender_program():
    path = os.environ.get("EVR_BLENDER") or shutil.which("blender")
    if not path:
        T.skip(NAME, "no Blender: Debian 12's 'blender' package (scripts/test-blender.sh installs it; "
               "it needs the package registry) or EVR_BLENDER=/path/to/blender")
    return path


def build_assets(blender, out):
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "blender_assets.py")
    start = time.time()
    try:
        p = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P", script,
                            "--", out], capture_output=True, text=True, timeout=300)
    except subprocess.TimeoutExpired:
        raise SystemExit(f"{NAME}: {blender} did not finish blender_assets.py in 300 s")
    if p.returncode != 0:
        print(p.stdout[-4000:], p.stderr[-4000:])
        raise SystemExit(f"{NAME}: {blender} -P blender_assets.py: exit {p.returncode}")
    print(f"{NAME}: Blender built the assets in {time.time() - start:.1f} s")


def inside(ev, box, pad):
    """Events whose pixel overlaps box (x0, y0, x1, y1 in pixel units, rows down) grown by pad."""
    x0, y0, x1, y1 = box
    x, y = ev["x"].astype(float), ev["y"].astype(float)
    return (x + 1 > x0 - pad) & (x < x1 + pad) & (y + 1 > y0 - pad) & (y < y1 + pad)


def pixels_in(box, pad, w, h):
    """Pixel centres of the image inside box grown by pad (a boolean image)."""
    x0, y0, x1, y1 = box
    xs, ys = np.arange(w) + 0.5, np.arange(h) + 0.5
    return (((xs > x0 - pad) & (xs < x1 + pad))[None, :]) & (((ys > y0 - pad) & (ys < y1 + pad))[:, None])


def check_file(tmp, side):
    name = os.path.splitext(side["file"])[0]
    w, h = side["resolution"]
    out = os.path.join(tmp, name)
    start = time.time()
    T.run("render", os.path.join(tmp, side["file"]), "-o", out, "--res", f"{w}x{h}", "--duration",
          side["duration"], "--fps", side["fps"], "--backend", "cpu", "--format", "npy", "--no-preview",
          "--quiet")
    print(f"{NAME}: {name}: rendered in {time.time() - start:.1f} s")
    ev = np.load(os.path.join(out, "events.npy"))
    t = ev["t"] * 1e-6
    n = len(ev)
    phases = side["phases"]
    T.check(n >= MIN_EVENTS_PHASE * len(phases), f"{name}: events where the mesh moves ({n})")
    if n == 0:
        return

    # when: nothing before the first phase starts or after the last one ends
    early = int(np.sum(t < phases[0]["t0"] - FRAME))
    late = int(np.sum(t > phases[-1]["t1"] + FRAME))
    T.check(early + late <= OUTSIDE_SHARE * n,
            f"{name}: no events while nothing moves (before {phases[0]['t0']:.3f} s: {early}, "
            f"after {phases[-1]['t1']:.3f} s: {late})")

    # where: nothing in the background
    bg = int(np.sum(~inside(ev, side["object_box"], PAD)))
    print(f"{NAME}: {name}: {n} events, {early} before the motion, {late} after, {bg} in the background")
    T.check(bg <= OUTSIDE_SHARE * n, f"{name}: no events outside the object's box {side['object_box']} ({bg})")

    for ph in phases:
        label = f"{name}: phase '{ph['name']}' ({ph['t0']:.3f}-{ph['t1']:.3f} s)"
        # its inside: a frame off each end, where the neighbouring phase may still be moving
        sel = (t > ph["t0"] + FRAME) & (t < ph["t1"] - FRAME)
        e = ev[sel]
        k = len(e)
        T.check(k >= MIN_EVENTS_PHASE, f"{label}: events ({k})")
        if k == 0:
            continue
        mid = 0.5 * (ph["t0"] + ph["t1"])
        first = int(np.sum(t[sel] < mid))
        T.check(0.2 * k <= first <= 0.8 * k,
                f"{label}: events spread over the phase ({first} of {k} in its first half)")
        moving = inside(e, ph["moving_box"], PAD)
        T.check(np.sum(moving) >= 0.99 * k,
                f"{label}: events in the moving box {ph['moving_box']} ({int(np.sum(moving))} of {k})")
        if ph["still_box"] is None:
            continue
        # the still part the moving box does not reach: the test is only as good as its size
        still_only = pixels_in(ph["still_box"], -PAD, w, h) & ~pixels_in(ph["moving_box"], PAD + 1, w, h)
        T.check(int(still_only.sum()) >= 100,
                f"{label}: the still region the test watches is large enough ({int(still_only.sum())} px)")
        quiet = int(np.sum(still_only[e["y"].astype(int), e["x"].astype(int)]))
        print(f"{NAME}: {label}: {k} events, {first} in its first half, {int(np.sum(moving))} in the "
              f"moving box, {quiet} in the still part ({int(still_only.sum())} px)")
        T.check(quiet <= OUTSIDE_SHARE * k, f"{label}: no events in the part that stays still ({quiet} of {k})")


blender = blender_program()
tmp = T.tmpdir()
build_assets(blender, tmp)
for name in ("arm", "face"):
    with open(os.path.join(tmp, name + ".json")) as f:
        check_file(tmp, json.load(f))
T.finish(NAME)
