#!/usr/bin/env bash
# Packs kdrt-render, kdrt-bench, kdrt_tests and the import helper with the
# shared libraries they need beyond glibc and libstdc++ (ldd), for a machine
# that has a GPU driver but not kdrt's build dependencies. There:
#   mkdir -p /tmp/kdrt && tar xJf kdrt-binaries.tar.xz -C /tmp/kdrt
#   export LD_LIBRARY_PATH=/tmp/kdrt/lib       # kdrt's libexec/ is found beside bin/; Python then
#                                              # loads these libz and ICD loader too, which is harmless
#   echo /path/to/libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd   # if the ICD is not registered
#   bench/gpu_tables.sh --render /tmp/kdrt/bin/kdrt-render --bench /tmp/kdrt/bin/kdrt-bench
# With no .git there, set KDRT_COMMIT, KDRT_COMMIT_DATE (and KDRT_UNCOMMITTED=1 if the copy held
# changes) for the results' records. kdrt_tests reads scenes and test data from the build's source
# tree (absolute paths): run it from a checkout at that same path. The OpenImageIO plugin
# (libkdrt_oiio.so, loaded on demand) is not packed: pictures other than PNG, PPM and PFM need it.
#
# Usage: bench/pack_binaries.sh [BUILD_DIR] [OUT]   (defaults: build, kdrt-binaries.tar.xz)
set -euo pipefail
build=${1:-build} out=${2:-kdrt-binaries.tar.xz}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/bin" "$stage/lib" "$stage/libexec"
for p in apps/kdrt-render/kdrt-render bench/kdrt-bench; do
  cp "$build/$p" "$stage/bin/"  # gpu_tables.sh needs both: a build without them fails here
done
[ -x "$build/tests/kdrt_tests" ] && cp "$build/tests/kdrt_tests" "$stage/bin/"
cp "$build/libkdrt/kdrt-import" "$stage/libexec/"
# Every library the programs load, but the C and C++ runtimes, which the target's own must provide.
if ldd "$stage"/bin/* "$stage"/libexec/* | grep -q "not found"; then
  echo "pack_binaries: a library is missing here (ldd says 'not found')" >&2
  exit 1
fi
ldd "$stage"/bin/* "$stage"/libexec/* | awk '$3 ~ /^\// { print $3 }' | sort -u |
  grep -v -E '/(libc|libm|libstdc\+\+|libgcc_s|ld-linux[^/]*|libpthread|libdl|librt)\.so' |
  while read -r lib; do cp -L "$lib" "$stage/lib/"; done
strip "$stage"/bin/* "$stage"/libexec/*
tar cf - -C "$stage" bin lib libexec | xz -6 -T0 >"$out"
echo "pack_binaries: $out ($(du -h "$out" | cut -f1)): $(ls "$stage/bin" | tr '\n' ' ')" >&2
