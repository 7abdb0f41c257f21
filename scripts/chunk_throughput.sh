#!/usr/bin/env bash
# Frames per second of one machine denoising a shot as one process against as 2 chunks run side
# by side (issue 40 item 4; docs/farm.md): each chunk process gets half the cores
# (OMP_NUM_THREADS), the second starts after the default warm-up. Runs alternate, REPEATS
# times; prints each run and the medians (wall time, files included).
#
#   scripts/chunk_throughput.sh RTDENOISE [WIDTHxHEIGHT] [FRAMES] [REPEATS] [METHOD] [WARMUP]
#   (defaults 320x240, 96 frames, 5 repeats, detail, the command's default warm-up)
set -euo pipefail
rtdenoise=$1
size=${2:-320x240}
frames=${3:-96}
repeats=${4:-5}
method=${5:-detail}
warmup=()
[ -n "${6:-}" ] && warmup=(--warmup "$6")
cores=$(nproc)
half=$(((cores + 1) / 2))
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$rtdenoise" render camera-pan -o "$work/scene" --width "${size%x*}" --height "${size#*x}" \
  --frames "$frames" --ref-spp 1 -q
now() { date +%s.%N; }
middle=$((frames / 2))
one=() two=()
for ((r = 0; r < repeats; r++)); do
  start=$(now)
  "$rtdenoise" denoise "$work/scene" -o "$work/one" --method "$method" --device cpu -q
  one+=("$(echo "$frames / ($(now) - $start)" | bc -l)")
  start=$(now)
  OMP_NUM_THREADS=$half "$rtdenoise" denoise "$work/scene" -o "$work/two" --method "$method" \
    --device cpu -q --frames "0:$middle" &
  first=$!
  OMP_NUM_THREADS=$half "$rtdenoise" denoise "$work/scene" -o "$work/two" --method "$method" \
    --device cpu -q --frames "$middle:$frames" "${warmup[@]}"
  wait "$first"
  two+=("$(echo "$frames / ($(now) - $start)" | bc -l)")
  printf 'run %d: one process %.1f fps, 2 chunks %.1f fps\n' "$((r + 1))" "${one[r]}" "${two[r]}"
done
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
m1=$(median "${one[@]}")
m2=$(median "${two[@]}")
printf '%s, %s, %d frames, %s, %d cores: one process %.1f fps, 2 chunks (%d threads each, the second after a warm-up of %s) %.1f fps: %.2fx\n' \
  "$(uname -n)" "$size" "$frames" "$method" "$cores" "$m1" "$half" "${6:-the default}" "$m2" \
  "$(echo "$m2 / $m1" | bc -l)"
