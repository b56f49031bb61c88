"""--frames-out: intensity frames at a fixed rate for frame-based tools (v2e and the like), on the
built-in 'square' scene (numbers from the header of src/scene/demo_square.c).

Frame k is every pixel's intensity at exactly t_k = start + k/F, for every t_k up to and including
the end of the run: floor(duration * F) + 1 frames. Checked: the count (with and without a frame
at the end), the times in frames.csv, the 16-bit and 8-bit PNGs against the analytic image at t_k
(the square's edges at their exact position at t_k, the intensity of the lit plane), that events
are byte-identical with and without frames, and the refusal to overwrite frames without --force.
PNGs are decoded with zlib only."""
import csv
import math
import os
import struct
import zlib

import evrtest as T


def read_png(path):
    """A gray 8- or 16-bit PNG as (width, height, depth, rows of ints)."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, hdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype, _, _, interlace = hdr
    assert ctype == 0 and interlace == 0 and depth in (8, 16), hdr
    bpp = depth // 8
    stride = w * bpp
    raw = zlib.decompress(idat)
    rows, prev = [], bytearray(stride)
    for y in range(h):
        ft = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ft == 1:
                line[i] = (line[i] + a) & 255
            elif ft == 2:
                line[i] = (line[i] + b) & 255
            elif ft == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ft == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        prev = line
        if depth == 8:
            rows.append(list(line))
        else:
            rows.append([line[2 * i] << 8 | line[2 * i + 1] for i in range(w)])
    return w, h, depth, rows


def read_csv(d):
    with open(os.path.join(d, "frames.csv")) as f:
        return list(csv.DictReader(f))


def srgb8(v):
    v = min(max(v, 0.0), 1.0)
    s = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
    return round(s * 255)


# ---- the analytic image of the square scene at time t ----
TANH = 0.25            # tan(yfov / 2)
AMBIENT = 0.02
DARK, BRIGHT = 0.1, 0.1 * math.exp(2)


def expected(i, j, W, H, t):
    """(intensity, distance in metres from the pixel centre's view point to the nearest square edge)."""
    nx = 2 * (i + 0.5) / W - 1
    ny = 1 - 2 * (j + 0.5) / H
    # on the square's plane (z = 0.01, 3.99 from the camera and the lamp)
    X, Y = nx * TANH * 3.99, ny * TANH * 3.99
    xc = -1 + t
    inside = abs(X - xc) < 0.25 and abs(Y) < 0.25
    edge = min(abs(abs(X - xc) - 0.25) if abs(Y) < 0.25 + 1e-3 else 9, abs(abs(Y) - 0.25) if abs(X - xc) < 0.25 + 1e-3 else 9)
    if inside:
        d = math.sqrt(X * X + Y * Y + 3.99 ** 2)
        return BRIGHT * (AMBIENT + 16 * 3.99 / d ** 3), edge
    Xb, Yb = nx * TANH * 4, ny * TANH * 4
    d = math.sqrt(Xb * Xb + Yb * Yb + 16)
    return DARK * (AMBIENT + 16 * 4 / d ** 3), edge


W = H = 128
FPS, FRAMES_FPS, MAX, EXPOSURE = 30, 7, 4.0, 1.5
base = T.tmpdir()
common = ["demo", "--scene", "square", "--res", f"{W}x{H}", "--fps", FPS, "--samples-per-frame", 10,
          "--format", "npy", "--no-preview", "--quiet", "--backend", "cpu"]
plain = os.path.join(base, "plain")
run = os.path.join(base, "run")
frames = os.path.join(run, "frames")         # inside the run folder
T.run(*common, "-o", plain)
T.run(*common, "-o", run, "--frames-out", frames, "--frames-fps", FRAMES_FPS, "--frames-exposure", EXPOSURE,
      "--frames-max", MAX)

# events are not touched by the frame samples
with open(os.path.join(plain, "events.npy"), "rb") as a, open(os.path.join(run, "events.npy"), "rb") as b:
    T.check(a.read() == b.read(), "events byte-identical with and without --frames-out")

# count and times: 2 s at 7 frames/s: t = 0, 1/7, ..., 14/7 = 2 (the end included)
rows = read_csv(frames)
n = math.floor(2.0 * FRAMES_FPS) + 1
T.check(len(rows) == n, f"{n} frames over 2 s at {FRAMES_FPS}/s, the end included (got {len(rows)})")
T.check(all(int(r["index"]) == k and abs(float(r["time_s"]) - k / FRAMES_FPS) < 1e-8 for k, r in enumerate(rows)),
        "frames.csv times are start + k/F")
T.check(T.load_run_json(run)["stats"].get("intensity_frames") == n, "run.json counts the frames")
cfg = T.load_run_json(run)["config"]
T.check(cfg.get("frames_fps") == FRAMES_FPS and cfg.get("frames_max") == MAX and cfg.get("frames_out") == frames,
        "frame options in the configuration")

bad16 = bad8 = bad_side = checked = 0
for r in rows:
    t = float(r["time_s"])
    w, h, depth, img16 = read_png(os.path.join(frames, r["linear16_png"]))
    T.check((w, h, depth) == (W, H, 16), f"{r['linear16_png']}: {w}x{h}, {depth} bits")
    w, h, depth, img8 = read_png(os.path.join(frames, r["srgb8_png"]))
    T.check((w, h, depth) == (W, H, 8), f"{r['srgb8_png']}: {w}x{h}, {depth} bits")
    for j in range(H):
        for i in range(W):
            want, edge = expected(i, j, W, H, t)
            # a pixel centre within 1 mm of an edge may go either way (0.06 pixel here; a frame
            # taken one sample interval, 1/300 s, off t_k would move the edges by 3.3 mm)
            if edge < 1e-3:
                continue
            checked += 1
            got = img16[j][i] * MAX / 65535
            if abs(got - want) > 0.01 * want + 2 * MAX / 65535:
                bad16 += 1
                if (want > 0.3) != (got > 0.3):
                    bad_side += 1
            if abs(img8[j][i] - srgb8(want * EXPOSURE)) > 1:
                bad8 += 1
T.check(checked > 0.9 * W * H * n, f"enough pixels checked ({checked})")
T.check(bad_side == 0, f"the square is exactly where it is at t_k in every frame ({bad_side} pixels on the wrong side of an edge)")
T.check(bad16 == 0, f"16-bit frames match the analytic intensity within 1% ({bad16} of {checked} differ)")
T.check(bad8 == 0, f"8-bit frames match the analytic sRGB value within 1 ({bad8} of {checked} differ)")

# no frame at the end: 1.95 s at 10/s: t = 0 .. 1.9, 20 frames; a folder outside the run folder
small = ["demo", "--scene", "square", "--res", "16x16", "--fps", FPS, "--samples-per-frame", 2, "--format", "npy",
         "--no-preview", "--quiet", "--backend", "cpu", "--duration", 1.95]
outside = os.path.join(base, "outside", "frames")
T.run(*small, "-o", os.path.join(base, "r2"), "--frames-out", outside, "--frames-fps", 10)
rows = read_csv(outside)
T.check(len(rows) == 20 and abs(float(rows[-1]["time_s"]) - 1.9) < 1e-8,
        f"1.95 s at 10/s: 20 frames, the last at 1.9 s (got {len(rows)})")
T.check(all(os.path.exists(os.path.join(outside, r[k])) for r in rows for k in ("srgb8_png", "linear16_png")),
        "every listed file exists")
T.check(not [f for f in os.listdir(outside) if f.endswith(".tmp")], "no temporary files left")

# default rate: the segment rate
T.run(*small, "-o", os.path.join(base, "r3"), "--frames-out", os.path.join(base, "f3"))
T.check(len(read_csv(os.path.join(base, "f3"))) == math.floor(1.95 * FPS) + 1, "--frames-fps defaults to --fps")

# a folder that holds frames is refused without --force, overwritten with it
p = T.run(*small, "-o", os.path.join(base, "r4"), "--frames-out", outside, "--frames-fps", 5, expect=None)
T.check(p.returncode != 0 and "already holds frames" in p.stderr and len(p.stderr.strip().splitlines()) == 1,
        f"existing frames refused with one line ({p.returncode}: {p.stderr.strip()})")
T.check(not os.path.exists(os.path.join(base, "r4")), "a refused run leaves no run folder")
T.run(*small, "-o", os.path.join(base, "r4"), "--frames-out", outside, "--frames-fps", 5, "--force")
T.check(len(read_csv(outside)) == 10 and len(os.listdir(outside)) == 2 * 10 + 1,
        "--force replaces the frames (stale ones removed)")

# bad values: one clear line
for opt, val in (("--frames-fps", "0"), ("--frames-max", "-1"), ("--frames-exposure", "nan")):
    p = T.run(*small, "-o", os.path.join(base, "r5"), "--frames-out", os.path.join(base, "f5"), opt, val, expect=None)
    T.check(p.returncode != 0 and opt in p.stderr and len(p.stderr.strip().splitlines()) == 1,
            f"{opt} {val} refused with one line ({p.stderr.strip()})")
# the CUDA backend (where this build has it and a GPU is usable): the same frames as the CPU
# (up to floating-point differences in hit points at the edges) and events untouched by them
cu = ["demo", "--scene", "square", "--res", "64x64", "--fps", FPS, "--samples-per-frame", 10, "--format", "npy",
      "--no-preview", "--quiet", "--backend", "cuda"]
probe = T.run(*cu, "--duration", 0.1, "-o", os.path.join(base, "probe"), expect=None)
if probe.returncode != 0:
    print("test_frames: CUDA part skipped:", probe.stderr.strip())
else:
    fc, fg = os.path.join(base, "fc"), os.path.join(base, "fg")
    T.run(*[a if a != "cuda" else "cpu" for a in cu], "-o", os.path.join(base, "c-cpu"), "--frames-out", fc,
          "--frames-fps", FRAMES_FPS)
    T.run(*cu, "-o", os.path.join(base, "c-gpu"), "--frames-out", fg, "--frames-fps", FRAMES_FPS)
    T.run(*cu, "-o", os.path.join(base, "c-gpu-plain"))
    with open(os.path.join(base, "c-gpu", "events.npy"), "rb") as a, \
            open(os.path.join(base, "c-gpu-plain", "events.npy"), "rb") as b:
        T.check(a.read() == b.read(), "CUDA: events byte-identical with and without --frames-out")
    rc, rg = read_csv(fc), read_csv(fg)
    T.check([r["time_s"] for r in rc] == [r["time_s"] for r in rg], "CUDA: the same frame times as the CPU")
    diff = total = 0
    for a, b in zip(rc, rg):
        ia = read_png(os.path.join(fc, a["linear16_png"]))[3]
        ib = read_png(os.path.join(fg, b["linear16_png"]))[3]
        for ra, rb in zip(ia, ib):
            for va, vb in zip(ra, rb):
                total += 1
                diff += abs(va - vb) > max(0.01 * va, 4)
    T.check(diff <= 0.001 * total, f"CUDA frames match the CPU's ({diff} of {total} pixels differ by over 1%)")
T.finish("test_frames")
