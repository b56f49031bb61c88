"""What evray leaves in a run folder, and how a run ends: events.h5 byte-identical for the same
inputs however the writers' flushes fell; --force starts from a folder without the earlier run's
files; a write that fails (a file size limit, a full file system) ends the run with one clear
line and keeps valid files holding every event the writers took, marked in run.json; Ctrl-C's
files hold exactly what the message says; a second Ctrl-C, or SIGTERM, stops a long segment at
once."""
import json
import os
import resource
import shutil
import signal
import subprocess
import time

import numpy as np

import evrtest as T

EYE = ["--res", "64x48", "--quiet"]


def run_env(env, *args, expect=0, limit=None):
    """evray with extra environment variables (dict), and a file size limit in bytes."""
    def preexec():
        if limit:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    p = subprocess.run([T.EVRAY, *map(str, args)], capture_output=True, text=True,
                       env={**os.environ, **env}, preexec_fn=preexec)
    if expect is not None and p.returncode != expect:
        print(p.stdout, p.stderr)
        raise SystemExit(f"evray {' '.join(map(str, args))}: exit {p.returncode}, expected {expect}")
    return p


def read(path):
    with open(path, "rb") as f:
        return f.read()


def event_files(d):
    """The run folder's event files as (t, x, y, p) arrays of int64, read with h5py, numpy."""
    import h5py
    out = {}
    meta = T.load_run_json(d)
    for name in meta["outputs"]:
        p = os.path.join(d, name)
        if name.endswith(".h5"):
            with h5py.File(p, "r") as f:
                out[name] = np.stack([f["events"][k][()].astype(np.int64) for k in "txyp"], 1)
        elif name.endswith(".npy"):
            a = np.load(p)
            out[name] = np.stack([a[k].astype(np.int64) for k in "txyp"], 1)
        elif name.endswith(".txt"):
            a = np.loadtxt(p, ndmin=2).reshape(-1, 4)
            out[name] = np.stack([np.round(a[:, 0] * 1e6).astype(np.int64),
                                  *(a[:, k].astype(np.int64) for k in (1, 2, 3))], 1)
    return meta, out


def check_kept(d, what, reference=None):
    """A run folder left by a stopped or failed run: run.json says so, every event file is valid,
    sorted, holds the number of events run.json counts, all the same events, and (reference: the
    events of a run that went on) exactly those before complete_until_seconds."""
    meta, files = event_files(d)
    s = meta["stats"]
    T.check(s["interrupted"] is True and s["complete"] is False, f"{what}: run.json: not complete")
    T.check(len(files) > 0, f"{what}: event files kept")
    first = None
    for name, ev in files.items():
        T.check(len(ev) == s["events"], f"{what}: {name} holds the {s['events']} events run.json counts ({len(ev)})")
        T.check(bool(np.all(np.diff(ev[:, 0]) >= 0)), f"{what}: {name} sorted")
        if first is None:
            first = ev
        else:
            T.check(np.array_equal(ev, first), f"{what}: {name} holds the same events as the others")
    until_us = s["complete_until_seconds"] * 1e6
    if first is not None and len(first):
        T.check(first[-1, 0] < until_us, f"{what}: no event at or after complete_until")
    if reference is not None and first is not None:
        want = reference[reference[:, 0] < round(until_us)]
        T.check(np.array_equal(first, want),
                f"{what}: every event before complete_until ({len(first)} of {len(want)})")
    T.check(not [f for f in os.listdir(d) if f.endswith(".tmp") or f.startswith(".evray")],
            f"{what}: no temporary or reserve file left: {os.listdir(d)}")
    return meta


root = T.tmpdir()

# --- events.h5 byte-identical: two runs, one flushing after every batch (EVR_FLUSH_SECONDS=0, a
# hidden test switch), the other at the usual interval
a, b = os.path.join(root, "a"), os.path.join(root, "b")
RUN = ["--res", "128x96", "--duration", "0.5", "--quiet", "--no-preview"]
run_env({"EVR_FLUSH_SECONDS": "0"}, "-o", a, *RUN)
run_env({}, "-o", b, *RUN)
ha, hb = read(os.path.join(a, "events.h5")), read(os.path.join(b, "events.h5"))
T.check(len(ha) > 100000, f"a run of more than one HDF5 chunk ({len(ha)} bytes)")
T.check(ha == hb, "events.h5 byte-identical for the same inputs, whenever the flushes came")

