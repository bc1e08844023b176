#!/bin/sh
# ctest driver: the cpu device's AVX2 copies (libkdrt/src/cpu/cpu_isa.h) keep
# their AVX2 code to themselves.
#
# check_cpu_isa_objects.sh OBJDUMP OBJECT...
#
# Of the objects, those compiled from a *_avx2.cpp are disassembled. Each
# function outside namespace isa_avx2 must be free of VEX-encoded (AVX)
# instructions: such a function is an inline one that other objects share,
# and the linker may keep this copy of it for every caller, also on a
# processor without AVX. And the isa_avx2 functions must use AVX (a copy that
# compiled without its target would pass the first check and gain nothing).
# "AVX code" is any VEX-encoded instruction, BMI1/BMI2's, popcnt, lzcnt and
# movbe: what GCC's target for the copy adds (Clang's adds popcnt of the
# three). Not tzcnt: baseline code has it too, as the rep bsf that GCC emits
# for a count of trailing zeros (a bsf where tzcnt is missing), which
# objdump shows as tzcnt; so a leaked BMI count of trailing zeros, which
# differs from bsf for 0, goes unseen.
set -eu
objdump=$1
shift
checked=0
for object in "$@"; do
    case "$object" in *_avx2.cpp.o | *_avx2.cpp.obj) ;; *) continue ;; esac
    checked=$((checked + 1))
    "$objdump" -d -C --no-show-raw-insn "$object" | awk -v object="$object" '
        /^[0-9a-f]+ </ { name = $0; next }
        /\t(v[a-z0-9]+|andn|bextr|blsi|blsr|bzhi|mulx|pdep|pext|rorx|sarx|shlx|shrx|popcnt|lzcnt|movbe)[ \t]/ {
            if (name ~ /isa_avx2::/) avx_inside++
            else if (!(name in leaked)) { leaked[name] = 1; print object ": AVX code outside isa_avx2: " name; bad++ }
        }
        END {
            if (avx_inside == 0) { print object ": no AVX code in isa_avx2"; bad++ }
            exit bad > 0
        }'
done
if [ "$checked" -eq 0 ]; then
    echo "no *_avx2.cpp object among the arguments" >&2
    exit 1
fi
echo "$checked AVX2 object(s) checked"
