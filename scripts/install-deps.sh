#!/usr/bin/env bash
# Installs the Debian 12 packages kdrt needs, skipping what is already there.
# Usage: scripts/install-deps.sh [--full] [--bench]
#   (none)   what a release build, kdrt-render, the quick test tier and the Python
#            package (scripts/python-env.sh: a venv, the rest from PyPI) need
#   --full   also the full test tier's toolchain: clang-15 with libFuzzer and
#            llvm-15 (the sanitizers' symbolizer), Open MPI for the cluster build,
#            assimp-testmodels (seeds of the model importer's fuzzers, scripts/fuzz.sh)
#   --bench  also the benchmark peers and plots: Embree 3, POV-Ray, matplotlib
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  ocl-icd-opencl-dev opencl-c-headers opencl-clhpp-headers pocl-opencl-icd clinfo
  libglm-dev libopenimageio-dev openimageio-tools
  catch2 nlohmann-json3-dev libtbb-dev libxxhash-dev libcli11-dev
  libassimp-dev libpng-dev
  python3-venv python3-dev
)
for arg in "$@"; do
  case "$arg" in
    --full) packages+=(clang-15 libfuzzer-15-dev llvm-15 libopenmpi-dev openmpi-bin assimp-testmodels) ;;
    --bench) packages+=(libembree-dev povray python3-matplotlib) ;;
    *) echo "usage: scripts/install-deps.sh [--full] [--bench]" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: everything is installed"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
