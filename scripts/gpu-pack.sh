#!/bin/sh
# Builds evray with CUDA here and gathers the program, labels_compare (tests/labels_compare.c:
# test_cuda_labels.py's comparison without h5py, which the GPU machine lacks) and the shared
# libraries a bare CUDA machine lacks into gpu-carry/ (git-ignored), for running on the GPU
# machine:
#   scripts/gpu-unpack.sh && LD_LIBRARY_PATH=gpu-carry/lib gpu-carry/evray ...
# With --python, also the Python package (gpu-carry/python/evray: its module on the stable ABI, so
# the GPU machine's python3 loads it; numpy is there), built in build-gpu-py (position-independent
# code, kept apart from build-gpu's program):
#   LD_LIBRARY_PATH=gpu-carry/lib PYTHONPATH=gpu-carry/python python3 -c 'import evray'
set -eu
cd "$(dirname "$0")/.."
python=0
[ "${1:-}" = "--python" ] && python=1
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
cmake --build build-gpu -j"$(nproc)"
rm -rf gpu-carry
mkdir -p gpu-carry/lib
cp build-gpu/evray build-gpu/labels_compare gpu-carry/
strip gpu-carry/evray gpu-carry/labels_compare   # the carry limit is 64 MiB
# the GPU tests are Python scripts around the program; the C tests run here, in CI

# every library but the C runtime, the driver and what every Ubuntu 24.04 base system has (the
# carry limit is 64 MiB)
ldd build-gpu/evray build-gpu/labels_compare | awk '/=> \// {print $3}' | sort -u | \
    grep -v -E '/(libc|libm|libpthread|libdl|librt|libresolv|ld-linux[^/]*|libgcc_s|libstdc\+\+|libcuda)\.so' | \
    grep -v -E '/(libz|libzstd|libcrypto|libssl|libgnutls|libp11-kit|libunistring|libidn2|libffi|libgmp|libtasn1|libnettle|libhogweed|libcom_err|libkeyutils|libkrb5|libkrb5support|libk5crypto|libgssapi_krb5)\.so' | \
    grep -v -E '/(libcurl|libssh2|libldap-[0-9.]*|liblber-[0-9.]*|libsasl2|libnghttp2|libpsl|librtmp|libbrotli[a-z]*|libaec|libsz|libpng16)\.so' | \
    while read -r lib; do cp -L "$lib" gpu-carry/lib/; done
# packed: the carry limit is 64 MiB and the libraries alone come close (unpacked there by
# scripts/gpu-unpack.sh, which scripts/gpu-check.sh runs)
carried="evray labels_compare lib"
if [ "$python" = 1 ]; then
    cmake -S . -B build-gpu-py -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90 -DEVR_PYTHON_MODULE=ON >/dev/null
    cmake --build build-gpu-py -j"$(nproc)" --target _evray
    mkdir -p gpu-carry/python/evray
    cp python/evray/__init__.py build-gpu-py/_evray.abi3.so gpu-carry/python/evray/
    strip --strip-unneeded gpu-carry/python/evray/_evray.abi3.so
    carried="$carried python"
fi
# shellcheck disable=SC2086
(cd gpu-carry && tar -czf ../gpu-carry.tar.gz $carried)
rm -rf gpu-carry
mkdir gpu-carry
mv gpu-carry.tar.gz gpu-carry/
du -sh gpu-carry
