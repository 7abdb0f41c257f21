#!/usr/bin/env bash
# Makes the README's before/after pictures from the course scene (frame 19 of box):
# the noisy input, each method's result, and the reprojection validity map of `temporal`.
#   scripts/readme_images.sh [BUILD_DIR]   (default build/release)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-build/release}/rtdenoise"
box=../shared/data/box
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# A 0-radius JBF without firefly removal and energy restoration is the identity: the input.
"$bin" denoise "$box" -o "$work/input" --method jbf --radius 0 --no-outlier --no-energy --png -q
"$bin" denoise "$box" -o "$work/jbf" --method jbf --png -q
"$bin" denoise "$box" -o "$work/atrous" --method atrous --png -q
"$bin" denoise "$box" -o "$work/temporal" --method temporal --png --debug -q
"$bin" denoise "$box" -o "$work/svgf" --method svgf --png -q
"$bin" denoise "$box" -o "$work/detail" --method detail --png -q
mkdir -p docs/images
for m in input jbf atrous temporal svgf detail; do cp "$work/$m/result_19.png" "docs/images/box_$m.png"; done
cp "$work/temporal/reprojection_19.png" docs/images/box_reprojection.png
echo "wrote docs/images/box_{input,jbf,atrous,temporal,svgf,detail,reprojection}.png"