# --- --force: the earlier run's files go (events.npy/.txt, previews), a file of the user's stays
f = os.path.join(root, "force")
T.run("-o", f, *EYE, "--duration", "0.2", "--format", "all", "--preview", "png")
T.check(os.path.isdir(os.path.join(f, "preview")) and os.path.exists(os.path.join(f, "events.npy")),
        "the first run wrote previews and events.npy")
with open(os.path.join(f, "notes.txt"), "w") as fh:
    fh.write("mine\n")
T.run("-o", f, *EYE, "--duration", "0.1", "--format", "h5", "--no-preview", "--force")
T.check(sorted(os.listdir(f)) == ["camera_poses.txt", "events.h5", "notes.txt", "run.json"],
        f"--force: only the new run's files and the user's ({sorted(os.listdir(f))})")

# --- a write that fails (a file size limit of 3 MB: EFBIG, as a full disk's ENOSPC): one line of
# error, exit 1, and the run folder keeps valid files with every event the writers took
full = os.path.join(root, "full")
T.run("-o", full, *EYE, "--duration", "1.2", "--format", "npy", "--no-preview")
_, ref = event_files(full)
ref = ref["events.npy"]
lim = os.path.join(root, "limit")
p = run_env({}, "-o", lim, *EYE, "--duration", "1.2", "--format", "h5,npy,txt", "--no-preview",
            expect=1, limit=3 << 20)
lines = p.stderr.strip().splitlines()
T.check(len(lines) == 2 and lines[0].startswith("evray: error: ") and "File too large" in lines[0]
        and "keeps every event before" in lines[1], f"a write error: one clear line, then what is kept: {lines}")
if os.path.exists(os.path.join(lim, "run.json")):
    meta = check_kept(lim, "file size limit", ref)
    T.check("File too large" in meta.get("failed", ""), "run.json names the failure")
    T.check(meta["stats"]["events"] > 10000, f"events before the failure kept ({meta['stats']['events']})")
else:
    T.check(False, f"a failed run keeps its folder and run.json ({os.listdir(lim) if os.path.exists(lim) else 'none'})")


# --- a full file system: tmpfs in a mount namespace of its own (root, or a user namespace)
def in_tmpfs(size, out, *args):
    """Runs evray with -o on a fresh tmpfs of size; copies the run folder to out. None: no way
    to mount one here."""
    script = ('mount -t tmpfs -o size=%s tmpfs "$1" || exit 99; shift; d="$1"; shift; '
              '"$@" -o "$d/run"; rc=$?; mkdir -p "%s"; [ -d "$d/run" ] && cp -a "$d/run/." "%s/"; '
              'exit $rc') % (size, out, out)
    mnt = os.path.join(root, "mnt")
    os.makedirs(mnt, exist_ok=True)
    for unshare in (["unshare", "-m"], ["unshare", "-rm"]):
        try:
            p = subprocess.run([*unshare, "sh", "-c", script, "sh", mnt, mnt, T.EVRAY, *map(str, args)],
                               capture_output=True, text=True)
        except FileNotFoundError:
            return None
        if p.returncode != 99 and "unshare failed" not in p.stderr:
            return p
    return None


tiny = in_tmpfs("4k", os.path.join(root, "tiny"), *EYE, "--duration", "0.3")
if tiny is None:
    print("note: no tmpfs could be mounted here (no root, no user namespaces): full-disk cases skipped")
else:
    T.check(tiny.returncode == 1 and tiny.stderr.count("\n") == 1 and "not enough free space" in tiny.stderr,
            f"a 4 KB file system: a clear error, no crash ({tiny.returncode}: {tiny.stderr.strip()})")
    out = os.path.join(root, "small")
    p = in_tmpfs("8m", out, *EYE, "--duration", "1.2", "--format", "h5,npy,txt", "--no-preview")
    T.check(p.returncode == 1 and "No space left on device" in p.stderr,
            f"an 8 MB file system fills: exit 1, the error says why ({p.returncode}: {p.stderr.strip()})")
    if os.path.exists(os.path.join(out, "run.json")):
        check_kept(out, "full file system", ref)
    else:
        T.check(False, f"a full file system keeps the run folder ({os.listdir(out)})")


