"""Shared helpers for the Python tests: run the evray binary, load its outputs."""
import json
import os
import struct
import subprocess
import sys
import shutil
import tempfile

import gltf_build  # tests/, beside this file

EVRAY = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("EVRAY", "build/evray")
failures = []


def oracle_python(modules, optional=False):
    """The Python of the oracle environment (build/venv, made by scripts/test-venv.sh) that can
    import modules; exits 77 (CTest: skipped) with a clear line when there is none, or with
    optional returns None."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    # the environment beside the program, else the release build's (for build-asan)
    candidates = [os.environ.get("EVR_VENV_PYTHON"),
                  os.path.join(os.path.dirname(os.path.abspath(EVRAY)), "venv", "bin", "python"),
                  os.path.join(root, "build", "venv", "bin", "python")]
    python = next((c for c in candidates if c and os.path.exists(c)), candidates[1])
    probe = subprocess.run([python, "-c", "import " + ", ".join(modules)], capture_output=True,
                           text=True) if os.path.exists(python) else None
    if probe is None or probe.returncode != 0:
        why = "missing" if probe is None else "unusable: " + probe.stderr.strip().splitlines()[-1]
        if optional:
            print(f"note: the oracle environment {python} is {why}")
            return None
        print(f"SKIP: the oracle environment {python} is {why} (run scripts/test-venv.sh; it "
              "needs the package registry)")
        sys.exit(77)
    return python


def labels_compare_program():
    """labels_compare (tests/labels_compare.c), built beside the evray under test (and carried
    beside it to the GPU machine); None when it is not there."""
    p = os.path.join(os.path.dirname(os.path.abspath(EVRAY)), "labels_compare")
    return p if os.access(p, os.X_OK) else None


def compare_labels(a, b):
    """labels_compare's figures for two labels.h5 (a dict: same, depth, flow, seen, ...)."""
    prog = labels_compare_program()
    if prog is None:
        raise SystemExit("labels_compare is not built beside " + EVRAY)
    p = subprocess.run([prog, a, b], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"labels_compare {a} {b}: exit {p.returncode}: {p.stderr.strip()}")
    return json.loads(p.stdout)


def check(cond, what):
    if not cond:
        failures.append(what)
        print("CHECK failed:", what, file=sys.stderr)


def run(*args, expect=0):
    p = subprocess.run([EVRAY, *map(str, args)], capture_output=True, text=True)
    if expect is not None and p.returncode != expect:
        print(p.stdout, p.stderr, file=sys.stderr)
        raise SystemExit(f"evray {' '.join(map(str, args))}: exit {p.returncode}, expected {expect}")
    return p


def run_env(env, *args, expect=0):
    """run() with environment variable env set to 1 (None: as it is), for hidden switches that a
    test compares against (e.g. EVR_NO_COHERENCE)."""
    if env is None:
        return run(*args, expect=expect)
    os.environ[env] = "1"
    try:
        return run(*args, expect=expect)
    finally:
        os.environ.pop(env, None)


