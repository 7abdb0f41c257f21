#!/usr/bin/env bash
# Installs what rtdenoise needs to build, test and make videos, from Debian's packages.
set -euo pipefail
# libclang-rt-dev: clang's sanitizer and libFuzzer runtimes (the debug and fuzz presets);
# libdeflate-dev: the EXR reader's faster inflate (optional: zlib without it).
# python3-dev, python3-numpy, pybind11-dev: the Python module (python/); python3-pytest: its tests.
# slurm-wlm, munge: the farm test's one-node Slurm (tests/test_farm_slurm.sh runs its own
# daemons, on its own key, socket and ports; the packages' services are not used).
packages=(cmake ninja-build clang libclang-rt-dev libomp-dev g++ libopenexr-dev libpng-dev
          libdeflate-dev libfmt-dev libcli11-dev libgtest-dev libbenchmark-dev ffmpeg
          python3-dev python3-numpy python3-pytest pybind11-dev python3-pybind11 slurm-wlm munge)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
