#!/usr/bin/env bash
# Installs the Debian 12 packages kdrt needs, skipping what is already there
# (Open MPI for the cluster build, -DKDRT_MPI=ON, which scripts/test.sh makes).
# Usage: scripts/install-deps.sh [--bench]   (--bench adds Embree, POV-Ray, tinyobjloader)
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  ocl-icd-opencl-dev opencl-c-headers opencl-clhpp-headers pocl-opencl-icd clinfo
  libglm-dev libopenimageio-dev openimageio-tools
  catch2 nlohmann-json3-dev libtbb-dev libxxhash-dev libcli11-dev
  libassimp-dev libpng-dev
  clang-15 libfuzzer-15-dev llvm-15  # llvm-15: the llvm-symbolizer-15 the sanitizers' suppressions need
  libopenmpi-dev openmpi-bin
  assimp-testmodels  # seeds of the model importer's fuzzers (scripts/fuzz.sh)
)
if [[ "${1:-}" == "--bench" ]]; then
  packages+=(libembree-dev povray libtinyobjloader-dev)
fi

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
