#!/usr/bin/env bash
# The quality table (docs/results.md): renders each built-in test scene with a converged reference,
# denoises it with every method (defaults), and prints scene x method: relMSE, PSNR, SSIM and
# temporal error (means over the frames) as a Markdown table.
#   scripts/quality_table.sh [WIDTH HEIGHT FRAMES REF_SPP]   (default 128 128 8 256)
# Environment: SCENES (default the four below), METHODS (default "input jbf atrous temporal
# svgf") and EXTRA (options added to
# every denoise, e.g. EXTRA="--svgf-clamp-k 0" METHODS=svgf for the paper's SVGF), RENDER_EXTRA
# (options added to every render, e.g. "--confidence": the renderer's A-SVGF confidence, which
# the detail method then reads).
set -euo pipefail
cd "$(dirname "$0")/.."
width="${1:-128}" height="${2:-128}" frames="${3:-8}" refspp="${4:-256}"
bin=build/release/rtdenoise
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "| scene | method | relMSE | PSNR (dB) | SSIM | temporal error |"
echo "|---|---|---|---|---|---|"
for scene in ${SCENES:-moving-objects camera-pan thin-geometry switching-light}; do
  "$bin" render "$scene" -o "$work/$scene" --width "$width" --height "$height" \
      --frames "$frames" --ref-spp "$refspp" ${RENDER_EXTRA:-} -q
  # "input": the noisy frames themselves (a 0-radius JBF without firefly removal is the identity)
  for method in ${METHODS:-input jbf atrous temporal svgf}; do
    args=(--method "$method" ${EXTRA:-})
    [ "$method" = input ] && args=(--method jbf --radius 0 --no-outlier --no-albedo)
    "$bin" denoise "$work/$scene" -o "$work/$scene-$method" "${args[@]}" -q
    "$bin" compare "$work/$scene-$method" "$work/$scene/reference" \
        --json "$work/$scene-$method.json" -q 2>/dev/null
    python3 - "$scene" "$method" "$work/$scene-$method.json" <<'PY'
import json, sys
scene, method, path = sys.argv[1:4]
m = json.load(open(path))["mean"]
fmt = lambda v, f: "inf" if v is None else format(v, f)
print(f"| {scene} | {method} | {fmt(m['rel_mse'], '.4f')} | {fmt(m['psnr'], '.2f')} | "
      f"{fmt(m['ssim'], '.3f')} | {fmt(m['temporal_error'], '.4f')} |")
PY
  done
done
echo
echo "(${width}x${height}, ${frames} frames, 1 spp input, ${refspp}-spp reference; $(date -u +%F))"
