#!/usr/bin/env bash
# The GPU checks of issue 24's `detail` method in one short call (device time is scarce): the
# `gpu` tests (CPU/CUDA equivalence, detail with and without the split signal), memcheck over
# detail on an odd size with and without the split files, and CUDA timings of detail against
# svgf at 1080p and 4K (combined) and on 1080p split renders of the reflection scene.
# Run from the repository root after `. .devcarry/setup.sh` (scripts/stage_gpu_run.sh).
#   [BASELINE=other/rtdenoise] scripts/gpu_detail_checks.sh [OUT_DIR] [FRAMES]
#   (default $OUT or out/gpu, 100 frames; BASELINE: also 3 rounds alternating it with this
#   build on both 1080p inputs, for an A/B in one call). It leaves more logs than the device tool
#   returns (8 files): there, give a folder under /tmp and copy its gpu_detail_checks.tar.gz
#   into $OUT.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${1:-${OUT:-out/gpu}}" frames="${2:-100}"
bin=build/release/rtdenoise
work=/tmp/rtd-detail-gpu
mkdir -p "$out" "$work"
status=0
. scripts/step.sh  # step NAME COMMAND...
command -v nvidia-smi > /dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.max.sm \
    --format=csv > "$out/gpu.txt" 2>&1 && cat "$out/gpu.txt"
step gpu-tests ctest --preset release -L gpu --output-on-failure
step render-split-small "$bin" render reflections -o "$work/split-small" --width 301 --height 203 \
    --frames 3 --gbuffer-only --split -q
step render-split-1080p "$bin" render reflections -o "$work/split-1080p" --width 1920 \
    --height 1080 --frames 4 --gbuffer-only --split -q
if command -v compute-sanitizer > /dev/null; then
    step memcheck-detail compute-sanitizer --tool memcheck --error-exitcode 1 \
        "$bin" bench --device cuda --method detail --size 700x300 --frames 3
    step memcheck-detail-split compute-sanitizer --tool memcheck --error-exitcode 1 \
        "$bin" bench --device cuda --method detail --input "$work/split-small" --frames 3
else
    echo "== memcheck: skipped (no compute-sanitizer)"
fi
step bench-combined "$bin" bench --device cuda --method svgf detail --size 1920x1080 3840x2160 \
    --frames "$frames" --cache "$work/cache" --json "$out/detail_cuda_combined.json"
step bench-split "$bin" bench --device cuda --method svgf detail --input "$work/split-1080p" \
    --frames "$frames" --json "$out/detail_cuda_split.json"
if [ -n "${BASELINE:-}" ]; then
    for round in 1 2 3; do
        for build in baseline this; do
            b=$bin
            [ "$build" = baseline ] && b=$BASELINE
            step "ab-combined-$build-$round" "$b" bench --device cuda --method svgf detail \
                --size 1920x1080 --frames "$frames" --cache "$work/cache"
            step "ab-split-$build-$round" "$b" bench --device cuda --method svgf detail \
                --input "$work/split-1080p" --frames "$frames"
        done
    done
fi
# One file back is simpler than many: the device tool returns a few files per call.
tar -czf /tmp/gpu_detail_checks.tar.gz -C "$(dirname "$out")" "$(basename "$out")" &&
    mv /tmp/gpu_detail_checks.tar.gz "$out/"
exit $status