def interrupt(started_file, after, *args):
    """Runs evray with args, sends it SIGINT (Ctrl-C) `after` seconds after started_file appears
    (a writer's temporary file: the run has begun), and returns the finished process's
    (returncode, stderr)."""
    import signal
    import time
    proc = subprocess.Popen([EVRAY, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and not os.path.exists(started_file):
        time.sleep(0.05)
    time.sleep(after)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err


_tmpdirs = []


def tmpdir():
    """A fresh folder for a test's files: removed by finish() when every check passed, kept (and
    named) for inspection when one failed."""
    d = tempfile.mkdtemp(prefix="evray-test-")
    _tmpdirs.append(d)
    return d


def load_run_json(d):
    with open(os.path.join(d, "run.json")) as f:
        return json.load(f)


def load_h5(path):
    import h5py
    with h5py.File(path, "r") as f:
        ev = {k: f["events"][k][()] for k in ("x", "y", "t", "p")}
        ms = f["ms_to_idx"][()]
        attrs = dict(f.attrs)
    return ev, ms, attrs


def npy_columns(data, names):
    """The named columns of an events.npy file's bytes, as tuples per event, without numpy (the GPU
    machine has none): the header's dtype gives the record layout."""
    import ast
    import struct
    major = data[6]
    hlen = struct.unpack_from("<H" if major == 1 else "<I", data, 8)[0]
    start = 10 + hlen if major == 1 else 12 + hlen
    header = ast.literal_eval(data[10 if major == 1 else 12:start].decode("latin1"))
    sizes = {"i8": 8, "u8": 8, "u2": 2, "i2": 2, "i1": 1, "u1": 1, "f8": 8, "i4": 4, "u4": 4, "f4": 4}
    codes = {"i8": "q", "u8": "Q", "u2": "H", "i2": "h", "i1": "b", "u1": "B", "i4": "i", "u4": "I",
             "f8": "d", "f4": "f"}
    offset, at = 0, {}
    for name, typ in header["descr"]:
        typ = typ.lstrip("<>|=")
        at[name] = (offset, "<" + codes[typ])
        offset += sizes[typ]
    n = (len(data) - start) // offset
    cols = [at[name] for name in names]
    return [tuple(struct.unpack_from(c, data, start + i * offset + o)[0] for o, c in cols) for i in range(n)]


def npy_event_times(data):
    """The t column (microseconds) of an events.npy file's bytes."""
    return [t for (t,) in npy_columns(data, ("t",))]


def npy_event_pixels(data):
    """The (x, y) of every event of an events.npy file's bytes."""
    return npy_columns(data, ("x", "y"))


def boundary_share(npy, segments, duration):
    """The share of an events.npy's events within a tenth of a segment of a segment boundary."""
    t = npy_event_times(npy)
    near = 0
    for us in t:
        phase = (us * 1e-6 * segments / duration) % 1.0
        near += phase < 0.1 or phase > 0.9
    return near / max(len(t), 1)


def quad_gltf(path, with_triangles=True, animated=False):
    """A lit grey quad facing +Z seen by a camera at z = 3; optionally moving."""
    g = gltf_build.Gltf()
    g.camera("cam", yfov=0.8, translation=[0, 0, 3])
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}})
    if with_triangles:
        pos, _, _, idx = gltf_build.rect(-1, 1, -1, 1, 0)
        quad = g.node("quad", mesh=g.mesh("quad", [g.primitive(pos, idx, grey)]))
    else:
        quad = g.node("quad")
    if animated:
        g.animation([(quad, "translation", [0.0, 1.0], [(0, 0, 0), (0.5, 0, 0)])])
    g.write(path)


def clips_gltf(path, clips):
    """Two lit grey quads facing +Z, "a" at x = -1.2 and "b" at x = +1.2 (0.8 wide), seen by a
    camera at z = 6, and animation clips: clips is a list of (name, channels), each channel
    (node name, path, key times, flat values) with path translation or scale."""
    g = gltf_build.Gltf()
    g.camera("cam", yfov=0.8, translation=[0, 0, 6])
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}})
    pos, _, _, idx = gltf_build.rect(-0.4, 0.4, -0.4, 0.4, 0)
    quad = g.mesh("quad", [g.primitive(pos, idx, grey)])
    names = {"a": g.node("a", mesh=quad, translation=[-1.2, 0, 0]),
             "b": g.node("b", mesh=quad, translation=[1.2, 0, 0])}
    for name, channels in clips:
        g.animation([(names[node], prop, times, values) for node, prop, times, values in channels],
                    name=name)
    g.write(path)


def read_pfm(path):
    """A PFM image (evray still writes them): width, height and the RGB floats in the file's
    order, rows bottom to top."""
    with open(path, "rb") as f:
        data = f.read()
    head = data.split(b"\n", 3)
    check(head[0] == b"PF", f"{path}: PFM magic")
    w, h = map(int, head[1].split())
    check(float(head[2]) < 0, f"{path}: little-endian scale")
    px = struct.unpack(f"<{w * h * 3}f", head[3][: w * h * 12])
    return w, h, px


def pfm_rows(path):
    """A PFM image as rows top to bottom, each a list of (r, g, b)."""
    w, h, px = read_pfm(path)
    return [[tuple(px[3 * (r * w + c):3 * (r * w + c) + 3]) for c in range(w)]
            for r in reversed(range(h))]


def luminance(rgb):
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]


