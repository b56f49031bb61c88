#!/bin/sh
# Fresh Debian 12 to a built evray: packages, then a release build in ./build.
set -eu
cd "$(dirname "$0")/.."
scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
