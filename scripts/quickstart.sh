#!/usr/bin/env bash
# The main job on the embedded default input: installs the dependencies (Debian packages), builds,
# renders the built-in moving-objects scene (320x240, 16 frames, 1 spp, 64-spp reference),
# denoises it with the default method (detail), writes the video and contact sheets, and prints
# the quality table against the reference.
#   scripts/quickstart.sh [OUT_DIR]   (default out/quickstart)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/quickstart}"
bash scripts/install_deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target rtdenoise_cli
bin=build/release/rtdenoise
"$bin" render moving-objects -o "$out/scene" --width 320 --height 240 --frames 16 --ref-spp 64
"$bin" denoise "$out/scene" -o "$out/denoised" --video "$out/denoised.mp4"
"$bin" compare "$out/denoised" "$out/scene/reference" --images "$out/contact" \
    --json "$out/quality.json"
echo "video: $out/denoised.mp4   contact sheets: $out/contact/   metrics: $out/quality.json"
