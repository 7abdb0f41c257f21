#!/usr/bin/env bash
# Prepares .devcarry/ (ignored by git): what a bare GPU machine without this project's Debian
# packages needs to run the GPU tests and the CUDA benchmarks from this machine's release build:
# the binaries with their CTest files, the shared libraries they load, 4 frames of the course
# scene, and setup.sh. On the GPU machine, from the repository root:
#   . .devcarry/setup.sh && ctest --preset release -L gpu --output-on-failure
#   build/release/rtdenoise bench --device cuda --frames 200
#   scripts/gpu_checklist.sh "$OUT"       (all the GPU checks in one call)
# (setup.sh links this checkout's path and ../shared's there: the paths the build recorded.)
#   scripts/stage_gpu_run.sh [BUILD_DIR]   (default build/release, built with nvcc)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build/release}"
stage=.devcarry
grep -qx '/.devcarry/' .git/info/exclude 2>/dev/null || echo '/.devcarry/' >> .git/info/exclude
rm -rf "$stage" && mkdir -p "$stage/libs" "$stage/shared/data/box" "$stage/$build/tests" \
  "$stage/$build/bench" "$stage/$build/src/render" "$stage/$build/src/metrics"
touch "$stage/$build/src/render/CTestTestfile.cmake" "$stage/$build/src/metrics/CTestTestfile.cmake"
cp "$build/CTestTestfile.cmake" "$build/rtdenoise" "$stage/$build/"
cp "$build"/tests/CTestTestfile.cmake "$build"/tests/*_include.cmake "$build"/tests/test_gpu \
  "$build"/tests/test_gpu*_tests.cmake "$stage/$build/tests/"
cp "$build/bench/bench_methods" "$build/bench/CTestTestfile.cmake" "$stage/$build/bench/"
# Every library the binaries load that is not the C/C++ runtime itself.
for lib in $(ldd "$build/rtdenoise" "$build/tests/test_gpu" "$build/bench/bench_methods" |
             awk '/=> \//{print $3}' | sort -u); do
  case "$(basename "$lib")" in
    libc.so*|libm.so*|libstdc++.so*|libgcc_s.so*|ld-linux*) ;;
    *) cp -L "$lib" "$stage/libs/" ;;
  esac
done
box=../shared/data/box
if [ -f "$box/beauty_0.exr" ]; then
  for i in 0 1 2 3; do cp "$box"/*_"$i".* "$stage/shared/data/box/"; done
fi
here="$(pwd -P)" shared="$(cd .. && pwd -P)/shared"
cat > "$stage/setup.sh" <<SETUP
# Sourced on the GPU machine from the repository root.
mkdir -p "$(dirname "$here")"
[ "\$PWD" = "$here" ] || ln -sfn "\$PWD" "$here"
ln -sfn "\$PWD/$stage/shared" "$shared"
mkdir -p build && cp -a $stage/build/. build/
export LD_LIBRARY_PATH="\$PWD/$stage/libs:\${LD_LIBRARY_PATH:-}"
SETUP
du -sh "$stage"
