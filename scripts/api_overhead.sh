#!/usr/bin/env bash
# What calling rtdenoise from Python costs on top of the library: the median ms per frame of
# `rtdenoise bench` (C++, the denoiser alone) and of rtdenoise.Denoiser.denoise (Python over the
# C API: arrays bound, a new output array per call) on the same rendered frames, alternating
# ROUNDS times in one run (the VM's speed drifts). Needs the release build with its Python module.
#   scripts/api_overhead.sh [WIDTHxHEIGHT] [METHOD]     (default 512x512 svgf)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-512x512}"
method="${2:-svgf}"
rounds="${ROUNDS:-3}"
frames="${FRAMES:-40}"
python="${PYTHON:-/usr/bin/python3}"
bin=build/release/rtdenoise
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$bin" render moving-objects -o "$work/scene" --width "${size%x*}" --height "${size#*x}" \
    --frames 4 --gbuffer-only -q
for round in $(seq "$rounds"); do
  "$bin" bench --input "$work/scene" --method "$method" --device cpu --frames "$frames" \
      --json "$work/bench.json" >/dev/null
  cpp=$("$python" -c "import json,sys; print(json.load(open(sys.argv[1]))['cases'][0]['median_ms'])" \
      "$work/bench.json")
  py=$(PYTHONPATH=build/release/python "$python" - "$work/scene" "$method" "$frames" <<'PY'
import statistics, sys, time
import rtdenoise
scene, method, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
inputs = [frame.inputs() for frame in rtdenoise.open_sequence(scene)]
den = rtdenoise.Denoiser(method, device="cpu")
den.denoise(**inputs[0])  # warm-up: the library's buffers are allocated here
times = []
for i in range(count):
    start = time.perf_counter()
    den.denoise(**inputs[i % len(inputs)])
    times.append((time.perf_counter() - start) * 1e3)
print(f"{statistics.median(times):.4f}")
PY
)
  "$python" -c "import sys; c, p = map(float, sys.argv[1:3]); print(f'round {sys.argv[3]}: C++ {c:.3f} ms, Python {p:.3f} ms, Python / C++ {p / c:.3f}')" "$cpp" "$py" "$round"
done
