#!/usr/bin/env bash
# Denoises a shot on a Slurm cluster: one array task per chunk of frames (each after its warm-up
# frames), then a final task that checks every frame was written and names any chunk that was
# not. docs/farm.md explains the chunks, the warm-up and the other farm managers.
#
#   scripts/farm_slurm.sh INPUT -o OUT --frames A:B [--chunk N] [--warmup W] [--rtdenoise PATH]
#                         [--sbatch "ARGS"] [--wait] [-- DENOISE_OPTIONS...]
#       submits the shot (frames A..B-1, the input's numbers) as ceil((B-A)/N) chunks of N
#       frames (default 200: the default warm-up of 48 frames adds 24 %) and the final check;
#       --wait waits for the check and exits with its status. --sbatch: more sbatch options for
#       every task ("--partition=gpu --gres=gpu:1 --cpus-per-task=8"); each task's OpenMP
#       threads follow --cpus-per-task.
#   scripts/farm_slurm.sh --check OUT [--frames A:B --chunk N]
#       what the final task runs (exit 1 naming each chunk that is missing frames or did not
#       finish); with --frames and --chunk, for a shot another manager ran: result files only
#   scripts/farm_slurm.sh --resubmit OUT K[,K...] [--wait]
#                                            reruns those chunks alone, then the check again
#
# OUT/farm/ holds the job's files: the chunk table (chunks.txt), the task scripts, one log per
# chunk (chunk_K.log), chunk_K.done once chunk K finished, and check.log. OUT must be on storage
# every node sees. Rerunning a submission or a chunk rewrites the same files (results are
# written to a temporary name and renamed, so none is ever half-written).
set -euo pipefail

# The usage lines of the header above; exits with $1 (2: a mistake, 0: --help).
usage() {
  sed -n '6,17p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit "${1:-2}"
}
die() {
  echo "farm_slurm: $*" >&2
  exit 2
}

