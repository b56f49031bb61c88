#!/bin/sh
# The whole test suite: a release build and an AddressSanitizer+UBSan build, every test in each.
set -eu
cd "$(dirname "$0")/.."
scripts/deps.sh
jobs="$(nproc)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$jobs"
# CUDA code is built and compiled in the release build; the sanitizers check the host code
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DEVR_SANITIZE=ON -DEVR_CUDA=OFF
cmake --build build-asan -j"$jobs"
scripts/test-venv.sh build/venv
scripts/test-blender.sh
echo "== release build =="
(cd build && ctest --output-on-failure -j"$jobs")
echo "== AddressSanitizer + UBSan build =="
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export LSAN_OPTIONS="suppressions=$(pwd)/tests/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
(cd build-asan && ctest --output-on-failure -j"$jobs")
