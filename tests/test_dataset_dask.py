"""evray dataset on a local Dask cluster (dask.distributed's LocalCluster, two worker processes:
`--scheduler local:2`), from a YAML specification, in the oracle environment (scripts/test-venv.sh
installs Dask and PyYAML there): the 6 clips run to a complete manifest, each clip's files are
byte-identical to a run on this machine's cores (tests/test_dataset.py's ways), and a run killed
while one clip hangs finishes only that clip when run again."""
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time

import evrtest as T
from test_dataset import RUNNER, SPEC, latest, manifest, same_files, slow_evray

FILES = ["events.h5", "events.npy", "labels.h5"]


def to_yaml(spec):
    """The specification as YAML (JSON is YAML's subset; written out as a YAML user would)."""
    def val(v):
        return json.dumps(v)
    lines = [f"clips: {spec['clips']}", f"seed: {spec['seed']}", "scenes:"]
    lines += [f"  - {val(s)}" for s in spec["scenes"]]
    lines += [f"format: {spec['format']}", f"labels_fps: {spec['labels_fps']}", "options:"]
    lines += [f"  {k}: {val(v)}" for k, v in spec["options"].items()]
    lines += ["vary:"] + [f"  {k}: {val(v)}" for k, v in spec["vary"].items()]
    return "\n".join(lines) + "\n"


def main():
    python = T.oracle_python(["dask.distributed", "yaml", "h5py"])
    evray = os.path.abspath(T.EVRAY)
    tmp = tempfile.mkdtemp(prefix="evray-dask-")
    try:
        spec = os.path.join(tmp, "spec.yaml")
        open(spec, "w").write(to_yaml(SPEC))
        local = os.path.join(tmp, "local")
        json.dump(SPEC, open(os.path.join(tmp, "spec.json"), "w"))
        p = subprocess.run([evray, "dataset", os.path.join(tmp, "spec.json"), "-o", local],
                           capture_output=True, text=True)
        T.check(p.returncode == 0, f"the local run: {p.stderr.strip()[-300:]}")

        dask = os.path.join(tmp, "dask")
        t0 = time.time()
        p = subprocess.run([python, RUNNER, spec, "-o", dask, "--scheduler", "local:2", "--evray",
                            evray], capture_output=True, text=True)
        T.check(p.returncode == 0, f"the Dask run: exit {p.returncode}: {p.stderr.strip()[-400:]}")
        rows = latest(dask)
        T.check(sorted(rows) == list(range(6)) and all(r["status"] == "done" for r in rows.values()),
                f"a complete manifest on Dask: {[(k, r['status'], r.get('error')) for k, r in rows.items()]}")
        print(f"test_dataset_dask: 6 clips on a local Dask cluster in {time.time() - t0:.1f} s")
        for k in range(6):
            d = same_files(os.path.join(local, "clips", f"{k:05d}"),
                           os.path.join(dask, "clips", f"{k:05d}"), FILES)
            T.check(d is None, f"clip {k}: {d} on Dask differs from the local run's")

        # killed while clip 3 hangs (the other worker finishes the rest): the rerun runs clip 3
        killed = os.path.join(tmp, "killed")
        wrapper = slow_evray(tmp, evray)
        p = subprocess.Popen([python, RUNNER, spec, "-o", killed, "--scheduler", "local:2",
                              "--evray", wrapper], stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, start_new_session=True)
        deadline = time.time() + 300
        while time.time() < deadline and len(latest(killed)) < 5:
            time.sleep(0.05)
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        before = latest(killed)
        T.check(sorted(before) == [0, 1, 2, 4, 5] and all(r["status"] == "done"
                                                          for r in before.values()),
                f"the killed Dask run finished all but clip 3 ({sorted(before)})")
        n = len(manifest(killed))
        p = subprocess.run([python, RUNNER, spec, "-o", killed, "--scheduler", "local:2",
                            "--evray", evray], capture_output=True, text=True)
        new = manifest(killed)[n:]
        T.check(p.returncode == 0 and [r["clip"] for r in new] == [3] and new[0]["status"] == "done",
                f"the rerun on Dask ran clip 3 alone: {[(r['clip'], r['status']) for r in new]}")
        d = same_files(os.path.join(local, "clips", "00003"), os.path.join(killed, "clips", "00003"),
                       FILES)
        T.check(d is None, f"clip 3 rerun on Dask: {d} differs")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    T.finish("test_dataset_dask")


if __name__ == "__main__":
    main()
