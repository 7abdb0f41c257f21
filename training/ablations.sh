#!/usr/bin/env bash
# What each group of input features and the temporal loss term contribute: the learned method
# retrained without each in turn (same corpus, options and seed as the default weights' run),
# then scored on the generated validation set beside the full run. Reports only: nothing here
# chooses anything.
#
#   training/ablations.sh [CORPUS=cache/corpus128] [STEPS=4000]
# Runs: training/runs/ablation-<name>/; table: training/runs/ablations.md.
set -euo pipefail
cd "$(dirname "$0")/.."
corpus=${1:-cache/corpus128}
steps=${2:-4000}
common=(--corpus "$corpus" --steps "$steps" --relmse-clip 10 --tonemap display --threads 2)
declare -A variants=(
  [full]=""
  [no-temporal-term]="--no-temporal"
  [no-relative-noise]="--drop-feature 0"
  [no-history]="--drop-feature 1,2"
  [no-level-differences]="--drop-feature 3,4,5,6,7"
  [no-level-variances]="--drop-feature 8,9,10,11,12,13"
)
methods=svgf
for name in full no-temporal-term no-relative-noise no-history no-level-differences no-level-variances; do
  out=training/runs/ablation-$name
  if [ ! -f "$out/learned_weights.txt" ]; then
    # shellcheck disable=SC2086
    /usr/bin/python3 training/train.py "${common[@]}" --out "$out" ${variants[$name]} > "$out.log" 2>&1
  fi
  methods+=",learned=$out/learned_weights.txt"
done
PYTHONPATH=build/release/python:scripts /usr/bin/python3 scripts/validation_table.py \
  --corpus "$corpus" --sets validation --methods "$methods" | tee training/runs/ablations.md
