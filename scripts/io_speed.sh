#!/usr/bin/env bash
# Whether the command line keeps up with the denoiser: the whole-process frame rate of
# `rtdenoise denoise DATA -o OUT` (every frame read, denoised and written; the process's wall
# time, start-up included) against the denoise-only rate of `rtdenoise bench --input DATA` (the
# median frame, inputs in memory), both on the CPU with one method, measured alternately in one
# run (the VM's speed drifts between runs). Several builds may be given, to compare them in the
# same run; each round runs every build's bench and denoise in turn.
#   scripts/io_speed.sh [DATA=../shared/data/box] [ROUNDS=5] [BIN...=build/release/rtdenoise]
# Environment: METHOD (svgf), DENOISE_OPTIONS (extra options of denoise, e.g. "--compression zip").
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
data=${1:-$here/../shared/data/box}
rounds=${2:-5}
shift $(($# < 2 ? $# : 2))
bins=("$@")
[[ ${#bins[@]} -gt 0 ]] || bins=("$here/build/release/rtdenoise")
method=${METHOD:-svgf}
read -r -a denoiseOptions <<<"${DENOISE_OPTIONS:-}"
frames=$(find "$data" -maxdepth 1 -name 'beauty_*.exr' | wc -l)
[[ $frames -gt 0 ]] || { echo "io_speed.sh: no beauty_<i>.exr in $data" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores;" \
    "$frames frames of $data; method $method on the CPU; denoise options: ${DENOISE_OPTIONS:-(defaults)}"
for ((r = 0; r < rounds; ++r)); do
    for ((b = 0; b < ${#bins[@]}; ++b)); do
        bin=${bins[b]}
        bench=$("$bin" bench --input "$data" --method "$method" --device cpu --frames 20 2>&1)
        benchMs=$(awk -v m="$method" '$1 == m && $2 == "cpu" {print $3}' <<<"$bench")
        start=$(date +%s.%N)
        summary=$("$bin" denoise "$data" -o "$work/out$b" --method "$method" --device cpu \
            "${denoiseOptions[@]}" 2>/dev/null)
        end=$(date +%s.%N)
        # The command's own figures: fps from the first read to the last write, and its medians.
        ownFps=$(sed -n 's/.*(\([0-9.]*\) fps overall.*/\1/p' <<<"$summary")
        denoiseMs=$(awk '$1 == "denoise" && $2 == "median" {print $3}' <<<"$summary")
        readWaitMs=$(awk '$1 == "read" && $2 == "wait" {print $4}' <<<"$summary")
        writeMs=$(awk '$1 == "write" && $2 == "median" {print $3}' <<<"$summary")
        echo "$b $benchMs $start $end $ownFps $denoiseMs $readWaitMs $writeMs" >>"$work/rows"
    done
done
python3 - "$work/rows" "$frames" "${bins[@]}" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1])]
frames = int(sys.argv[2])
bins = sys.argv[3:]
print("build: bench ms/frame (rate) | denoise whole-process fps, ratio to the bench rate | "
      "the command's own: fps, denoise / read wait / write medians ms (medians over rounds)")
for b, name in enumerate(bins):
    mine = [r for r in rows if int(r[0]) == b]
    med = lambda i: statistics.median(float(r[i]) for r in mine)
    ratios = [frames / (float(r[3]) - float(r[2])) / (1000.0 / float(r[1])) for r in mine]
    whole = statistics.median(frames / (float(r[3]) - float(r[2])) for r in mine)
    print(f"{name}: bench {med(1):.2f} ms ({1000.0 / med(1):.1f} fps) | whole process "
          f"{whole:.1f} fps, ratio {statistics.median(ratios):.2f} "
          f"({min(ratios):.2f}-{max(ratios):.2f}, {len(mine)} rounds) | own {med(4):.1f} fps, "
          f"{med(5):.1f} / {med(6):.1f} / {med(7):.1f} ms")
PY