# ---- the final check: every chunk finished and every frame written ----
check() {
  local out=$1 farm=$1/farm rows markers=1
  if [ -n "${2:-}" ]; then  # the chunks of --frames A:B --chunk N, without Slurm's markers
    rows=$(chunk_table "$2" "$3")
    markers=0
  else
    [ -f "$farm/chunks.txt" ] || die "$farm/chunks.txt: no such file: submit the shot first"
    rows=$(cat "$farm/chunks.txt")
  fi
  local missing_chunks=() k a b n missing_frames
  while read -r k a b; do
    missing_frames=()
    for ((n = a; n < b; n++)); do
      [ -f "$out/result_$n.exr" ] || missing_frames+=("$n")
    done
    if { [ $markers = 1 ] && [ ! -f "$farm/chunk_$k.done" ]; } || [ ${#missing_frames[@]} -gt 0 ]; then
      missing_chunks+=("$k")
      if [ ${#missing_frames[@]} -gt 0 ]; then
        echo "chunk $k (frames $a:$b): ${#missing_frames[@]} frames missing" \
          "(result_${missing_frames[0]}.exr ...)$([ $markers = 1 ] && echo "; its log: $farm/chunk_$k.log")"
      else
        echo "chunk $k (frames $a:$b): did not finish (no $farm/chunk_$k.done);" \
          "its log: $farm/chunk_$k.log"
      fi
    fi
  done <<< "$rows"
  local chunks total
  chunks=$(wc -l <<< "$rows")
  total=$(awk '{ s += $3 - $2 } END { print s }' <<< "$rows")
  if [ ${#missing_chunks[@]} -gt 0 ]; then
    local list
    list=$(IFS=,; echo "${missing_chunks[*]}")
    echo "FAILED: ${#missing_chunks[@]} of $chunks chunks incomplete; rerun them alone:"
    if [ $markers = 1 ]; then
      echo "  $(cd "$(dirname "$0")" && pwd)/farm_slurm.sh --resubmit $out $list"
    else
      echo "  (chunks $list, in your manager)"
    fi
    return 1
  fi
  echo "OK: all $total frames of $chunks chunks written to $out"
}

# "K A B" per chunk of N frames of A:B (frames A..B-1).
chunk_table() {
  local frames=$1 size=$2 first end a b k=0
  [[ $frames =~ ^([0-9]+):([0-9]+)$ ]] || die "--frames A:B: the shot's frames A..B-1, got '$frames'"
  first=${BASH_REMATCH[1]} end=${BASH_REMATCH[2]}
  [[ $size =~ ^[1-9][0-9]*$ ]] || die "--chunk $size: give the frames per chunk, 1 or more"
  for ((a = first; a < end; a += size, k++)); do
    b=$((a + size < end ? a + size : end))
    echo "$k $a $b"
  done
}

# Submits the array tasks `array` ("0-3" or "2,5") of OUT/farm/chunk.sbatch, then the check
# after them; prints the job ids; with wait=1 waits for the check and returns its status.
submit() {
  local farm=$1 array=$2 wait=$3 chunk_job check_job
  local -a extra=()
  read -r -a extra < "$farm/sbatch_args"
  chunk_job=$(sbatch --parsable --array="$array" --output="$farm/chunk_%a.log" "${extra[@]}" \
    "$farm/chunk.sbatch")
  chunk_job=${chunk_job%%;*}
  # afterany: the check runs however the chunks ended, and names the ones that failed.
  check_job=$(sbatch --parsable --dependency="afterany:$chunk_job" --job-name=rtd-check \
    --output="$farm/check.log" ${wait:+--wait} "$farm/check.sbatch") && status=0 || status=$?
  check_job=${check_job%%;*}
  echo "submitted chunks $array as job $chunk_job, the check as job $check_job (logs: $farm)"
  if [ "$wait" = 1 ]; then
    cat "$farm/check.log"
    return "$status"
  fi
}

case "${1:-}" in
  -h | --help) usage 0 ;;
  "") usage ;;
  --check)
    if [ $# -eq 6 ] && [ "$3" = --frames ] && [ "$5" = --chunk ]; then
      check "$2" "$4" "$6"
    else
      [ $# -eq 2 ] || usage
      check "$2"
    fi
    exit
    ;;
  --resubmit)
    [ $# -ge 3 ] || usage
    out=$2 chunks=$3 wait=""
    [ "${4:-}" = --wait ] && wait=1
    [ -f "$out/farm/chunk.sbatch" ] || die "$out/farm/chunk.sbatch: no such file: submit first"
    [[ $chunks =~ ^[0-9]+(,[0-9]+)*$ ]] || die "--resubmit $chunks: give chunk numbers, 2 or 2,5"
    for k in ${chunks//,/ }; do
      grep -q "^$k " "$out/farm/chunks.txt" || die "chunk $k: not in $out/farm/chunks.txt"
      rm -f "$out/farm/chunk_$k.done"
    done
    submit "$out/farm" "$chunks" "$wait"
    exit
    ;;
esac

input=$1
shift
out="" frames="" chunk=200 warmup="" rtdenoise="" sbatch_args="" wait=""
denoise_options=()
while [ $# -gt 0 ]; do
  case "$1" in
    -o | --output) out=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --chunk) chunk=$2; shift 2 ;;
    --warmup) warmup=$2; shift 2 ;;
    --rtdenoise) rtdenoise=$2; shift 2 ;;
    --sbatch) sbatch_args=$2; shift 2 ;;
    --wait) wait=1; shift ;;
    --) shift; denoise_options=("$@"); break ;;
    *) die "unknown option $1 (denoise options go after --)" ;;
  esac
