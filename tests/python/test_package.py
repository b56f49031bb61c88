"""The evray Python package as installed by pip (tests/test_python.py runs these in the virtual
environment scripts/python-venv.sh makes): the square scene's streamed events against its
analytic crossing times, the stream against events.h5 and every other file format of the same
run, configuration errors, stopping early, Ctrl-C, and back-pressure on a slow consumer."""
import os
import shutil
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import evray

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import evrtest  # noqa: E402  (tests/: the square's analytic crossings)

W = H = 64
C_ON, C_OFF = 0.3, 0.25
SQUARE = dict(res=(W, H), pos_thres=C_ON, neg_thres=C_OFF, fps=30, samples_per_frame=10,
              log_floor=1e-4, no_preview=True, threads=2)


@pytest.fixture(scope="module")
def square():
    return evray.demo("square")


def streamed(sim, **kw):
    return np.concatenate(list(sim.stream(**kw)))


def test_installed():
    assert evray.__file__.find("site-packages") >= 0, evray.__file__  # not the source tree
    p = subprocess.run(["evray", "--version"], capture_output=True, text=True)
    assert p.returncode == 0 and evray.__version__ in p.stdout
    assert "square" in evray.demo_names() and "eye" in evray.demo_names()
    assert "square_camera" in evray.demo("square").describe()
    assert set(evray.EVENT_DTYPE.names) == {"x", "y", "t", "p", "id"}
    assert evray.EVENT_DTYPE["t"] == np.int64 and evray.EVENT_DTYPE["x"] == np.uint16


def test_square_against_analytic_crossings(square):
    sim = evray.Simulator(square, evray.Config(**SQUARE))
    ev = streamed(sim)
    assert len(ev) > 0 and bool(np.all(np.diff(ev["t"]) >= 0))
    checked, bad_count, errors, silent = evrtest.square_crossings(ev, W, H, C_ON, C_OFF)
    dt = 1.0 / (30 * 10)  # the sample interval
    assert checked > 500
    assert bad_count == 0
    assert max(errors) <= dt + 2e-6
    assert silent
    assert sim.stats["events_on"] + sim.stats["events_off"] == len(ev)
    assert not sim.stats["interrupted"]


def test_event_ids(square):
    """Config(event_ids=True): every streamed event names an instance of the scene (the square
    or its background; README "Ground truth"), and without it every id is 0."""
    ev = streamed(evray.Simulator(square, evray.Config(**SQUARE, event_ids=True)))
    assert len(ev) > 500
    assert set(np.unique(ev["id"]).tolist()) <= {1, 2} and bool(np.all(ev["id"] > 0))
    plain = streamed(evray.Simulator(square, evray.Config(**SQUARE)))
    assert bool(np.all(plain["id"] == 0))
    assert np.array_equal(plain[["x", "y", "t", "p"]], ev[["x", "y", "t", "p"]])


