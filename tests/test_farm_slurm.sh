#!/usr/bin/env bash
# The farm on a real scheduler (issue 40): starts a one-node Slurm on localhost (munged,
# slurmctld, slurmd as the user running the test, root or not: jobs then run as that user; their
# key, config, state and logs in a temporary folder; stopped and removed at exit), renders a 48-frame camera-pan scene, submits it with
# scripts/farm_slurm.sh as 4 chunks of 12 frames with the default warm-up, waits, and checks:
#   - the final task reports every frame written, and the results are those of one run over the
#     whole shot (with the default warm-up every chunk here starts from frame 0: identical);
#   - a chunk whose frame is deleted is reported by name, and rerun alone it completes the shot;
#   - a bad submission (a range beyond the input) fails before anything is queued.
#
#   tests/test_farm_slurm.sh RTDENOISE      exit 0 pass, 1 fail, 77 skip (no Slurm or MUNGE)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
rtdenoise=${1:-${RTDENOISE:-}}
[ -x "$rtdenoise" ] || { echo "usage: $0 RTDENOISE (the rtdenoise binary)"; exit 2; }
for tool in munged mungekey slurmctld slurmd sbatch sinfo scancel; do
  if ! command -v "$tool" > /dev/null && [ ! -x "/usr/sbin/$tool" ]; then
    echo "SKIP: $tool is not installed (Debian: apt-get install slurm-wlm munge)"
    exit 77
  fi
done
export PATH=$PATH:/usr/sbin
start=$(date +%s)
user=$(id -un)
work=$(mktemp -d)
chmod 700 "$work"
pids=()
cleanup() {
  # Jobs of this test's cluster only (its slurm.conf): their steps would outlive the daemons.
  if [ "${SLURM_CONF:-}" = "$work/slurm/slurm.conf" ]; then
    scancel --quiet --user="$user" 2> /dev/null || true
  fi
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
  done
  rm -rf "$work"
}
trap cleanup EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# ---- MUNGE: a key and a daemon of our own, on our own socket ----
mkdir -p "$work/munge"
chmod 700 "$work/munge"
mungekey --create --keyfile="$work/munge/munge.key" --bits=1024
chmod 400 "$work/munge/munge.key"
munged --foreground --force --socket="$work/munge/socket" --key-file="$work/munge/munge.key" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" \
  --seed-file="$work/munge/munged.seed" > "$work/munge/stdout.log" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$work/munge/socket" ] && break; sleep 0.1; done
[ -S "$work/munge/socket" ] || { cat "$work/munge/"*.log; echo "FAIL: munged did not start"; exit 1; }

# ---- Slurm: one node, this machine, ports no one else here uses, daemons as this user ----
port=$((20000 + RANDOM % 20000))
mkdir -p "$work/slurm/state" "$work/slurm/spool"
cat > "$work/slurm/slurm.conf" << EOF
ClusterName=rtdtest
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/socket
StateSaveLocation=$work/slurm/state
SlurmdSpoolDir=$work/slurm/spool
SlurmctldPidFile=$work/slurm/slurmctld.pid
SlurmdPidFile=$work/slurm/slurmd.pid
SlurmctldLogFile=$work/slurm/slurmctld.log
SlurmdLogFile=$work/slurm/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=localhost CPUs=2 State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm/slurm.conf
slurmctld -D -c -f "$SLURM_CONF" > "$work/slurm/slurmctld.stdout" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" > "$work/slurm/slurmd.stdout" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  [ "$(sinfo -h -o %T 2> /dev/null)" = idle ] && break
  sleep 0.2
done
if [ "$(sinfo -h -o %T 2> /dev/null)" != idle ]; then
  sinfo || true
  tail -n 20 "$work/slurm/"*.log "$work/slurm/"*.stdout
  echo "FAIL: the one-node Slurm did not come up"
  exit 1
fi
echo "Slurm up in $(($(date +%s) - start)) s (slurmctld port $port)"

# ---- the shot: rendered, then denoised once as a whole ----
scene=$work/scene
"$rtdenoise" render camera-pan -o "$scene" --width 96 --height 64 --frames 48 --ref-spp 1 \
  > "$work/render.log" 2>&1 || { cat "$work/render.log"; echo "FAIL: render"; exit 1; }
