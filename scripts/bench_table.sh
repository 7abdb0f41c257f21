#!/usr/bin/env bash
# The README's speed figures, from `rtdenoise bench` (medians; JSON beside the printed tables):
#   1. every CPU instruction set on the course scene (box, 512x512), speed-ups against the scalar
#      kernels measured in the same run;
#   2. scaling with the pixel count: every method at 512x512, 1280x720, 1920x1080, 3840x2160 on
#      rendered inputs (moving-objects), on the widest instruction set and on CUDA.
#   scripts/bench_table.sh [OUT_DIR] [FRAMES]   (default docs/bench, 5 timed frames per case)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-docs/bench}" frames="${2:-5}"
bin=build/release/rtdenoise
mkdir -p "$out"
box=../shared/data/box
if [ -f "$box/beauty_0.exr" ]; then
  "$bin" bench --input "$box" --device cpu-scalar cpu-sse2 cpu-avx2 cpu-avx512 \
      --frames "$frames" --json "$out/isa_box.json"
fi
# Devices this machine lacks (no GPU, no AVX-512) are reported as skipped.
"$bin" bench --device cpu cuda --frames "$frames" --json "$out/scaling.json"
