#!/usr/bin/env bash
# The test tiers (README.md).
#
# scripts/test.sh quick: the edit-test loop. An incremental release build of
# the library, kdrt-render and the tests, then every test labelled `quick`
# (ctest --preset quick): the ones that take seconds, a few minutes in all
# on two cores. Tests tagged [slow] and the install, MPI, SPIR and bench tests
# are left to the full tier.
#
# scripts/test.sh: the full tier, for CI and releases. The robustness tests
# under AddressSanitizer and UndefinedBehaviorSanitizer (kdrt_asan_tests),
# the libFuzzer targets (scripts/fuzz.sh, on the same library), the kd-tree builder and the API's
# concurrent calls under ThreadSanitizer (kdrt_tsan_tests), then every test
# in a release build through CTest, the cluster build's tests under mpirun
# and the Python package's pytest suite included. Needs the full toolchain: scripts/install-deps.sh --full.
#
# Exits non-zero when any test fails.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
# PoCL is installed by scripts/install-deps.sh: the OpenCL tests must run, not skip.
export KDRT_REQUIRE_OPENCL=1

if [[ "${1:-}" == "quick" ]]; then
  cmake --preset release >/dev/null
  cmake --build --preset quick -j "$jobs"
  # A build configured with the Python package (the full tier's) rebuilds
  # its module too: the quick tier runs the pytest suite on it.
  if grep -q "^KDRT_PYTHON:BOOL=ON" build/CMakeCache.txt; then
    cmake --build --preset release --target _kdrt _kdrt_stub -j "$jobs"
  fi
  echo "== quick tier (ctest -L quick)"
  exec ctest --preset quick
elif [[ $# -gt 0 ]]; then
  echo "usage: scripts/test.sh [quick]" >&2
  exit 2
fi

# The sanitizers' suppressions (tests/*.supp) match function names: without
# clang-15's symbolizer TSan reports TBB's known false positives as races.
command -v llvm-symbolizer-15 >/dev/null || {
  echo "test.sh: llvm-symbolizer-15 is missing (package llvm-15; scripts/install-deps.sh --full installs it)" >&2
  exit 1
}

cmake --preset asan >/dev/null
cmake --build --preset asan -j "$jobs"
echo "== sanitizer run (ASan + UBSan; clang-15), ${SECONDS} s in"
asan_run() {
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp" ./build-asan/tests/kdrt_asan_tests "$@" --order rand --rng-seed 1 --warn NoTests
}
# LeakSanitizer's own stop-the-world tracer can crash as the process exits,
# after every test passed ("Tracer caught signal 11"; google/sanitizers#1353):
# such a run is repeated once, leak check included. A failed test or a leak
# report fails at once. $1: the run's log.
asan_tests() {
  local log=$1
  shift
  local attempt
  for attempt in 1 2; do
    if asan_run "$@" >"$log" 2>&1; then
      return 0
    fi
    if ((attempt == 1)) && grep -q "^All tests passed" "$log" && grep -q "^Tracer caught signal" "$log" &&
      grep -q "LeakSanitizer has encountered a fatal error" "$log"; then
      echo "test.sh: LeakSanitizer's tracer crashed after every test passed ($*); running again" >&2
      continue
    fi
    return 1
  done
}
# Two processes side by side: the traversal tests take about as long as all
# the others (the sets are disjoint).
asan_tests build-asan/traversal-tests.log "[traversal]" &
traversal_tests=$!
trap 'kill "$traversal_tests" 2>/dev/null || true' EXIT  # an interrupted script does not leave it running
asan_status=0
asan_tests build-asan/other-tests.log "[kdtree],[bvh]~[traversal],[io],[packets],[scene],[intersect],[camera],[import],[api],[enum]" ||
  asan_status=1
cat build-asan/other-tests.log
wait "$traversal_tests" || asan_status=1
trap - EXIT
cat build-asan/traversal-tests.log
if ((asan_status != 0)); then
  echo "test.sh: the sanitizer run failed" >&2
  exit 1
fi

echo "== fuzzing (libFuzzer, ASan + UBSan), ${SECONDS} s in"
scripts/fuzz.sh 15  # eight targets: 60 s on two cores

echo "== ThreadSanitizer build and run (the parallel kd-tree builder's tests and the API's concurrent calls; clang-15), ${SECONDS} s in"
cmake --preset tsan >/dev/null
cmake --build --preset tsan -j "$jobs"
TSAN_OPTIONS="halt_on_error=1:suppressions=$PWD/tests/tsan.supp" ./build-tsan/tests/kdrt_tsan_tests "[kdtree],[parallel]"

# The release build includes the cluster mode (-DKDRT_MPI=ON): its tests run
# kdrt-render under mpirun with three ranks (label mpi); and the Python
# package (-DKDRT_PYTHON=ON, in build/python), whose pytest suite runs on the
# cpu device and PoCL (label python), with the tools of scripts/python-env.sh.
scripts/python-env.sh --deps
cmake --preset release -DKDRT_MPI=ON -DKDRT_PYTHON=ON -DPython_EXECUTABLE="$PWD/build-python/venv/bin/python" >/dev/null
cmake --build --preset release -j "$jobs"
echo "== release run (all tests, the mpi ones included), ${SECONDS} s in"
ctest --preset release
echo "test.sh: the full tier passed in ${SECONDS} s"
