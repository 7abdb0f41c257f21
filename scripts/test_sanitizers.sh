#!/usr/bin/env bash
# The sanitizer runs (scripts/test.sh calls it; issue 20): the whole test suite built with the
# `debug` preset (clang, -O1, AddressSanitizer + UndefinedBehaviorSanitizer, any finding fatal;
# every label but soak, so the quality tier too),
# then each libFuzzer target of the `fuzz` preset for RTD_FUZZ_RUNS inputs (20000) over its seed
# corpus. Any sanitizer report fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="$(nproc)"
# LeakSanitizer on, and a report of a leak, overflow or UB is an error exit (the preset's
# -fno-sanitize-recover=all makes UBSan's abort the test).
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

cmake --preset debug
cmake --build --preset debug -j "$jobs"
ctest --preset debug -j "$jobs"

cmake --preset fuzz
cmake --build --preset fuzz -j "$jobs" --target fuzz_exr fuzz_frame fuzz_matrix fuzz_blender fuzz_config
ctest --preset fuzz
