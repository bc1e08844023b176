#!/usr/bin/env bash
# Several devices against one (kdrt-render --stats-json, the frame's render_ms:
# no tree build, kernel compile or image write): the cpu alone, OpenCL alone,
# and cpu+opencl with several tile sizes, interleaved round by round so that
# load from other processes hits every configuration alike; medians.
# Usage: scripts/bench_tiles.sh [SCENE [WIDTHxHEIGHT [ROUNDS [TILES...]]]]
#   e.g. scripts/bench_tiles.sh scenes/ball-o-calypse.json 800x600 5 16 32 64 128
set -eu
scene=${1:-scenes/ball-o-calypse.json}
size=${2:-800x600}
rounds=${3:-5}
shift $(( $# < 3 ? $# : 3 ))
tiles=("$@")
[ ${#tiles[@]} -gt 0 ] || tiles=(16 32 64 128)
render=${KDRT_RENDER:-build/apps/kdrt-render/kdrt-render}
width=${size%x*} height=${size#*x}

configs=("cpu" "opencl")
for t in "${tiles[@]}"; do configs+=("cpu,opencl@$t"); done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

for ((r = 0; r < rounds; ++r)); do
    for c in "${configs[@]}"; do
        device=${c%@*} args=()
        [ "$c" = "$device" ] || args=(--tile "${c#*@}")
        "$render" "$scene" --width "$width" --height "$height" --device "$device" "${args[@]}" --stats-json \
            >"$tmp/$c.$r.json"
    done
done

printf '%-18s %10s %10s  %s\n' config median_ms min_ms "opencl share of the pixels (median run)"
for c in "${configs[@]}"; do
    python3 - "$tmp" "$c" "$rounds" <<'PY'
import json, statistics, sys
tmp, c, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
runs = [json.load(open(f"{tmp}/{c}.{r}.json")) for r in range(rounds)]
ms = [j["render_ms"] for j in runs]
med = statistics.median(ms)
share = ""
shares = [j.get("device_shares") for j in runs]
if shares[0]:
    total = sum(s["pixels"] for s in shares[0])
    fr = sorted(sum(s["pixels"] for s in sh if s["device"].startswith("opencl")) / total for sh in shares)
    share = f"{100 * fr[len(fr) // 2]:.0f}%"
print(f"{c:<18} {med:10.1f} {min(ms):10.1f}  {share}")
PY
done
