"""Animation clips on the command line: clips on disjoint nodes play together; of clips sharing a
node the first plays and the notice names the others; --animation NAME|INDEX|all chooses (render,
still, info); a clip the file lacks is one line and a non-zero exit; the duration `evray info`
prints is one `evray render --duration` takes and plays to the clip's end. Where a quad is comes
from `evray still` images (PFM) at one time."""
import math
import os
import re

import evrtest as T

tmp = T.tmpdir()
RES = 48


def quad_at(scene, t, *animation):
    """{node: (centre x, centre y, lit pixels)} of the quads at time t in image pixels (x to the
    right, y up), "a" the left half of the image and "b" the right half."""
    out = os.path.join(tmp, "still.pfm")
    T.run("still", scene, "--time", t, "--res", f"{RES}x{RES}", "-q", "-o", out, *animation)
    w, h, px = T.read_pfm(out)
    found = {}
    for node, xs in (("a", range(0, w // 2)), ("b", range(w // 2, w))):
        sx = sy = n = 0
        for y in range(h):  # rows bottom to top: y grows upwards
            for x in xs:
                if px[3 * (y * w + x)] > 0.05:
                    sx, sy, n = sx + x, sy + y, n + 1
        found[node] = (sx / n, sy / n, n) if n else (math.nan, math.nan, 0)
    return found


def moved(before, after):
    return after[0] - before[0], after[1] - before[1]


def render(scene, *args):
    """(exit code, stderr, run.json or None) of a small render."""
    d = os.path.join(tmp, "run")
    p = T.run("render", scene, "-o", d, "--force", "--res", "16x16", "--samples-per-frame", "1",
              "--no-preview", *args, expect=None)
    return p.returncode, p.stderr, (T.load_run_json(d) if p.returncode == 0 else None)


def clip_lines(info):
    return {int(m.group(1)): m.group(0) for m in re.finditer(r"^  \[(\d+)\] .*: duration .*$", info, re.M)}


# ---- (a) one clip per object (as Blender exports them): both play --------------------------
disjoint = os.path.join(tmp, "disjoint.gltf")
T.clips_gltf(disjoint, [("a_right", [("a", "translation", [0, 1], [-1.2, 0, 0, -0.6, 0, 0])]),
                        # b_up ends at 4/3 s as float32: info must print every digit it needs
                        ("b_up", [("b", "translation", [0, 4 / 3], [1.2, 0, 0, 1.2, 0.8, 0])])])
info = T.run("info", disjoint).stdout
lines = clip_lines(info)
T.check("clips: 2, 2 play" in info, "disjoint clips: info says both play")
T.check(lines.get(0, "").endswith("plays") and lines.get(1, "").endswith("plays"),
        "disjoint clips: each line says it plays")
rest, later = quad_at(disjoint, 0), quad_at(disjoint, 1)
dx_a, dy_a = moved(rest["a"], later["a"])
dx_b, dy_b = moved(rest["b"], later["b"])
print(f"disjoint: a moved ({dx_a:.1f}, {dy_a:.1f}) px, b moved ({dx_b:.1f}, {dy_b:.1f}) px")
T.check(dx_a > 4 and abs(dy_a) < 1, "disjoint clips: a moves right")
T.check(dy_b > 4 and abs(dx_b) < 1, "disjoint clips: b moves up at the same time")
rc, err, run = render(disjoint)
T.check(rc == 0 and "not played" not in err, "disjoint clips: no notice")
T.check(run and run["scene"]["clips_played"] == ["a_right", "b_up"], "run.json: both clips played")
end = run["scene"]["animation_end"] if run else math.nan
T.check(abs(end - 4 / 3) < 1e-6 and run["stats"]["segments_planned"] == math.ceil(end * 30 - 1e-9),
        "disjoint clips: the render runs to the end of the longer clip")

# ---- (c) the duration info prints, fed back to render --duration ---------------------------
m = re.search(r"duration (\S+) s", lines.get(1, ""))
T.check(m is not None, "info prints clip 1's duration")
if m:
    printed = m.group(1)
    T.check(float(printed) == end, f"info's duration {printed} is the clip's end {end!r} exactly")
    # the end is a little over 4/3 s: 41 segments at 30 fps, where a rounded 1.333333 gives 40
    want = math.ceil(end * 30 - 1e-9)
    rc, err, run = render(disjoint, "--duration", printed)
    print(f"b_up: info prints duration {printed}; {want} segments at 30 fps")
    T.check(rc == 0, f"render --duration {printed} (as info prints it) is accepted: {err.strip()}")
    T.check(want == 41 and run and run["stats"]["segments_planned"] == want,
            f"--duration {printed}: {want} segments")
    # b_up alone: its end is the animation's end, and render without --duration plays to it
    rc, err, run = render(disjoint, "--animation", "b_up")
    T.check(rc == 0 and run and run["stats"]["segments_planned"] == want and
            run["scene"]["animation_end"] == end, "--animation b_up: plays to its end")
    # a_right alone ends at 1 s: b_up's duration is beyond it
    rc, err, run = render(disjoint, "--animation", "0", "--duration", printed)
    T.check(rc == 2 and "beyond the end of the animation (1 s)" in err,
            "--animation 0 --duration (b_up's): refused, a_right ends at 1 s")

# ---- (b) walk and run animate the same node: one plays --------------------------------------
same = os.path.join(tmp, "same.gltf")
T.clips_gltf(same, [("walk", [("a", "translation", [0, 1], [-1.2, 0, 0, -0.6, 0, 0])]),
                    ("run", [("a", "translation", [0, 1], [-1.2, 0, 0, -1.2, 0.6, 0]),
                             ("a", "scale", [0, 1], [1, 1, 1, 1.5, 1.5, 1])])])
rest = quad_at(same, 0)["a"]


def check_motion(what, args, right, up, grows):
    a = quad_at(same, 1, *args)["a"]
    dx, dy = moved(rest, a)
    area = a[2] / max(rest[2], 1)
    print(f"{what}: a moved ({dx:.1f}, {dy:.1f}) px, area x{area:.2f}")
    T.check(dx > 4 if right else abs(dx) < 1, f"{what}: moves right: {right}")
    T.check(dy > 4 if up else abs(dy) < 1, f"{what}: moves up: {up}")
    T.check(area > 1.8 if grows else abs(area - 1) < 0.2, f"{what}: grows: {grows}")


check_motion("default (walk)", [], right=True, up=False, grows=False)
check_motion("--animation 1", ["--animation", "1"], right=False, up=True, grows=True)
check_motion("--animation run", ["--animation", "run"], right=False, up=True, grows=True)
# all: walk's translation wins (the first clip's keys), run's scale is the only scale
check_motion("--animation all", ["--animation", "all"], right=True, up=False, grows=True)

rc, err, run = render(same)
notes = [l for l in err.splitlines() if "not played" in l]
T.check(rc == 0 and len(notes) == 1, "same node: one notice line")
T.check(notes and "'run'" in notes[0] and "'walk'" in notes[0] and "--animation" in notes[0],
        "the notice names run, walk and --animation")
T.check(run and run["scene"]["clips_played"] == ["walk"], "run.json: walk played")
rc, err, run = render(same, "-q")
T.check(rc == 0 and "not played" not in err, "--quiet: no notice")
rc, err, run = render(same, "--animation", "all")
T.check(rc == 0 and "not played" not in err and run and run["scene"]["clips_played"] == ["walk", "run"],
        "--animation all: no notice, both clips")
p = T.run("still", same, "--res", "8x8", "-o", os.path.join(tmp, "s.pfm"), expect=0)
T.check(p.stderr.count("not played") == 1, "still prints the notice too")

info = T.run("info", same).stdout
lines = clip_lines(info)
T.check(lines.get(1, "").endswith("not played: it animates a node that [0] \"walk\" animates"),
        "info: run does not play, and why")
info = T.run("info", same, "--animation", "run").stdout
lines = clip_lines(info)
T.check(lines.get(0, "").endswith("not played: not chosen") and lines.get(1, "").endswith("plays"),
        "info --animation run: run plays, walk not chosen")

for bad in ("nope", "7"):
    for cmd in (["render", same, "-o", os.path.join(tmp, "bad")], ["info", same],
                ["still", same, "-o", os.path.join(tmp, "bad.pfm")]):
        p = T.run(*cmd, "--animation", bad, expect=None)
        err = p.stderr.strip().splitlines()
        T.check(p.returncode != 0 and len(err) == 1 and f"no animation clip '{bad}'" in err[0] and
                "0 'walk', 1 'run'" in err[0], f"{cmd[0]} --animation {bad}: one line listing the clips")
p = T.run("render", same, "--animation", expect=None)
T.check(p.returncode == 2 and "--animation needs a value" in p.stderr, "--animation without a value")
T.check("--animation" in T.run("render", "--help").stdout, "render --help lists --animation")

T.finish("test_clips")
