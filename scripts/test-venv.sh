#!/bin/sh
# Creates a Python virtual environment (default build/venv) holding the independent readers that
# tests/test_prophesee.py, tests/test_rosbag.py and tests/test_aedat4.py check evray's camera
# formats against, pinned, from PyPI: expelliarmus (EVT 2.0, DAT), evlib (EVT 2.0, EVT 3.0), evt3
# and faery (EVT 3.0), rosbags (ROS1 bags), dv-processing and aedat (AEDAT 4.0), h5py; and Dask
# (dask.distributed, with PyYAML) for tests/test_dataset_dask.py. Never the
# system Python. Without network it says so and leaves no environment: those tests then skip.
set -eu
cd "$(dirname "$0")/.."
venv="${1:-build/venv}"
PKGS="numpy==2.4.6 h5py==3.16.0 expelliarmus==1.1.12 evlib==0.13.2 evt3==0.4.1 faery==0.7.1 rosbags==0.11.9 dv-processing==2.0.4 aedat==2.3.0 dask==2026.8.0 distributed==2026.8.0"
stamp="$venv/evray-oracles.txt"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$PKGS" ]; then
    exit 0
fi
rm -rf "$venv"
if ! python3 -m venv "$venv"; then
    echo "test-venv: python3 -m venv failed (Debian: apt-get install python3-venv); oracle tests will skip" >&2
    rm -rf "$venv"
    exit 0
fi
# shellcheck disable=SC2086
if ! "$venv/bin/pip" install --quiet --disable-pip-version-check $PKGS; then
    echo "test-venv: cannot install $PKGS (no network?); oracle tests will skip" >&2
    rm -rf "$venv"
    exit 0
fi
echo "$PKGS" >"$stamp"
