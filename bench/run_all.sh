#!/usr/bin/env bash
# The one command behind BENCHMARKS.md. Builds kdrt-render and kdrt-bench from
# this checkout (Release, in build-bench/; kdrt-render with MPI in
# build-bench-mpi/ when Open MPI is installed), runs every measurement into
# bench/results/ (one step per line below, each logged with the machine's load
# in steps.jsonl), then writes BENCHMARKS.md from those results alone. A step
# that fails is reported at the end; its section of BENCHMARKS.md says so.
#
# Usage: bench/run_all.sh [--quick] [--build DIR] [--mpi-build DIR] [--out DIR]
#   --quick          tiny sizes, one run each: a smoke test of the whole pipeline, which
#                    writes OUT/BENCHMARKS.md (OUT: BUILD/results-quick), not ./BENCHMARKS.md
#   --build DIR      take kdrt-render and kdrt-bench from this build instead of building
#   --mpi-build DIR  take the cluster's kdrt-render (-DKDRT_MPI=ON) from this build
#   --out DIR        where the results go (default: bench/results)
# Python: $PYTHON, else Debian's /usr/bin/python3 (python3-matplotlib draws the plots).
set -euo pipefail
cd "$(dirname "$0")/.."
quick=() build="" mpi_build="" out=""
while (($#)); do
  case "$1" in
    --quick) quick=(--quick) ;;
    --build) build=$2; shift ;;
    --mpi-build) mpi_build=$2; shift ;;
    --out) out=$2; shift ;;
    *) echo "usage: bench/run_all.sh [--quick] [--build DIR] [--mpi-build DIR] [--out DIR]" >&2; exit 2 ;;
  esac
  shift
done
py=${PYTHON:-$([ -x /usr/bin/python3 ] && echo /usr/bin/python3 || echo python3)}

if [ -z "$build" ]; then
  build=build-bench
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKDRT_BUILD_TESTS=OFF >/dev/null
  cmake --build "$build" --target kdrt-render kdrt-bench
  if [ -z "$mpi_build" ] && command -v mpicxx >/dev/null; then
    mpi_build=build-bench-mpi
    cmake -S . -B "$mpi_build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DKDRT_BUILD_TESTS=OFF -DKDRT_BUILD_BENCH=OFF \
      -DKDRT_MPI=ON >/dev/null
    cmake --build "$mpi_build" --target kdrt-render
  fi
fi
render=$build/apps/kdrt-render/kdrt-render bench=$build/bench/kdrt-bench
if ((${#quick[@]})); then
  out=${out:-$build/results-quick} doc=$out/BENCHMARKS.md mesh=heightfield:101 torus=torus:10k layers=layers:4
  mid_torus=torus:20k big_torus=torus:10k
else
  out=${out:-bench/results} doc=BENCHMARKS.md mesh=heightfield:1001 torus=torus:100k layers=layers:32
  mid_torus=torus:1M  # Whitted frames, kd-tree against BVH (section d)
  big_torus=torus:4M  # the whole process's memory on a big mesh (section a)
fi
mkdir -p "$out"
rm -rf "$out"/*.json "$out"/steps.jsonl "$out"/*.png "$out"/gpu
"$py" bench/benchlib.py machine "$out" "$render"
hf=$("$bench" generate "$mesh" "$build/meshes")  # the 2M-triangle heightfield as OBJ and scene file
big=$("$bench" generate "$big_torus" "$build/meshes")
structure_meshes=$hf,$("$bench" generate "$torus" "$build/meshes"),$("$bench" generate "$mid_torus" "$build/meshes")
structure_meshes+=,$("$bench" generate "$layers" "$build/meshes")
gpu=$("$render" --list-devices | awk -F'|' '$4 ~ /^ *gpu *$/ { split($1, id, " "); print id[1]; exit }')

failed=()
step() { "$py" bench/benchlib.py step "$out" "$1" -- "${@:2}" || failed+=("$1"); }
step table "$bench" table "${quick[@]}" --out "$out"
step rays "$bench" rays "${quick[@]}" --out "$out"
step build "$bench" build "${quick[@]}" --out "$out"
step frames "$bench" frames "${quick[@]}" --out "$out"
step structures "$py" bench/structures.py "${quick[@]}" --render "$render" --meshes "$structure_meshes" --out "$out"
step processes "$py" bench/processes.py "${quick[@]}" --render "$render" --bench "$bench" --meshes "$hf,$big" --out "$out"
step accuracy "$py" bench/accuracy.py "${quick[@]}" --render "$render" --out "$out"
step devices "$py" bench/devices.py "${quick[@]}" --render "$render" --out "$out"
if [ -n "$mpi_build" ]; then
  step cluster "$py" bench/cluster.py "${quick[@]}" --render "$mpi_build/apps/kdrt-render/kdrt-render" --out "$out"
else
  echo "run_all: no kdrt-render with MPI (Open MPI not installed, or --build without --mpi-build): no cluster" >&2
fi
# Python: kdrt.RaycastingScene against Open3D and trimesh, with the module
# built into $build when scripts/python-env.sh --bench has made the venv.
venv=build-python/venv/bin/python
if [ -x "$venv" ] && "$venv" -c "import open3d, trimesh, embreex, nanobind" 2>/dev/null; then
  cmake -S . -B "$build" -DKDRT_PYTHON=ON -DPython_EXECUTABLE="$PWD/$venv" >/dev/null
  cmake --build "$build" --target _kdrt
  step python env PYTHONPATH="$build/python" "$venv" bench/python_raycasting.py "${quick[@]}" --out "$out"
else
  echo "run_all: no Python step (scripts/python-env.sh --bench makes its environment)" >&2
fi
if [ -n "$gpu" ]; then
  step gpu "$py" bench/opencl_device_tables.py --render "$render" --device "$gpu" --meshes "$hf" --out "$out/gpu"
  # kd-tree against BVH on the GPU, and Warp (when warp-lang imports): into bench/results-gpu, kept
  # in the repository for the runs without a GPU.
  ((${#quick[@]})) || step gpu-tables bench/gpu_tables.sh --render "$render" --bench "$bench" --device "$gpu"
fi

"$py" bench/write_benchmarks.py "$out" >"$doc"
echo "run_all: wrote $doc from $out${failed[*]:+; FAILED steps: ${failed[*]}}" >&2
((${#failed[@]} == 0))