def glint_point(centre, radius, light):
    """The point of a sphere whose normal halves the directions to the camera (at the origin)
    and to a point light: where a smooth sphere shows the light's glint (fixed-point iteration)."""
    def unit(v):
        n = sum(x * x for x in v) ** 0.5
        return tuple(x / n for x in v)
    p = (centre[0], centre[1], centre[2] + radius)
    for _ in range(200):
        h = unit(tuple(a + b for a, b in zip(unit(tuple(-x for x in p)),
                                             unit(tuple(l - x for l, x in zip(light, p))))))
        p = tuple(c + radius * x for c, x in zip(centre, h))
    return p


def bright_centroid(values):
    """values: {(column, row): luminance}; the luminance-weighted centre (pixel centres at + 0.5)
    of those above half the largest, and the largest."""
    peak = max(values.values())
    bright = [(c, r, v) for (c, r), v in values.items() if v > 0.5 * peak]
    w = sum(v for _, _, v in bright)
    return (sum((c + 0.5) * v for c, _, v in bright) / w,
            sum((r + 0.5) * v for _, r, v in bright) / w, peak)


def deform_assets(tmp):
    """The moving deforming test scenes (skins and morph targets) that tests/deform_assets.py
    writes into a folder under tmp (`deform_assets.py DIR`), those `evray info` reads: their
    paths; none where that writer is missing or fails (the tests' deforming cases then do not
    run)."""
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "deform_assets.py")
    if not os.path.exists(script):
        return []
    out = os.path.join(tmp, "deform-assets")
    os.makedirs(out, exist_ok=True)
    if subprocess.run([sys.executable, script, out], capture_output=True, text=True).returncode != 0:
        return []
    # the assets that move (the others hold still or are bad input): morph targets, a skin with
    # two influence sets, a bending cylinder, two primitives, one mesh under two skins
    moving = ("morph_slide", "skin_slide8", "bend_cylinder", "morph_two_prims", "skin_shared")
    paths = [os.path.join(out, name + ".gltf") for name in moving]
    return [p for p in paths if os.path.exists(p) and run("info", p, expect=None).returncode == 0]


def square_crossings(ev, w, h, c_on, c_off):
    """The built-in 'square' scene's events against its analytic crossings (tests/test_square.py
    derives them): the pixels checked, how many of them have the wrong number of ON or OFF events,
    the largest |t - analytic| in seconds of each correctly counted pixel, and whether the rows the
    square never reaches stay silent. A pixel whose centre looks at X on the square's plane sees
    the leading edge at t = X + 0.75 and the trailing edge at t = X + 1.25; it fires floor(2 / c_on)
    ON events and floor(that * c_on / c_off) OFF events."""
    import math
    half = 3.99 / 4.0   # half-width of the view at the square's plane
    count_on = int(math.floor(2.0 / c_on))
    count_off = int(math.floor(count_on * c_on / c_off))
    by_pixel = {}
    for e in ev:
        by_pixel.setdefault((int(e["x"]), int(e["y"])), []).append((int(e["t"]), int(e["p"])))
    checked = bad = 0
    errors = []
    for j in range(h):
        y = (1 - (j + 0.5) / h * 2) * half
        if abs(y) > 0.22:
            continue
        for i in range(w):
            x = ((i + 0.5) / w * 2 - 1) * half
            if x < -0.6 or x > 0.7:
                continue
            t_on, t_off = x + 0.75, x + 1.25
            evs = by_pixel.get((i, j), [])
            on = [t for t, p in evs if p == 1]
            off = [t for t, p in evs if p == 0]
            checked += 1
            if len(on) != count_on or len(off) != count_off:
                bad += 1
                continue
            errors.append(max(max(abs(t * 1e-6 - t_on) for t in on), max(abs(t * 1e-6 - t_off) for t in off)))
    quiet_rows = [j for j in range(h) if abs((1 - (j + 0.5) / h * 2) * half) > 0.3]
    silent = not any(y in quiet_rows for (_, y) in by_pixel)
    return checked, bad, errors, silent


def skip(name, why):
    """Ends a test that cannot run here (ctest's SKIP_RETURN_CODE 77), its folders removed."""
    for d in _tmpdirs:
        shutil.rmtree(d, ignore_errors=True)
    print(f"{name}: skipped: {why}")
    raise SystemExit(77)


def finish(name):
    if failures:
        print(f"{name}: {len(failures)} check(s) failed (files kept in {', '.join(_tmpdirs)})")
        raise SystemExit(1)
    for d in _tmpdirs:
        shutil.rmtree(d, ignore_errors=True)
    print(f"{name}: all checks passed")
