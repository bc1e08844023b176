#!/usr/bin/env bash
# Builds the libFuzzer targets (clang-15, ASan + UBSan: build preset "fuzz", in
# the asan preset's tree, on the library the sanitizer tests use) and
# runs each for a bounded time on a scratch copy of its seed corpus
# (tests/fuzz/corpus/<target>/, which stays unchanged; the model importer's
# targets also get the models of Debian's assimp-testmodels package of their
# formats, up to 128 KiB each, when it is installed). Exits non-zero when a
# target finds a crash, a sanitizer report, a timeout or an out-of-memory; the
# reproducer is left in build-asan/fuzz/findings/<target>/.
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET]   (default 20)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-20}

cmake --preset asan >/dev/null
cmake --build --preset fuzz -j "$(nproc)"

# The assimp-testmodels files of a model target's formats, as extra seeds.
add_package_seeds() {
  local corpus=$1 work=$2 models=/usr/share/assimp/models pattern
  case $corpus in
    model_gltf) pattern='.*\.\(gltf\|glb\)' ;;
    model_ply) pattern='.*\.ply' ;;
    model_fbx) pattern='.*\.fbx' ;;
    *) return 0 ;;
  esac
  [ -d "$models" ] || return 0
  find "$models" -iregex "$pattern" -size -128k -type f | while read -r f; do
    cp "$f" "$work/pkg-$(echo "${f#"$models"/}" | tr '/ ' '__')"
  done
}

# One target per core at a time: -max_total_time is wall-clock time, so each
# keeps its whole budget.
fuzz_one() {
  local target=$1 corpus=${1#fuzz_}
  local work=build-asan/fuzz/corpus/$corpus findings=build-asan/fuzz/findings/$1
  rm -rf "$work" "$findings"
  mkdir -p "$work" "$findings"
  cp tests/fuzz/corpus/"$corpus"/* "$work"/
  add_package_seeds "$corpus" "$work"
  # The model targets' import helper (built with ASan, so without its address-space limit) is
  # held to 2 GiB by ASan itself; Assimp's leaks on malformed files are not kdrt's.
  local lsan="" asan=detect_leaks=1:abort_on_error=1
  if [[ $corpus == model_* ]]; then
    lsan="suppressions=$PWD/tests/fuzz/lsan-assimp.supp"
    asan+=:hard_rss_limit_mb=2048
  fi
  ASAN_OPTIONS=$asan UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 LSAN_OPTIONS="$lsan" \
    ./build-asan/tests/fuzz/"$target" "$work" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
    -artifact_prefix="$findings"/ -print_final_stats=1 >"$findings/log.txt" 2>&1
}

targets=(fuzz_scene_json fuzz_obj fuzz_tree_file fuzz_bvh_file fuzz_scene_wire fuzz_model_gltf fuzz_model_ply fuzz_model_fbx)
at_once=$(nproc)
status=0
for ((first = 0; first < ${#targets[@]}; first += at_once)); do
  batch=("${targets[@]:first:at_once}")
  pids=()
  for target in "${batch[@]}"; do
    echo "== fuzzing $target for ${seconds} s"
    fuzz_one "$target" &
    pids+=($!)
  done
  for i in "${!batch[@]}"; do
    target=${batch[i]}
    findings=build-asan/fuzz/findings/$target
    if ! wait "${pids[i]}"; then
      echo "!! $target found a problem: $(ls "$findings" | grep -v log.txt | tr '\n' ' ')"
      tail -n 40 "$findings/log.txt"
      status=1
    fi
    echo "$target: $(grep -E "^stat::number_of_executed_units|^stat::new_units_added" "$findings/log.txt" | tr '\n' ' ')"
  done
done
exit $status
