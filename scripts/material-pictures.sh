#!/bin/sh
# Makes the materials' pictures in docs/img (README.md lists them): the all-materials scene
# (tests/all_materials.py) as `evray still` sees it and its events as `evray render`'s preview
# shows them, and five test scenes of tests/test_materials_render.py (tests/material_assets.py)
# from the tests' own camera. Small PNGs; about 15 s on two cores.
#   scripts/material-pictures.sh [BINARY] [OUTDIR]     (default build/evray, docs/img)
set -eu
cd "$(dirname "$0")/.."
bin="${1:-build/evray}"
out="${2:-docs/img}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
python3 - "$work" <<'EOF'
import sys
sys.path.insert(0, "tests")
import all_materials
import material_assets as MA
all_materials.write(sys.argv[1])
for make in (MA.transmission_slab, MA.glint_sphere, MA.alpha_mask_card, MA.normal_plane_tangents,
             MA.emissive_texture):
    make(sys.argv[1])
EOF
# the lamp is moving at t = 0.6 (from 0.5 on); the events are those of 0.55 to 0.6 s, the second
# preview window of a run from 0.5 s (ON blue, OFF red)
"$bin" still "$work/all_materials.gltf" --res 320x240 --time 0.6 -q -o "$out/materials-all.png"
"$bin" render "$work/all_materials.gltf" -o "$work/run" --res 320x240 --start 0.5 --duration 0.1 \
    --preview-window 0.05 --format npy --quiet
cp "$work/run/preview/events_000001.png" "$out/materials-all-events.png"
# name, asset, exposure (linear radiance times E is white): the glint is thousands of times
# brighter than the black sphere; exposure 100 shows the sphere's faint reflection of the ambient
while read -r name asset exposure; do
    "$bin" still "$work/$asset.gltf" --res 128x128 -q --exposure "$exposure" -o "$out/materials-$name.png"
done <<'EOF'
slab transmission_slab 1
glint glint_sphere 100
mask alpha_mask_card 3
normal-map normal_plane_tangents 3
emissive emissive_texture 0.2
EOF
ls -l "$out"/materials-*.png
