#!/usr/bin/env bash
# The README's test command, what CI runs (.ci/run): builds the release preset and runs the whole
# test suite, then the soak (1000 frames per method at constant resident memory), then the
# sanitizer runs (scripts/test_sanitizers.sh: the suite under ASan + UBSan, the fuzz targets).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release
cmake --build --preset release -j "$(nproc)"
ctest --preset release -j "$(nproc)"
# One test at a time: each denoiser's threads use every core, and the timing it prints means
# something.
ctest --preset soak
bash scripts/test_sanitizers.sh