# On the CPU (bit-for-bit the same in every process): the comparison below is exact.
"$rtdenoise" denoise "$scene" -o "$work/single" -q --device cpu ||
  { echo "FAIL: the single run"; exit 1; }

# ---- a bad submission fails before anything is queued ----
if "$here/scripts/farm_slurm.sh" "$scene" -o "$work/bad" --frames 40:60 --chunk 10 \
  --rtdenoise "$rtdenoise" > "$work/bad.log" 2>&1; then
  fail "a range beyond the input was submitted"
fi
grep -q "frames 40..59 reach outside .*frames 0..47)" "$work/bad.log" || fail "the bad range's message: $(cat "$work/bad.log")"
[ ! -e "$work/bad/farm/chunks.txt" ] || fail "the bad submission wrote its chunk table"
[ -z "$(squeue -h)" ] || fail "the bad submission queued jobs: $(squeue -h)"

# ---- the farm: 4 chunks of 12 frames with the default warm-up ----
farm_start=$(date +%s)
if ! "$here/scripts/farm_slurm.sh" "$scene" -o "$work/farm" --frames 0:48 --chunk 12 \
  --rtdenoise "$rtdenoise" --wait -- --device cpu > "$work/farm.log" 2>&1; then
  cat "$work/farm.log" "$work/farm/farm/"*.log
  fail "the farm run failed"
fi
echo "4 chunks denoised and checked through Slurm in $(($(date +%s) - farm_start)) s"
grep -q "OK: all 48 frames of 4 chunks written" "$work/farm.log" || fail "the check: $(cat "$work/farm.log")"

# The assembled shot against the single run, per frame (relMSE, temporal error): with the
# default warm-up (48, docs/farm.md) every chunk of this 48-frame shot warms up from frame 0, so
# they must be the same values, bit for bit (the seam tolerances of shorter warm-ups: test_chunks).
same_as_single_run() {
  "$rtdenoise" compare "$work/farm" "$work/single" --json "$work/compare.json" \
    > "$work/compare.log" 2>&1 || { cat "$work/compare.log"; return 1; }
  python3 - "$work/compare.json" << 'EOF'
import json, sys
frames = json.load(open(sys.argv[1]))["frames"]
worst_rel = max(f["rel_mse"] for f in frames)
worst_temporal = max(f["temporal_error"] or 0.0 for f in frames)
print(f"assembled vs single run, {len(frames)} frames: worst relMSE {worst_rel:g}, "
      f"worst temporal error {worst_temporal:g} (both must be 0)")
sys.exit(0 if worst_rel == 0 and worst_temporal == 0 else 1)
EOF
}
same_as_single_run || fail "the chunks differ from the single run"

# ---- a lost frame: the check names its chunk; rerun alone, the shot is complete again ----
rm "$work/farm/result_30.exr"
if "$here/scripts/farm_slurm.sh" --check "$work/farm" > "$work/check.log" 2>&1; then
  fail "the check passed without result_30.exr"
fi
grep -q "chunk 2 (frames 24:36): 1 frames missing (result_30.exr" "$work/check.log" ||
  fail "the check's report: $(cat "$work/check.log")"
grep -q -- "--resubmit $work/farm 2\$" "$work/check.log" || fail "no resubmit line: $(cat "$work/check.log")"
"$here/scripts/farm_slurm.sh" --resubmit "$work/farm" 2 --wait > "$work/resubmit.log" 2>&1 ||
  fail "the resubmitted chunk: $(cat "$work/resubmit.log")"
grep -q "OK: all 48 frames of 4 chunks written" "$work/resubmit.log" ||
  fail "the check after the rerun: $(cat "$work/resubmit.log")"
same_as_single_run || fail "the rerun chunk differs from the single run"

echo "slurm farm test: $(($(date +%s) - start)) s in all"
if [ $failures -gt 0 ]; then
  tail -n 5 "$work/slurm/"*.log
  exit 1
fi
echo "PASS"