def test_stream_equals_files(square, tmp_path):
    """One run streamed and written: the stream is events.h5 exactly, and every format read back
    by evray.read is the same events; the evray command's run of the same scene and seed too."""
    sim = evray.Simulator(square, evray.Config(**SQUARE, format="all", seed=7))
    ev = streamed(sim, out_dir=tmp_path / "run")
    h5 = evray.read(tmp_path / "run" / "events.h5")
    assert h5.dtype == evray.EVENT_DTYPE
    assert len(ev) > 1000 and np.array_equal(ev, h5)
    packed = np.dtype([("x", "<u2"), ("y", "<u2"), ("t", "<i8"), ("p", "i1"), ("id", "<u4")])
    assert h5.astype(packed).tobytes() == ev.astype(packed).tobytes()  # byte for byte
    files = [f for f in os.listdir(tmp_path / "run") if f.startswith("events.")]
    assert len(files) >= 5, files
    for f in files:
        got = evray.read(tmp_path / "run" / f)
        assert np.array_equal(got, ev), f
    # the evray command (the package's) with the same options
    p = subprocess.run(["evray", "demo", "--scene", "square", "-o", str(tmp_path / "cli"), "--res", f"{W}x{H}",
                        "--pos-thres", str(C_ON), "--neg-thres", str(C_OFF), "--fps", "30",
                        "--samples-per-frame", "10", "--log-floor", "1e-4", "--no-preview", "--seed", "7",
                        "--threads", "2", "--quiet"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert np.array_equal(evray.read(tmp_path / "cli" / "events.h5"), ev)
    # sim.run writes the same
    sim.run(tmp_path / "again")
    assert np.array_equal(evray.read(tmp_path / "again" / "events.h5"), ev)


def test_config_errors(square):
    with pytest.raises(ValueError, match="unknown option 'bogus'"):
        evray.Config(bogus=1)
    with pytest.raises(ValueError, match="--res expects"):
        evray.Config(res="abc")
    with pytest.raises(ValueError, match="threshold"):
        evray.Config(pos_thres=-1)
    with pytest.raises(ValueError, match="unknown backend"):
        evray.Config(backend="quantum")
    with pytest.raises(ValueError, match="flag"):
        evray.Config(no_skip="yes")
    with pytest.raises(ValueError, match="no camera named 'nope'"):
        evray.Simulator(square, evray.Config(camera="nope"))
    with pytest.raises(ValueError, match="beyond the end of the animation"):
        evray.Simulator(square, duration=100)
    with pytest.raises(OSError):
        evray.load("/nonexistent/scene.glb")
    with pytest.raises((OSError, RuntimeError)):
        evray.read("/nonexistent/events.h5")
    # names and defaults are the program's: every option of `evray render --help` is one
    p = subprocess.run(["evray", "render", "--help"], capture_output=True, text=True)
    for name, (flag, _, _) in evray.options().items():
        assert flag in p.stdout, flag
    # a sensor preset first, then the options given, wherever they are
    evray.Config(pos_thres=0.5, sensor="davis346")


def test_break_early(square, tmp_path):
    full = streamed(evray.Simulator(square, evray.Config(**SQUARE)))
    sim = evray.Simulator(square, evray.Config(**SQUARE))
    got = []
    for batch in sim.stream(out_dir=tmp_path / "run"):
        got.append(batch.copy())
        if len(got) == 2:
            break
    st = sim.stats
    assert st["interrupted"] == 1 and st["segments_done"] < st["segments_total"]
    got = np.concatenate(got)
    assert np.array_equal(got, full[:len(got)])
    # the files are complete up to where the run stopped: a prefix of the whole run's events
    h5 = evray.read(tmp_path / "run" / "events.h5")
    assert len(h5) >= len(got) and np.array_equal(h5, full[:len(h5)])
    # the Simulator runs again, to the end
    assert np.array_equal(streamed(sim), full)


def long_config():
    return evray.Config(res=(96, 96), fps=300, samples_per_frame=16, no_preview=True, threads=2)


def test_ctrl_c(square, tmp_path):
    """SIGINT during sim.run and during a stream: KeyboardInterrupt, the run stopped, its files
    complete."""
    sim = evray.Simulator(square, long_config())
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.time()
    with pytest.raises(KeyboardInterrupt):
        sim.run(tmp_path / "run")
    assert time.time() - t0 < 5
    st = sim.stats
    assert st["interrupted"] == 1 and st["segments_done"] < st["segments_total"]
    evray.read(tmp_path / "run" / "events.h5")  # a valid file
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    n = 0
    with pytest.raises(KeyboardInterrupt):
        for batch in sim.stream():
            n += len(batch)
            time.sleep(0.01)
    assert sim.stats["interrupted"] == 1


def rss_bytes():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def test_slow_consumer(square):
    """A consumer that stops taking batches holds the run back: the run waits once the batch it
    hands over and the write queue behind it are full (32 batches at most: run/write_queue.c), its
    memory does not grow, and the
    events are the same as a fast consumer's."""
    fast = list(evray.Simulator(square, long_config()).stream())
    sizes = np.cumsum([len(b) for b in fast])
    sim = evray.Simulator(square, long_config())
    it = sim.stream()
    got = [next(it).copy()]
    # held back, the run stops once the hand-off and the queue are full; on a loaded machine it
    # takes longer to get there than the second the whole run takes on 2 idle cores: wait until
    # two looks half a second apart see the same segments done (30 s at most)
    st1, deadline = sim.stats, time.monotonic() + 30.0
    while True:
        time.sleep(0.5)
        st2 = sim.stats
        if st2["segments_done"] == st1["segments_done"] or time.monotonic() > deadline:
            break
        st1 = st2
    st1 = st2
    rss1 = rss_bytes()
    time.sleep(0.5)
    st2 = sim.stats
    rss2 = rss_bytes()
    emitted = st2["events_on"] + st2["events_off"]
    # one batch taken, one in the hand-off, 32 queued (and the one being pushed counted)
    assert len(sizes) > 100 and emitted <= sizes[1 + 1 + 32 + 1]
    assert st2["segments_done"] == st1["segments_done"] < st2["segments_total"]
    assert rss2 - rss1 < 8 << 20
    for b in it:
        got.append(b)
        time.sleep(0.002)
    assert np.array_equal(np.concatenate(got), np.concatenate(fast))


def test_dataset(tmp_path):
    """The installed package's dataset runner: the installed evray program's dataset command
    (which runs python3 -m evray.dataset here) and run() from Python make the same clips, and
    EventDataset reads them back through evray.read."""
    from evray.dataset import EventDataset, run
    spec = {"clips": 2, "seed": 3, "scenes": [{"demo": "square"}], "format": "npy",
            "options": {"res": "32x24", "duration": 0.1, "samples-per-frame": 10},
            "vary": {"thres": [0.2, 0.3]}}
    path = tmp_path / "spec.json"
    path.write_text(__import__("json").dumps(spec))
    p = subprocess.run(["evray", "dataset", str(path), "-o", str(tmp_path / "cli")],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rows = run(str(path), str(tmp_path / "py"), progress=False, evray=shutil.which("evray"))
    assert [r["status"] for r in rows] == ["done", "done"]
    a, b = EventDataset(str(tmp_path / "cli")), EventDataset(str(tmp_path / "py"))
    assert len(a) == len(b) == 2
    for i in range(2):
        assert len(a[i]["events"]) == rows[i]["events"] > 0
        assert np.array_equal(a[i]["events"], b[i]["events"])
        assert a[i]["params"] == b[i]["params"]


def test_demo_variants():
    """evray.demo(name, seed): the eye's variants (as evray demo --scene-seed), refused for a scene
    without any."""
    cfg = evray.Config(res=(32, 24), duration=0.3, samples_per_frame=10, no_preview=True)
    counts = [len(streamed(evray.Simulator(evray.demo("eye", seed=s), cfg))) for s in (0, 0, 9)]
    assert counts[0] == counts[1] > 0 and counts[2] > 0 and counts[2] != counts[0]
    with pytest.raises(ValueError, match="no variants"):
        evray.demo("square", seed=1)
    with pytest.raises(ValueError):
        evray.demo("eye", seed=-1)