done
[ -n "$out" ] || die "give the output folder: -o OUT"
[[ $frames =~ ^([0-9]+):([0-9]+)$ ]] || die "--frames A:B: the shot's frames A..B-1, got '$frames'"
first=${BASH_REMATCH[1]} end=${BASH_REMATCH[2]}
[ "$end" -gt "$first" ] || die "--frames $frames: the shot is empty"
[[ $chunk =~ ^[1-9][0-9]*$ ]] || die "--chunk $chunk: give the frames per chunk, 1 or more"
[ -z "$warmup" ] || [[ $warmup =~ ^[0-9]+$ ]] || die "--warmup $warmup: give a frame count"
command -v sbatch > /dev/null || die "sbatch not found: run this on a Slurm submit host"
scontrol ping > /dev/null 2>&1 ||
  die "no Slurm controller answers (scontrol ping): run this on a submit host, or set SLURM_CONF"
if [ -z "$rtdenoise" ]; then
  rtdenoise=$(command -v rtdenoise || true)
  here=$(cd "$(dirname "$0")/.." && pwd)
  [ -n "$rtdenoise" ] || rtdenoise="$here/build/release/rtdenoise"
fi
[ -x "$rtdenoise" ] || die "$rtdenoise: not an executable (give --rtdenoise PATH)"
# Absolute paths, for tasks that start elsewhere; nothing is created before the checks below.
rtdenoise=$(realpath -m "$rtdenoise")
input=$(realpath -m "$input")
out=$(realpath -m "$out")
farm=$out/farm

warmup_option=()
[ -n "$warmup" ] && warmup_option=(--warmup "$warmup")
# Everything a task could fail on (missing or broken frames, a bad option) fails here, once,
# before anything is queued.
"$rtdenoise" denoise "$input" -o "$out" --frames "$first:$end" "${warmup_option[@]}" \
  "${denoise_options[@]}" --dry-run

mkdir -p "$farm"
rm -f "$farm"/chunk_*.done "$farm/check.log"
chunk_table "$frames" "$chunk" > "$farm/chunks.txt.tmp"
mv "$farm/chunks.txt.tmp" "$farm/chunks.txt"
chunks=$(wc -l < "$farm/chunks.txt")
echo "$sbatch_args" > "$farm/sbatch_args"

# The task scripts: self-contained, so that a chunk can be rerun alone with plain sbatch too.
{
  echo "#!/usr/bin/env bash"
  echo "#SBATCH --job-name=rtd-chunk"
  echo "#SBATCH --output=$farm/chunk_%a.log"
  echo "set -euo pipefail"
  echo "read -r k a b < <(grep \"^\$SLURM_ARRAY_TASK_ID \" $(printf %q "$farm/chunks.txt"))"
  echo "rm -f $(printf %q "$farm")/chunk_\$k.done"
  echo "export OMP_NUM_THREADS=\${SLURM_CPUS_PER_TASK:-\${OMP_NUM_THREADS:-}}"
  echo "[ -n \"\$OMP_NUM_THREADS\" ] || unset OMP_NUM_THREADS"
  # $a and $b are the task's own variables, expanded when it runs.
  # shellcheck disable=SC2016
  printf '%q denoise %q -o %q --frames "$a:$b"' "$rtdenoise" "$input" "$out"
  for option in "${warmup_option[@]}" "${denoise_options[@]}"; do printf ' %q' "$option"; done
  echo
  echo "echo \"\$SLURM_JOB_ID\" > $(printf %q "$farm")/chunk_\$k.done.tmp"
  echo "mv $(printf %q "$farm")/chunk_\$k.done.tmp $(printf %q "$farm")/chunk_\$k.done"
} > "$farm/chunk.sbatch"
{
  echo "#!/usr/bin/env bash"
  printf 'exec %q --check %q\n' "$(cd "$(dirname "$0")" && pwd)/$(basename "$0")" "$out"
} > "$farm/check.sbatch"
echo "$chunks chunks of up to $chunk frames, frames $first..$((end - 1))"
submit "$farm" "0-$((chunks - 1))" "$wait"
