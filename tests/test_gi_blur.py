"""The blurred estimate (--gi-blur, K = 4 by default; core/photon_blur.h) on the CPU backend (tests/test_cuda.py
compares the CUDA backend's): a still Cornell box makes no
events with it; the moving box's events are identical with and without change-driven sampling and
the gather memo; the flicker that a gather at every sample turns into events falls: the ceiling,
lit only by indirect light, makes a tenth of the events (a 1024-photons-a-pixel reference makes
none there: docs/benchmarks.md), and the whole room less than half; run.json records it; bad
values give one-line errors."""
import os

import numpy as np

import evrtest as T

tmp = T.tmpdir()


def render(name, scene, *extra, env=None):
    d = os.path.join(tmp, name)
    T.run_env(env, "demo", "--scene", scene, "-o", d, "--backend", "cpu", "--format", "npy", "--no-preview",
              "--quiet", "--res", "96x72", "--samples-per-frame", "10", *extra)
    return open(os.path.join(d, "events.npy"), "rb").read(), T.load_run_json(d), d


for mode in ([], ["--no-skip"]):
    _, js, _ = render("still" + "".join(mode), "cornell-still", "--gi", "photon", "--gi-blur", "4", "--duration",
                      "0.5", *mode)
    T.check(js["stats"]["events"] == 0, f"still Cornell box, --gi-blur {mode}: no events ({js['stats']['events']})")
    T.check(js["config"]["gi_blur"] == 4, "--gi-blur in run.json")

ev_s, js, d_s = render("blur", "cornell", "--gi", "photon", "--duration", "1")
ev_4, _, _ = render("blur-4", "cornell", "--gi", "photon", "--gi-blur", "4", "--duration", "1")
T.check(ev_4 == ev_s, "--gi-blur 4 is the default")
ev_b, jb, _ = render("blur-brute", "cornell", "--gi", "photon", "--gi-blur", "4", "--duration", "1", "--no-skip")
ev_m, jm, _ = render("blur-no-memo", "cornell", "--gi", "photon", "--gi-blur", "4", "--duration", "1",
                     env="EVR_GI_NO_MEMO")
ev_g, jg, d_g = render("gather", "cornell", "--gi", "photon", "--gi-blur", "0", "--duration", "1")
ev_d, jd, d_d = render("direct", "cornell", "--duration", "1")
T.check(js["stats"]["events"] > 0 and ev_s == ev_b, "--gi-blur: identical events with and without skipping")
T.check(ev_m == ev_s, "--gi-blur: identical events without the memo of a pixel's lookups")
T.check(js["stats"]["samples_traced"] < jb["stats"]["samples_traced"], "--gi-blur: pixels are still skipped")


def ceiling(d):
    ev = np.load(os.path.join(d, "events.npy"))
    return int((ev["y"] < 14).sum())  # the rows of the ceiling above the light's row


n_blur, n_gather, n_direct = js["stats"]["events"], jg["stats"]["events"], jd["stats"]["events"]
c_blur, c_gather = ceiling(d_s), ceiling(d_g)
print(f"cornell 96x72, 1 s: {n_blur} events blurred, {n_gather} gathered at every sample, {n_direct} direct light "
      f"only; on the ceiling {c_blur} and {c_gather}")
T.check(c_gather > 200 and c_blur * 8 < c_gather, "--gi-blur: the indirectly lit ceiling no longer flickers")
T.check(n_blur < 0.5 * n_gather and n_blur > n_direct, "--gi-blur: far fewer events than a gather at every sample, "
        "more than direct light alone")

# one-line errors
for bad in ("-1", "17", "x"):
    p = T.run("demo", "--scene", "cornell", "--gi", "photon", "--gi-blur", bad, "-o", os.path.join(tmp, "bad"),
              expect=None)
    T.check(p.returncode != 0 and "--gi-blur" in p.stderr and len(p.stderr.strip().splitlines()) == 1,
            f"--gi-blur {bad}: a one-line error ({p.stderr.strip()!r})")

T.finish("test_gi_blur")
