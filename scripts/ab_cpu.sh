#!/usr/bin/env bash
# Alternating A/B timing of two builds of the rtdenoise command on the CPU, for a machine whose
# speed drifts between runs (a shared VM): ROUNDS rounds, each running A then B, and the median
# of the per-round ratios B/A, for the whole frame and for the passes matching PASSES.
#   scripts/ab_cpu.sh BIN_A BIN_B METHOD [ROUNDS=10] [FRAMES=40] [SIZE=box] [PASSES=regex]
# SIZE "box" uses ../shared/data/box; WxH renders inputs once (cached in /tmp/rtd-ab-cache).
# PASSES defaults to the A-Trous passes of atrous/temporal/svgf and SVGF's variance.
set -euo pipefail
a=$1 b=$2 method=$3 rounds=${4:-10} frames=${5:-40} size=${6:-box}
passes=${7:-'(svgf-)?atrous[0-9]|svgf-variance'}
here=$(cd "$(dirname "$0")/.." && pwd)
if [[ $size == box ]]; then
    input=(--size 512x512 --input "$here/../shared/data/box")
else
    input=(--size "$size" --cache /tmp/rtd-ab-cache)
fi
results=$(mktemp)
trap 'rm -f "$results"' EXIT
for ((r = 0; r < rounds; ++r)); do
    for which in A B; do
        bin=$a
        [[ $which == B ]] && bin=$b
        out=$("$bin" bench --method "$method" --device cpu "${input[@]}" --frames "$frames" 2>&1)
        total=$(awk -v m="$method" '$1 == m && $2 ~ /^(cpu|cuda)/ {print $3}' <<<"$out")
        # (A method without such passes, jbf, sums none: grep's status is not a failure.)
        sum=$({ grep -E "^\s+($passes)\s" <<<"$out" || true; } | awk '{s += $2} END {printf "%.3f", s}')
        echo "$which $total $sum" >>"$results"
    done
done
python3 - "$results" "$method" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1])]
a = [r for r in rows if r[0] == "A"]
b = [r for r in rows if r[0] == "B"]
for col, label in ((1, "frame"), (2, "passes")):
    ta, tb = [float(r[col]) for r in a], [float(r[col]) for r in b]
    ratios = [y / x for x, y in zip(ta, tb) if x > 0]
    if not ratios:
        continue
    print(f"{sys.argv[2]} {label}: A median {statistics.median(ta):.3f} ms, "
          f"B median {statistics.median(tb):.3f} ms, B/A paired median "
          f"{statistics.median(ratios):.3f} ({min(ratios):.3f}-{max(ratios):.3f}, "
          f"{len(ratios)} rounds)")
PY
