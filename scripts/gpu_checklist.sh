#!/usr/bin/env bash
# Everything issue 5 asks of a GPU, in one call (device time is scarce): the `gpu` tests, a
# memory check of every method, the CUDA scaling table, the course scene, and the Google
# Benchmark cases; logs and JSON into OUT_DIR (on the accelerator machine: $OUT), tarred.
# Run from the repository root after `. .devcarry/setup.sh` (scripts/stage_gpu_run.sh), or in a
# build made there. Without a GPU every step reports itself skipped, so it runs anywhere.
#   scripts/gpu_checklist.sh [OUT_DIR] [FRAMES]   (default $OUT or out/gpu, 200 frames)
set -uo pipefail
cd "$(dirname "$0")/.."
out="${1:-${OUT:-out/gpu}}" frames="${2:-200}"
bin=build/release/rtdenoise
mkdir -p "$out"
status=0
. scripts/step.sh  # step NAME COMMAND...
command -v nvidia-smi > /dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.max.sm \
    --format=csv > "$out/gpu.txt" 2>&1
git rev-parse --short HEAD > "$out/commit.txt" 2>/dev/null
step gpu-tests ctest --preset release -L gpu --output-on-failure
if command -v compute-sanitizer > /dev/null; then
    step memcheck compute-sanitizer --tool memcheck --error-exitcode 1 \
        "$bin" bench --device cuda --size 700x300 --frames 3
else
    echo "== memcheck: skipped (no compute-sanitizer)"
fi
# The firefly removal's tile pass (--tile-passes on; off by default until timed here): races on
# its shared memory, then alternating runs against the separate passes at 1080p and 4K.
if command -v compute-sanitizer > /dev/null; then
    step racecheck-tiles compute-sanitizer --tool racecheck --error-exitcode 1 \
        "$bin" bench --device cuda --method temporal svgf --size 700x300 --frames 3 --tile-passes on
    step memcheck-tiles compute-sanitizer --tool memcheck --error-exitcode 1 \
        "$bin" bench --device cuda --method temporal svgf --size 700x300 --frames 3 --tile-passes on
fi
for size in 1920x1080 3840x2160; do
    for round in 1 2 3; do
        for tiles in off on; do
            step "tiles-$size-$tiles-$round" "$bin" bench --device cuda --method temporal svgf \
                --size "$size" --frames "$frames" --cache /tmp/rtd-bench-cache --tile-passes "$tiles"
        done
    done
done
step scaling "$bin" bench --device cuda --frames "$frames" --cache /tmp/rtd-bench-cache \
    --json "$out/cuda_scaling.json"
box=../shared/data/box
if [ -f "$box/beauty_0.exr" ]; then
    step box "$bin" bench --device cuda --input "$box" --frames "$frames" \
        --json "$out/cuda_box.json"
fi
step bench-methods build/release/bench/bench_methods --benchmark_filter=Cuda \
    --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
    --benchmark_out="$out/bench_methods_cuda.json"
# One file back is simpler than many: the device tool returns a few files per call.
tar -czf /tmp/gpu_checklist.tar.gz -C "$(dirname "$out")" "$(basename "$out")" &&
    mv /tmp/gpu_checklist.tar.gz "$out/"
exit $status
