#!/bin/sh
# Installs Debian 12's blender (3.4.1) when there is none: tests/test_blender.py runs it headless
# to build a skinned and a morph-target glTF file with Blender's own exporter. About 210 MB from
# the package registry (185 packages, 715 MiB installed), once per machine. Without network, or
# without the package, it says so and that test skips: it never stops the test run, and every
# registry call is bounded in time.
set -u
command -v blender >/dev/null 2>&1 && exit 0
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo -n"
# shellcheck disable=SC2086
if timeout 300 $SUDO apt-get update -qq &&
    timeout 900 $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq blender >/dev/null; then
    exit 0
fi
echo "test-blender: cannot install Debian's blender (no network?); tests/test_blender.py will skip" >&2
exit 0
