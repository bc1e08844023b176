#!/usr/bin/env bash
# The Python environment: a virtual environment in build-python/venv (Debian's
# Python refuses pip install outside one) with numpy, pytest and the build
# tools, then the kdrt package itself (pip install .: CMake builds libkdrt and
# the module). Needs the library's dependencies (scripts/install-deps.sh) and
# python3-venv, python3-dev.
#
#   scripts/python-env.sh          the package and its test tools
#   scripts/python-env.sh --deps   only the tools, for a CMake build with
#                                  -DKDRT_PYTHON=ON (what scripts/test.sh does)
#   scripts/python-env.sh --bench  also Open3D, trimesh and embreex for
#                                  bench/python_raycasting.py
set -euo pipefail
cd "$(dirname "$0")/.."
venv=build-python/venv
mode=${1:-}
case "$mode" in "" | --deps | --bench) ;; *) echo "usage: scripts/python-env.sh [--deps|--bench]" >&2; exit 2 ;; esac

if [[ ! -x $venv/bin/python ]]; then
  /usr/bin/python3 -m venv "$venv"
fi
pip=("$venv/bin/python" -m pip install --quiet --disable-pip-version-check)
"${pip[@]}" numpy pytest nanobind scikit-build-core
if [[ $mode == --bench ]]; then
  "${pip[@]}" open3d-cpu trimesh embreex
fi
if [[ $mode != --deps ]]; then
  # The build tools are already here: no isolated build environment to download.
  "${pip[@]}" --no-build-isolation .
fi
echo "python-env: $venv ($("$venv/bin/python" --version))"
