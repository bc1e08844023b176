#!/usr/bin/env bash
# Checks that every traversal over every tree gives the id map of brute force
# (traversal none), byte for byte (ids and hit distances), on the five scenes
# on one device, at their own 500x500 or SIZE x SIZE (the CTest test
# bench_id_maps runs it smaller, to fit the CI time).
# Usage: bench/check_id_maps.sh [KDRT_RENDER] [DEVICE] [SIZE]
#        (default: build/apps/kdrt-render/kdrt-render cpu, the scenes' size)
set -euo pipefail
cd "$(dirname "$0")/.."
render=$(realpath "${1:-build/apps/kdrt-render/kdrt-render}")
device=${2:-cpu}
size=()
if [ -n "${3:-}" ]; then size=(--width "$3" --height "$3"); fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
for scene in 2x2x4 insane purple-wall lens ball-o-calypse; do
  "$render" "scenes/$scene.json" --device "$device" "${size[@]}" --traversal none --max-depth 1 -q --aov-ids "$work/$scene-none.ids"
  for tree in median sah; do
    for traversal in restart ropes stack; do
      "$render" "scenes/$scene.json" --device "$device" --traversal "$traversal" --tree "$tree" "${size[@]}" --max-depth 1 -q \
        --aov-ids "$work/$scene-$tree-$traversal.ids"
      if cmp -s "$work/$scene-none.ids" "$work/$scene-$tree-$traversal.ids"; then
        echo "identical  $scene $tree $traversal"
      else
        echo "DIFFERENT  $scene $tree $traversal"
        status=1
      fi
    done
  done
done
exit $status