# --- evray convert onto a file system that fills: one line, exit 1, nothing left there, no
# crash (HDF5 used to be able to crash at exit after a failed close when it had read first)
def convert_in_tmpfs(size_kb, src, name):
    script = ('mount -t tmpfs -o size=%dk tmpfs "$1" || exit 99; "$2" convert "$3" "$1/%s"; '
              'rc=$?; ls -A "$1"; exit $rc') % (size_kb, name)
    mnt = os.path.join(root, "mnt-convert")
    os.makedirs(mnt, exist_ok=True)
    for unshare in (["unshare", "-m"], ["unshare", "-rm"]):
        p = subprocess.run([*unshare, "sh", "-c", script, "sh", mnt, T.EVRAY, src],
                           capture_output=True, text=True)
        if p.returncode != 99 and "unshare failed" not in p.stderr:
            return p
    return None


if tiny is not None:
    src = os.path.join(a, "events.h5")
    half = max(16, os.path.getsize(src) // 2048)
    for name in ("out.h5", "out.npy", "out.txt"):
        for kb in (16, half):
            p = convert_in_tmpfs(kb, src, name)
            lines = p.stderr.strip().splitlines()
            T.check(p.returncode == 1 and len(lines) == 1 and "No space left on device" in lines[0]
                    and p.stdout.strip() == "",
                    f"convert to {name} on a {kb} KB file system: one line, exit 1, nothing left "
                    f"({p.returncode}: {p.stderr.strip()!r}, left {p.stdout.split()})")


# --- Ctrl-C: the files hold exactly every event before the time the message gives
def signalled(d, sigs, *args, started=0.5):
    """Runs evray, sends sigs [(delay, signal)] once its HDF5 temporary file is there; returns
    (exit code, stderr, seconds from the last signal to the exit)."""
    proc = subprocess.Popen([T.EVRAY, "-o", d, *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and not os.path.exists(os.path.join(d, "events.h5.tmp")):
        time.sleep(0.02)
    time.sleep(started)
    t = time.time()
    for delay, sig in sigs:
        time.sleep(delay)
        t = time.time()
        proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err, time.time() - t


ic = os.path.join(root, "int")
rc, err, _ = signalled(ic, [(0, signal.SIGINT)], *EYE, "--duration", "5", "--format", "h5,npy",
                       "--no-preview", "--threads", "1", "--samples-per-frame", "10")
T.check(rc == 130, f"Ctrl-C: exit 130 ({rc}: {err.strip()})")
if rc == 130:
    meta = T.load_run_json(ic)
    until = meta["stats"]["complete_until_seconds"]
    T.check(f"holds every event before t = {until:.6f} s" in err, f"the message gives complete_until ({err.strip()})")
    fr = os.path.join(root, "int_ref")
    T.run("-o", fr, *EYE, "--duration", f"{until + 0.1:.6f}", "--format", "npy", "--no-preview",
          "--samples-per-frame", "10")
    _, r = event_files(fr)
    check_kept(ic, "Ctrl-C", r["events.npy"])

# --- a second Ctrl-C, and SIGTERM, stop a long segment (2 s of work and more) at once
LONG = [*EYE, "--res", "160x120", "--fps", "1", "--samples-per-frame", "300", "--duration", "5",
        "--format", "h5,npy", "--no-preview", "--threads", "1"]
for what, sigs in (("a second Ctrl-C", [(0, signal.SIGINT), (0.3, signal.SIGINT)]),
                   ("SIGTERM", [(0, signal.SIGTERM)])):
    d = os.path.join(root, what.replace(" ", "_"))
    rc, err, took = signalled(d, sigs, *LONG)
    T.check(rc == 130, f"{what}: exit 130 ({rc}: {err.strip()})")
    T.check(took < 3.0, f"{what}: stops at once ({took:.2f} s)")
    if rc == 130:
        check_kept(d, what)

T.finish("test_run_files")
