"""evray in Python: the C library's simulator (include/evray.h) with events as NumPy arrays.

    import evray
    scene = evray.demo("eye")                        # or evray.load("scene.glb")
    cfg = evray.Config(res="346x260", duration=0.5)  # the options of `evray render --help`
    sim = evray.Simulator(scene, cfg)
    for batch in sim.stream():                       # structured arrays: x, y, t (us), p
        ...
    sim.run("out")                                   # or the run folder, as the evray command
    events = evray.read("out/events.h5")             # any format evray writes

Rendering runs on the library's threads with the GIL released; Ctrl-C (KeyboardInterrupt) and
leaving a stream early stop the run cleanly."""
import os
import shutil
import tempfile

import numpy as np

from . import _evray

__version__ = _evray.version()

# The library's evr_event, field for field (include/evray.h): arrays are its records as they
# come, not converted. Fields by name, as tonic's transforms take them: x, y (uint16), t
# (int64 microseconds), p (int8, 1 ON, 0 OFF); and id (uint16: with Config(event_ids=True) 1 +
# the instance whose surface caused the event, 0 none; README "Ground truth").
EVENT_DTYPE = np.dtype({"names": ["x", "y", "t", "p", "id"],
                        "formats": ["<u2", "<u2", "<i8", "i1", "<u2"],
                        "offsets": [_evray.OFFSET_X, _evray.OFFSET_Y, _evray.OFFSET_T, _evray.OFFSET_P,
                                    _evray.OFFSET_ID],
                        "itemsize": _evray.EVENT_SIZE})

Scene = _evray.Scene


def _events(buf):
    return np.frombuffer(buf, dtype=EVENT_DTYPE)


def load(path, animation=None, strict=False, allow_external_files=False):
    """Loads a scene file (glTF 2.0 first of all; any format Assimp reads): a Scene."""
    return _evray.load(os.fspath(path), animation, bool(strict), bool(allow_external_files))


def demo(name="eye", seed=0):
    """A built-in scene (evray.demo_names() lists them); seed > 0: a variant of it (the eye's gaze
    plan and iris drawn from the seed, as `evray demo --scene-seed`)."""
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed < 2**64:
        raise ValueError(f"seed must be a whole number from 0 to 2^64 - 1 (got {seed!r})")
    return _evray.demo(name, seed)


def demo_names():
    return _evray.demo_names()


def read(path):
    """Every event of a file evray writes (events.h5, .txt, .npy, .raw, .dat, .aedat4, .bag, ...),
    as an array of EVENT_DTYPE."""
    buf, _, _ = _evray.read(os.fspath(path))
    return _events(buf)


def options():
    """The configuration's options: {python name: (option, takes a value, help)}."""
    return {flag[2:].replace("-", "_"): (flag, takes, help) for flag, takes, help in _evray.options()}


def _option_value(key, value):
    if isinstance(value, (tuple, list)):
        sep = "x" if key == "res" else ","
        return sep.join(_option_value(key, v) for v in value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


class Config:
    """The simulation's settings: the options of `evray render --help` as keyword arguments, named
    without the leading dashes and with '_' for '-' (res="346x260" or (346, 260), duration=0.5,
    sensor="davis346", no_skip=True, ...). Names, defaults and checks are the library's own
    (its configuration table); an unknown option or a bad value raises ValueError with the
    library's one-line message. A flag option takes True (False: left at its default)."""

    def __init__(self, **kwargs):
        takes = {name: t for name, (_, t, _) in options().items()}
        items = []
        for key, value in kwargs.items():
            flag = "--" + key.replace("_", "-")
            if key not in takes:
                raise ValueError(f"unknown option '{key}' (evray.options() lists them)")
            if takes[key]:
                items.append((flag, _option_value(key, value)))
            elif value is True:
                items.append((flag, None))
            elif value is not False and value is not None:
                raise ValueError(f"{flag} is a flag: True or False, got {value!r}")
        self._items = items
        self._c = _evray.make_config(items)  # checks every value now
        self.kwargs = dict(kwargs)

    def _with(self, extra, no_event_files=False):
        """The C configuration of these options and then extra's [(option, value), ...]."""
        return _evray.make_config(self._items + extra, no_event_files)

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.kwargs.items())
        return f"evray.Config({args})"


class Simulator:
    """A simulation of scene with config (evray.Config, or keyword arguments for one)."""

    def __init__(self, scene, config=None, **kwargs):
        if config is None:
            config = Config(**kwargs)
        elif kwargs:
            config = Config(**{**config.kwargs, **kwargs})
        self.scene = scene
        self.config = config
        self._stats = None
        self._run = None
        _evray.validate(scene, config._c)  # against the scene too (ValueError)

    @property
    def stats(self):
        """The run's statistics (a dict of evr_stats' fields): while it goes, as of its last
        finished segment; then the last run's final ones (None before any)."""
        return self._run.stats() if self._run is not None else self._stats

    def _start(self, cfg):
        if self._run is not None:
            raise RuntimeError("this Simulator is running already")
        self._run = _evray.new_run(self.scene, cfg)
        return self._run

    def _finish(self, run):
        try:
            run.finish()
        finally:
            self._stats = run.stats()
            self._run = None

    def stream(self, out_dir=None):
        """Yields the run's events as arrays of EVENT_DTYPE (x, y, t, p), in time order, as the
        library hands them over (a segment's worth or so each). Without out_dir no event file
        is written (a temporary run folder, without previews, is removed at the end); with it,
        the run folder is written as by run() and holds the same events. A slow consumer holds
        the run back (memory stays bounded); leaving the loop early, or Ctrl-C, stops the run
        cleanly. self.stats holds the run's statistics at the end."""
        tmp = None
        extra = []
        if out_dir is None:
            tmp = tempfile.mkdtemp(prefix="evray-stream-")
            extra = [("--out", os.path.join(tmp, "run")), ("--preview", "none")]
        else:
            extra = [("--out", os.fspath(out_dir))]
        try:
            run = self._start(self.config._with(extra, no_event_files=tmp is not None))
            try:
                run.start_stream()
                while True:
                    buf = run.next_batch()
                    if buf is None:
                        break
                    yield _events(buf)
            finally:
                self._finish(run)
        finally:
            if tmp:
                shutil.rmtree(tmp, ignore_errors=True)

    def run(self, out_dir=None):
        """Runs to the end writing the run folder (out_dir, else the configuration's --out), as
        the evray command does; returns the statistics (also self.stats). Ctrl-C stops the run
        and completes its files before KeyboardInterrupt goes on."""
        extra = [("--out", os.fspath(out_dir))] if out_dir is not None else []
        run = self._start(self.config._with(extra))
        try:
            run.start_files()
            run.wait()
        finally:
            self._finish(run)
        return self.stats


__all__ = ["Config", "Simulator", "Scene", "EVENT_DTYPE", "load", "demo", "demo_names", "read",
           "options"]
