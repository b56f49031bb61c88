"""Previews (issue 22): one exposure for the whole run from the visible scene, not blown out by a
black background and stable when something bright comes in; one animated PNG per run (events and
intensity side by side) read back by an independent reader (tests/apng_read.py) and equal, frame
for frame, to the per-window PNGs of --preview png; --preview none and --no-preview write none.

The scene is import_assets.py's dark_stage: grey boxes turning on a black background, a static
grey strip, and a bright flare that enters after 0.5 s."""
import json
import os
import sys

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import apng_read  # noqa: E402
import import_assets  # noqa: E402

tmp = T.tmpdir()
scene = import_assets.dark_stage(tmp)
W, H = 96, 72
common = ["--res", f"{W}x{H}", "--duration", "1", "--fps", "20", "--preview-window", "0.1",
          "--samples-per-frame", "2", "--backend", "cpu", "--format", "npy", "--quiet"]


def render(name, *extra):
    d = os.path.join(tmp, name)
    T.run("render", scene, "-o", d, *common, *extra)
    return d, T.load_run_json(d)


# ---- per-window PNGs: the exposure ----
d_png, meta = render("png", "--preview", "png")
frames = meta["stats"]["preview_frames"]
T.check(frames == 10, f"10 windows of 0.1 s (got {frames})")
gray = []
for k in range(frames):
    w, h, c, imgs, _ = apng_read.read(os.path.join(d_png, "preview", f"intensity_{k:06d}.png"))
    T.check((w, h, c) == (W, H, 1), f"intensity frame {k} is {W}x{H} gray")
    gray.append(imgs[0])
    apng_read.read(os.path.join(d_png, "preview", f"events_{k:06d}.png"))
T.check(not os.path.exists(os.path.join(d_png, "preview.apng")), "--preview png writes no video")

# the strip (y in [-0.95, -0.75], x in [-0.9, 0.9] at z = 0, where the view spans y in [-1, 1]
# and x in [-W/H, W/H]) never changes: its pixels keep their level in every frame, before and
# after the flare comes in
col = [int((x * H / W + 1) / 2 * W) for x in (-0.85, 0.85)]
strip = [y * W + x for y in range(int(H * 0.89), int(H * 0.96)) for x in range(col[0] + 1, col[1])]
levels = {tuple(g[i] for i in strip) for g in gray}
T.check(len(levels) == 1, f"the static strip keeps its levels in all {frames} frames ({len(levels)} versions)")
T.check(all(0 < v < 255 for v in next(iter(levels))), "the strip is neither black nor white")
flare_in = sum(1 for v in gray[-1] if v == 255)
T.check(flare_in > 0, "the bright flare shows (white) in the last frame")

# not blown out: in the first frame (grid and strip on black) the visible pixels are mostly mid
# levels, the black background stays black
first = gray[0]
visible = sorted(v for v in first if v > 0)
T.check(len(visible) > W * H // 20, f"the first frame shows the scene ({len(visible)} visible pixels)")
white = sum(1 for v in visible if v == 255)
median = visible[len(visible) // 2] if visible else 0
print(f"first frame: {len(visible)} visible pixels, median level {median}, {white} white; "
      f"exposure {meta['stats']['preview_exposure']:.4g}")
T.check(white <= len(visible) // 50, f"at most 2% of the visible pixels are white ({white})")
T.check(60 <= median <= 200, f"the visible scene's median level {median} is a mid gray")
T.check(sum(1 for v in first if v == 0) > W * H // 2, "the background stays black")

# ---- the video: one APNG, its frames the PNGs side by side ----
d_vid, meta_v = render("video")
path = os.path.join(d_vid, "preview.apng")
T.check(os.path.exists(path) and not os.path.exists(os.path.join(d_vid, "preview")),
        "the default writes one preview.apng and no preview/ folder")
try:
    w, h, c, vframes, delays = apng_read.read(path)
except (OSError, ValueError) as e:
    T.check(False, f"preview.apng reads back: {e}")
    w, h, c, vframes, delays = 0, 0, 0, [], []
T.check((w, h, c) == (2 * W, H, 3), f"the video is {2 * W}x{H} RGB (got {w}x{h}x{c})")
T.check(len(vframes) == frames == meta_v["stats"]["preview_frames"], f"one video frame per window ({len(vframes)})")
T.check(all(abs(dl - 0.1) < 1e-9 for dl in delays), "each frame plays for its window (0.1 s)")
T.check(meta_v["config"]["preview"] == "video" and meta["config"]["preview"] == "png", "run.json names the kind")
same = 0
for k, f in enumerate(vframes):
    _, _, _, ev, _ = apng_read.read(os.path.join(d_png, "preview", f"events_{k:06d}.png"))
    left = b"".join(f[y * 6 * W:y * 6 * W + 3 * W] for y in range(H))
    right = bytes(f[y * 6 * W + 3 * W + 3 * x] for y in range(H) for x in range(W))
    same += left == ev[0] and right == gray[k]
T.check(same == frames, f"video frames equal the PNGs side by side ({same} of {frames})")

# ---- none ----
for opt in (["--preview", "none"], ["--no-preview"]):
    d_none, meta_n = render("none" + opt[-1].replace("-", ""), *opt)
    T.check(not os.path.exists(os.path.join(d_none, "preview.apng")) and
            not os.path.exists(os.path.join(d_none, "preview")), f"{' '.join(opt)} writes no preview")
    T.check(meta_n["stats"]["preview_frames"] == 0, f"{' '.join(opt)}: run.json counts no preview frame")

p = T.run("render", scene, "-o", os.path.join(tmp, "bad"), "--preview", "mp4", expect=None)
T.check(p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "preview" in p.stderr,
        f"--preview mp4: one line, exit 2 ({p.stderr.strip()})")
T.check(not os.path.exists(os.path.join(tmp, "bad")), "a bad --preview leaves nothing behind")
T.finish("test_preview")
