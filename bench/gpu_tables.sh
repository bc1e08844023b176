#!/usr/bin/env bash
# BENCHMARKS.md's GPU section (e), on a machine with a GPU: the kd-tree against
# the BVH on the GPU beside kdrt's cpu device and Embree on that machine's
# cores (kdrt-bench rays), Whitted frames with each structure on each
# (bench/structures.py), and NVIDIA Warp's wp.Mesh on the same meshes and rays
# (bench/warp_rays.py). Results go to OUT, which write_benchmarks.py reads
# (bench/results-gpu, kept in the repository: most runs of run_all.sh have no GPU).
#
# Usage: bench/gpu_tables.sh --render KDRT_RENDER --bench KDRT_BENCH [--out DIR]
#                            [--device ID] [--export DIR] [--only kdrt|warp] [--quick]
#   --device ID    the OpenCL device measured (default: the first GPU kdrt-render lists)
#   --export DIR   where kdrt-bench rays writes the meshes and rays Warp reads (about 300 MB;
#                  default ${TMPDIR:-/tmp}/kdrt-gpu-export, outside the repository)
#   --only kdrt    the kdrt tables alone; --only warp: Warp alone, on an earlier --export
# Python: $PYTHON, else python3; warp-lang must import for the Warp step, which
# runs on $WARP_DEVICE (default cuda:0). bench/pack_binaries.sh carries the
# programs to a GPU machine without kdrt's build dependencies.
set -euo pipefail
cd "$(dirname "$0")/.."
render="" bench="" out=bench/results-gpu device="" export="" only="" quick=()
while (($#)); do
  case "$1" in
    --render) render=$2; shift ;;
    --bench) bench=$2; shift ;;
    --out) out=$2; shift ;;
    --device) device=$2; shift ;;
    --export) export=$2; shift ;;
    --only) only=$2; shift ;;
    --quick) quick=(--quick) ;;
    *) echo "usage: bench/gpu_tables.sh --render R --bench B [--out DIR] [--device ID] [--export DIR] [--only kdrt|warp] [--quick]" >&2
       exit 2 ;;
  esac
  shift
done
py=${PYTHON:-python3}
export=${export:-${TMPDIR:-/tmp}/kdrt-gpu-export}
mkdir -p "$out"
gpu=${device:-$("$render" --list-devices | awk -F'|' '$4 ~ /^ *gpu *$/ { split($1, id, " "); print id[1]; exit }')}
if [ -z "$gpu" ]; then
  echo "gpu_tables: kdrt-render --list-devices shows no GPU" >&2
  exit 1
fi
failed=()
step() { "$py" bench/benchlib.py step "$out" "$1" -- "${@:2}" || failed+=("$1"); }

if [ "$only" != warp ]; then
  # NOTES.md speaks of the run it sits beside: a new run starts without it.
  rm -rf "$out"/rays.json "$out"/structures.json "$out"/NOTES.md
  rm -f "$export"/*.json "$export"/*.f32 "$export"/*.u32 "$export"/*.u8  # what --export writes, nothing else
  "$py" bench/benchlib.py machine "$out" "$render"
  if ((${#quick[@]})); then
    meshes=torus:10k,heightfield:101 files=""
  else
    meshes=torus:100k,torus:1M,heightfield:1001,layers:32
    files=$("$bench" generate heightfield:1001 "$out/meshes"),$("$bench" generate torus:100k "$out/meshes")
    files=$files,$("$bench" generate layers:32 "$out/meshes")
  fi
  step rays "$bench" rays "${quick[@]}" --devices "cpu,$gpu" --meshes "$meshes" --scenes-dir scenes --export "$export" --device-buffers \
    --out "$out"
  step structures "$py" bench/structures.py "${quick[@]}" --render "$render" --devices "cpu,$gpu" --rounds 3 \
    --meshes "$files" --out "$out"
  rm -rf "$out/meshes"
fi
if [ "$only" != kdrt ]; then
  rm -f "$out"/warp.json
  step warp "$py" bench/warp_rays.py --export "$export" --device "${WARP_DEVICE:-cuda:0}" --out "$out"
fi
echo "gpu_tables: results in $out${failed[*]:+; FAILED steps: ${failed[*]}}" >&2
((${#failed[@]} == 0))
