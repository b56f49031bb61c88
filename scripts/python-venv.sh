#!/bin/sh
# Makes a fresh Python virtual environment (default build/pyvenv) and installs evray into it from
# this source tree the way a user does (pip wheel ., and the wheel installed: what pip install .
# does), without the CUDA backend (about a minute to build rather than 20), with what tests/python
# needs, pinned, from PyPI. The package's build tools come in first and the package builds
# without isolation, so that no network is needed past that point: without network it says so
# and leaves no environment (the Python package tests then skip); a package that fails to build
# is an error (exit 1).
#   scripts/python-venv.sh [VENV] [BUILD_DIR]
# BUILD_DIR (default build/python-pkg) is scikit-build-core's build folder, kept between runs so
# that a second install only rebuilds what changed.
set -eu
cd "$(dirname "$0")/.."
venv="${1:-build/pyvenv}"
build_dir="${2:-build/python-pkg}"
PKGS="numpy==2.4.6 pytest==9.2.0 iniconfig==2.3.1 pluggy==1.7.0 Pygments==2.21.0 scikit-build-core==1.1.2 packaging==26.4 pathspec==1.1.1"
rm -rf "$venv"
if ! python3 -m venv "$venv"; then
    echo "python-venv: python3 -m venv failed (Debian: apt-get install python3-venv); the Python package tests will skip" >&2
    rm -rf "$venv"
    exit 0
fi
# shellcheck disable=SC2086
if ! "$venv/bin/pip" install --quiet --disable-pip-version-check $PKGS; then
    echo "python-venv: cannot install $PKGS (no network?); the Python package tests will skip" >&2
    rm -rf "$venv"
    exit 0
fi
# pip wheel . then the wheel installed: both of the package's ways of being built are used
rm -rf "$build_dir/wheel"
if ! "$venv/bin/pip" wheel --quiet --disable-pip-version-check --no-build-isolation --no-deps \
    -C cmake.define.EVR_CUDA=OFF -C build-dir="$build_dir" -w "$build_dir/wheel" .; then
    echo "python-venv: pip wheel . failed" >&2
    exit 1
fi
if ! "$venv/bin/pip" install --quiet --disable-pip-version-check --no-deps "$build_dir"/wheel/evray-*.whl; then
    echo "python-venv: pip install of the wheel failed" >&2
    exit 1
fi
