#!/bin/sh
# On the GPU machine: unpacks what scripts/gpu-pack.sh packed (gpu-carry/evray,
# gpu-carry/labels_compare, gpu-carry/lib).
set -eu
cd "$(dirname "$0")/.."
if [ -f gpu-carry/gpu-carry.tar.gz ] && { [ ! -x gpu-carry/evray ] || [ ! -x gpu-carry/labels_compare ]; }; then tar -xzf gpu-carry/gpu-carry.tar.gz -C gpu-carry; fi
