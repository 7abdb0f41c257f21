#!/usr/bin/env bash
# The README's test command, what CI runs (.ci/run): builds the release preset and runs the whole
# test suite in its tiers: the fast tier (ctest --preset release), the quality tests (rendered
# scenes against 256-spp references), the soak (1000 frames per method at constant resident
# memory), the farm test (a shot in chunks through a one-node Slurm), then the sanitizer runs (scripts/test_sanitizers.sh: the suite under ASan + UBSan,
# quality tests included, and the fuzz targets).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release
cmake --build --preset release -j "$(nproc)"
ctest --preset release -j "$(nproc)"
# The installed package in a consumer project's build (label install: about 24 s).
ctest --preset install
# One process that renders the scenes and denoises them on every core.
ctest --preset quality
# One test at a time: each denoiser's threads use every core, and the timing it prints means
# something.
ctest --preset soak
# The farm on a one-node Slurm the test starts on localhost (about 30 s; skipped, saying so,
# without slurm-wlm and munge, which scripts/install_deps.sh installs).
ctest --preset slurm
bash scripts/test_sanitizers.sh
