#!/bin/sh
# Installs the Debian 12 packages evray needs to build and test, when any is missing.
set -eu
PKGS="build-essential clang-format cmake pkg-config libembree-dev libassimp-dev libhdf5-dev libpng-dev libstb-dev libdeflate-dev liblz4-dev libzstd-dev libxxhash-dev libbz2-dev python3 python3-dev python3-venv python3-numpy python3-h5py"
missing=""
for p in $PKGS; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "installing:$missing" >&2
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $missing
