#!/usr/bin/env bash
# Runs every measurement behind BENCHMARKS.md, one after the other, into one
# directory, logging the machine's load before and after each (the figures are
# only as good as the machine was quiet: 2 cores here, shared with builds).
# Usage: bench/run_all.sh [KDRT_BENCH_BINARY] [OUT_DIR]
set -euo pipefail
bench=${1:-build/bench/kdrt-bench}
out=${2:-bench/results}
mkdir -p "$out"
log="$out/run_all.log"
: > "$log"
run() {
  echo "== $(date -Iseconds) load $(cut -d' ' -f1-3 /proc/loadavg): kdrt-bench $*" | tee -a "$log"
  "$bench" "$@" --out "$out" 2>&1 | tee -a "$log" | grep -E "^kdrt-bench" | tail -1 || true
  echo "== $(date -Iseconds) load $(cut -d' ' -f1-3 /proc/loadavg): done" | tee -a "$log"
}
run table --runs 3
run embree --runs 5
run build
run rays --runs 3
run frames --runs 3
run schedules --runs 3
run startup --runs 3
run povray-compare --runs 3
