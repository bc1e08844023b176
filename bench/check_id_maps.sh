#!/usr/bin/env bash
# Checks that every traversal over every tree gives the id map of brute force
# (traversal none), byte for byte (ids and hit distances), on the five scenes
# at their full 500x500, on one device.
# Usage: bench/check_id_maps.sh [KDRT_RENDER] [DEVICE]   (default: build/apps/kdrt-render/kdrt-render cpu)
set -euo pipefail
cd "$(dirname "$0")/.."
render=${1:-build/apps/kdrt-render/kdrt-render}
device=${2:-cpu}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
for scene in 2x2x4 insane purple-wall lens ball-o-calypse; do
  "$render" "scenes/$scene.json" --device "$device" --traversal none --max-depth 1 -q --aov-ids "$work/$scene-none.ids"
  for tree in median sah; do
    for traversal in restart ropes stack; do
      "$render" "scenes/$scene.json" --device "$device" --traversal "$traversal" --tree "$tree" --max-depth 1 -q \
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
