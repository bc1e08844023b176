#!/usr/bin/env bash
# Render time of two kdrt-render binaries on the five study scenes, on the cpu
# device and PoCL, run in turn (A B B A A B ...) so both see the same load; prints
# a Markdown row per scene and device with the medians of render_ms.
# Usage: [AB_DEVICES="cpu"] [AB_SCENES="lens ..."] [AB_OLD_ENV="VAR=value ..."] [AB_NEW_ENV=...] \
#        [AB_ARGS="--accel kd"] bench/ab_render.sh OLD_KDRT_RENDER NEW_KDRT_RENDER [ROUNDS=5]
# AB_OLD_ENV and AB_NEW_ENV: environment for each side, e.g. one binary twice
# with AB_OLD_ENV=KDRT_CPU_ISA=baseline (the cpu device's SSE2 copy). AB_ARGS:
# kdrt-render options for both, e.g. --accel to name the structure when one
# binary is older than the BVH default.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1 new=$2 rounds=${3:-5}
render_ms() { env $4 "$1" "scenes/$2.json" --device "$3" ${AB_ARGS:-} --stats-json -o "/tmp/kdrt-ab-$$.png" 2>/dev/null |
  tail -n 1 | python3 -c "import json, sys; print(json.load(sys.stdin)['render_ms'])"; }
for dev in ${AB_DEVICES:-cpu opencl}; do
  for s in ${AB_SCENES:-2x2x4 insane purple-wall lens ball-o-calypse}; do
    a=() b=()
    for r in $(seq "$rounds"); do
      # A B, then B A: each side takes each place equally often, so that an
      # effect of the order cannot pass for one of the binaries.
      if (( r % 2 )); then
        a+=("$(render_ms "$old" "$s" "$dev" "${AB_OLD_ENV:-}")")
        b+=("$(render_ms "$new" "$s" "$dev" "${AB_NEW_ENV:-}")")
      else
        b+=("$(render_ms "$new" "$s" "$dev" "${AB_NEW_ENV:-}")")
        a+=("$(render_ms "$old" "$s" "$dev" "${AB_OLD_ENV:-}")")
      fi
    done
    python3 - "$s" "$dev" "${a[*]}" "${b[*]}" <<'PY'
import statistics, sys
scene, dev, a, b = sys.argv[1:]
a, b = statistics.median(map(float, a.split())), statistics.median(map(float, b.split()))
print(f"| {scene} | {dev} | {a:.1f} | {b:.1f} | {b / a:.2f} |")
PY
  done
done
rm -f "/tmp/kdrt-ab-$$.png"
