#!/usr/bin/env bash
# The Blender fixture's quality table (docs/inputs.md): tests/data/blender/noisy (Cycles, 1 spp,
# motion from its Vector pass) denoised by every method, against its 4096-spp reference.
#   scripts/fixture_quality.sh [BUILD_DIR=build/release]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bin=${1:-$here/build/release}/rtdenoise
fixture=$here/tests/data/blender
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| method | relMSE | PSNR (dB) | SSIM | temporal error |"
echo "|---|---|---|---|---|"
row() {
    "$bin" compare "$out/$1" "$fixture/reference" 2>/dev/null |
        awk -v name="$1" '$1 == "mean" {printf "| %s | %.4f | %.2f | %.4f | %.4f |\n", name, $3, $4, $5, $6}'
}
# The input itself: one A-Trous level whose colour sigma keeps every pixel as it is.
"$bin" denoise "$fixture/noisy" -o "$out/input" --method atrous --atrous-passes 1 \
    --sigma-color 1e-6 --no-separate-objects --no-outlier --device cpu -q
row input
for method in jbf atrous temporal svgf detail; do
    "$bin" denoise "$fixture/noisy" -o "$out/$method" --method "$method" --device cpu -q
    row "$method"
done
