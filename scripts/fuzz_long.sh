#!/usr/bin/env bash
# Runs the libFuzzer targets long, one after another (the fuzz preset's build; it is configured
# and built first): scripts/fuzz_long.sh [-n RUNS | -t SECONDS] [TARGET...]
# Default: 10000000 inputs per target, every target (fuzz_exr fuzz_frame fuzz_matrix fuzz_blender
# fuzz_config). Each runs at nice 10 over a corpus in build/fuzz/long/<target> (seeded from
# tests/fuzz/corpus, kept between runs); findings go to build/fuzz/long/artifacts/. Prints per
# target the inputs run, the time and the inputs per second, and a line per finding.
set -euo pipefail
cd "$(dirname "$0")/.."
limit=(-runs=10000000)
while getopts "n:t:" opt; do
  case "$opt" in
    n) limit=(-runs="$OPTARG") ;;
    t) limit=(-max_total_time="$OPTARG") ;;
    *) echo "usage: $0 [-n RUNS | -t SECONDS] [TARGET...]" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(fuzz_exr fuzz_frame fuzz_matrix fuzz_blender fuzz_config)
declare -A corpus=([fuzz_exr]=exr [fuzz_frame]=frame [fuzz_matrix]=matrix [fuzz_blender]=blender [fuzz_config]=config)

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "$(nproc)" --target "${targets[@]}"
out=build/fuzz/long
mkdir -p "$out/artifacts"
status=0
summary=()
for t in "${targets[@]}"; do
  mkdir -p "$out/$t"
  log="$out/$t.log"
  start=$(date +%s)
  set +e
  nice -n 10 "build/fuzz/tests/fuzz/$t" "${limit[@]}" -rss_limit_mb=2048 -malloc_limit_mb=1024 \
    -timeout=20 -print_final_stats=1 -artifact_prefix="$out/artifacts/$t-" \
    "$out/$t" "tests/fuzz/corpus/${corpus[$t]}" >"$log" 2>&1
  rc=$?
  set -e
  seconds=$(( $(date +%s) - start ))
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  rate=$(( execs / (seconds > 0 ? seconds : 1) ))
  line="$t: $execs inputs in $seconds s ($rate/s), corpus $(ls "$out/$t" | wc -l) files, exit $rc"
  if [ "$rc" -ne 0 ]; then
    status=1
    line="$line: FINDING, see $log and $out/artifacts/"
  fi
  echo "$line"
  summary+=("$line")
done
echo "---"
printf '%s\n' "${summary[@]}"
exit $status
