#!/bin/sh
# Builds evray with CUDA here and gathers the program, the GPU tests and the shared libraries a
# bare CUDA machine lacks into gpu-carry/ (git-ignored), for running on the GPU machine:
#   LD_LIBRARY_PATH=gpu-carry/lib gpu-carry/evray ...
set -eu
cd "$(dirname "$0")/.."
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
cmake --build build-gpu -j"$(nproc)"
rm -rf gpu-carry
mkdir -p gpu-carry/lib
cp build-gpu/evray gpu-carry/
for t in build-gpu/tests/test_*; do [ -x "$t" ] && cp "$t" gpu-carry/; done
# every library but the C runtime and the driver, which the GPU machine has
ldd build-gpu/evray gpu-carry/test_* | awk '/=> \// {print $3}' | sort -u | \
    grep -v -E '/(libc|libm|libpthread|libdl|librt|ld-linux[^/]*|libgcc_s|libstdc\+\+|libcuda)\.so' | \
    while read -r lib; do cp -L "$lib" gpu-carry/lib/; done
du -sh gpu-carry
