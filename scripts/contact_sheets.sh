#!/usr/bin/env bash
# The contact sheets of the hard cases (docs/results.md): per scene one row, input / svgf / detail /
# reference, on the frame that shows the case (thin-geometry frame 7: thin shadows; reflections
# frame 7: reflections under camera motion; switching-light frame 6: the light just switched
# off). Writes docs/images/hard_cases.png (and one PNG per scene). The renders carry the split
# signal (--split), which detail reads and the others ignore.
#   scripts/contact_sheets.sh [SIZE=160] [REF_SPP=256] [BUILD_DIR=build/release]
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-160}" refspp="${2:-256}" bin="${3:-build/release}/rtdenoise"
command -v ffmpeg >/dev/null || { echo "contact_sheets.sh: ffmpeg is needed" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
identity=(--method jbf --radius 0 --no-outlier --no-albedo --png -q)
rows=()
for case in thin-geometry:7 reflections:7 switching-light:6; do
  scene=${case%:*} frame=${case#*:}
  "$bin" render "$scene" -o "$work/$scene" --width "$size" --height "$size" --frames 8 \
      --ref-spp "$refspp" --split -q
  "$bin" denoise "$work/$scene" -o "$work/$scene-input" "${identity[@]}"
  # The reference tone-mapped like the input: its frames as the beauty of the same G-buffer.
  mkdir "$work/$scene-ref"
  for f in "$work/$scene"/*.*; do ln -s "$f" "$work/$scene-ref/"; done
  for ((i = 0; i < 8; ++i)); do
    ln -sf "$work/$scene/reference/reference_$i.exr" "$work/$scene-ref/beauty_$i.exr"
  done
  "$bin" denoise "$work/$scene-ref" -o "$work/$scene-reference" "${identity[@]}"
  for method in svgf detail; do
    "$bin" denoise "$work/$scene" -o "$work/$scene-$method" --method "$method" --png -q
  done
  ffmpeg -loglevel error -y -i "$work/$scene-input/result_$frame.png" \
      -i "$work/$scene-svgf/result_$frame.png" -i "$work/$scene-detail/result_$frame.png" \
      -i "$work/$scene-reference/result_$frame.png" -filter_complex hstack=inputs=4 \
      "docs/images/hard_$scene.png"
  rows+=(-i "docs/images/hard_$scene.png")
done
ffmpeg -loglevel error -y "${rows[@]}" -filter_complex vstack=inputs=3 docs/images/hard_cases.png
echo "wrote docs/images/hard_cases.png (rows: thin-geometry 7, reflections 7, switching-light 6;"
echo "columns: input, svgf, detail, reference)"
