#!/usr/bin/env bash
# kdrt-render under mpirun (a -DKDRT_MPI=ON build), on this machine with
# three ranks: usage  mpi_test.sh KDRT_RENDER SCENES_DIR WORK_DIR CASE
#   identical       the five scenes (PNG, PFM, id map) byte for byte as one process renders them
#   opencl          the same on OpenCL devices (lens)
#   warnings        every rank's warnings printed by rank 0, once each, named by rank
#   frames          --frames: one file per frame, each as one process renders it
#   killed_rank     kill -9 of rank 1 mid-render: non-zero exit within seconds, mpirun names
#                   rank 1 and its host, no output file
#   bad_scene       a scene rank 0 refuses: exit 1, the loader's message once, no hang
#   device_failure  a rank that cannot open its device: exit 1, rank 0 names it, no output
#   usage_error     an output rank 0 refuses as a usage error: every rank exits 2 (mpirun's status
#                   is the first failing rank's), the message once, no output
#   mixed_options   ranks given other picture options (mpirun's "a : b" form): exit 1 naming the rank
#                   and the option, no output (not a frame of mixed pictures); other devices are fine
#   terminated      SIGTERM, then SIGINT, to mpirun during --frames: non-zero exit, rank 0 says the
#                   frame in progress was not written, and no temporary of it is left beside it
#   command_line_agreement  a command line that fails on some ranks (a bad value, --version or --help on
#                   some only, rank 0 alone failing): every rank exits 2, the message once naming the
#                   rank, never a hang; --version on every rank: printed once, exit 0
#   frame_outputs   a symlink at frame 1's output: exit 2 before any frame is written
#   model_crash     a model that overflowed Assimp's stack, and an importer that crashes (a stand-in
#                   helper): exit 1 naming the file, once, every rank ended
set -u
render=$1 scenes=$2 work=$3 case=$4
dir="$work/$case"
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1

fail() { echo "FAIL [$case]: $*"; for f in *.txt; do [ -e "$f" ] && { echo "--- $f:"; cat "$f"; }; done; exit 1; }

# Shared memory between the ranks (no single-copy mechanism, which containers
# often forbid), no binding (the ranks share the cores with everything else),
# more ranks than cores allowed, and root allowed where CI runs as root.
mpirun=(mpirun --oversubscribe --bind-to none --mca btl self,vader --mca btl_vader_single_copy_mechanism none
        --mca mpi_yield_when_idle 1)
[ "$(id -u)" = 0 ] && mpirun+=(--allow-run-as-root)
run_mpi() { timeout 120 "${mpirun[@]}" "$@"; }

same() { cmp -s "$1" "$2" || fail "$2 differs from $1"; }

case $case in
identical)
    for s in 2x2x4 ball-o-calypse insane lens purple-wall; do
        args=("$scenes/$s.json" --width 83 --height 61 -q)
        "$render" "${args[@]}" --threads 1 -o "one_$s.png" --aov-ids "one_$s.ids" >one.txt 2>&1 || fail "$s: one process failed"
        "$render" "${args[@]}" --threads 1 -o "one_$s.pfm" >one.txt 2>&1 || fail "$s: one process failed (pfm)"
        # Tiles of 16 x 16 (clipped at the edges) spread over the three ranks.
        run_mpi -np 3 "$render" "${args[@]}" --threads 1 --tile 16x16 -o "mpi_$s.png" --aov-ids "mpi_$s.ids" \
            >mpi.txt 2>&1 || fail "$s: mpirun failed"
        run_mpi -np 3 "$render" "${args[@]}" --threads 1 --tile 32x8 -o "mpi_$s.pfm" >mpi.txt 2>&1 ||
            fail "$s: mpirun failed (pfm)"
        same "one_$s.png" "mpi_$s.png"
        same "one_$s.ids" "mpi_$s.ids"
        same "one_$s.pfm" "mpi_$s.pfm"
    done
    # Every rank took tiles (the statistics list each rank's share): a render of a second or two in
    # 1400 tiles, long enough for every rank to have started.
    run_mpi -np 3 "$render" "$scenes/ball-o-calypse.json" --width 300 --height 300 --samples 2 --threads 1 --tile 8x8 --stats-json \
        >stats.txt 2>&1 || fail "mpirun --stats-json failed"
    for r in 0 1 2; do
        grep -Eq "\"device\":\"rank $r \([^)]*\): [^\"]*\",\"tiles\":[1-9]" stats.txt || fail "rank $r rendered no tile"
    done
    grep -q '"broadcast_bytes":[1-9]' stats.txt || fail "no broadcast reported"
    grep -q '"tree":"bvh"' stats.txt || fail "the cluster's frame does not report its BVH"
    ;;
opencl)
    args=("$scenes/lens.json" --width 70 --height 50 -q --device opencl)
    "$render" "${args[@]}" -o one.png --aov-ids one.ids >one.txt 2>&1 || fail "one process failed"
    run_mpi -np 3 "$render" "${args[@]}" --tile 16x16 -o mpi.png --aov-ids mpi.ids >mpi.txt 2>&1 || fail "mpirun failed"
    same one.png mpi.png
    same one.ids mpi.ids
    ;;
warnings)
    # Every rank's warnings reach rank 0's output, named, once per rank (not once per frame): here
    # each rank's OpenCL kernel cache is unusable. A rank's warnings travel with its tiles, so a rank
    # that rendered none (one that started late) has none printed. About a second and a half of work
    # in 2800 tiles: the workers take part.
    args=("$scenes/lens.json" --samples 2 -q --device opencl --kernel-cache /proc/kdrt-no-cache)
    # A small render first fills PoCL's own cache: a rank compiling from cold would start late.
    run_mpi -np 3 "$render" "${args[@]}" --width 16 --height 16 -o warm.png >warm.txt 2>&1 || fail "mpirun (warm-up) failed"
    run_mpi -np 3 "$render" "${args[@]}" --width 300 --height 300 --tile 8x8 --frames 2 -o mpi.png --stats-json \
        >stats.txt 2>mpi.txt ||
        fail "mpirun failed"
    workers=0
    for r in 0 1 2; do
        tiles=$(grep -o "\"device\":\"rank $r ([^\"]*\",\"tiles\":[0-9]*" stats.txt | sed 's/.*://' | sort -n | tail -1)
        n=$(grep -c "warning: rank $r ([^)]*): kernel cache /proc/kdrt-no-cache" mpi.txt)
        if [ "${tiles:-0}" -gt 0 ]; then
            [ "$n" = 1 ] || fail "rank $r rendered $tiles tiles, its warning was printed $n times"
            [ "$r" = 0 ] || workers=$((workers + 1))
        else
            [ "$n" = 0 ] || fail "rank $r rendered no tile, its warning was printed $n times"
        fi
    done
    [ "$workers" -gt 0 ] || fail "no worker rank rendered a tile"
    ;;
frames)
    args=("$scenes/2x2x4.json" --width 40 --height 30 -q --frames 5)
    "$render" "${args[@]}" -o one.png --aov-ids one.ids >one.txt 2>&1 || fail "one process failed"
    run_mpi -np 3 "$render" "${args[@]}" -o mpi.png --aov-ids mpi.ids >mpi.txt 2>&1 || fail "mpirun failed"
    for f in 0000 0001 0002 0003 0004; do
        same "one_$f.png" "mpi_$f.png"
        same "one_$f.ids" "mpi_$f.ids"
    done
    [ ! -e mpi.png ] && [ ! -e mpi_0005.png ] || fail "unexpected output names"
    # The orbit moves the camera: the frames differ.
    ! cmp -s one_0000.png one_0001.png || fail "frames 0 and 1 are the same picture"
    # Frames split in tiles give the same pictures too.
    run_mpi -np 3 "$render" "${args[@]}" --tile 16x16 -o tiled.png >mpi.txt 2>&1 || fail "mpirun --tile failed"
    same one_0003.png tiled_0003.png
    # Each frame's statistics report the scene's features, also for frames rank 0 rendered no
    # tile of (whole frames: with three ranks most are rendered by the others).
    "$render" "${args[@]}" --stats-json >one.json 2>one.txt || fail "one process --stats-json failed"
    run_mpi -np 3 "$render" "${args[@]}" --stats-json >mpi.json 2>mpi.txt || fail "mpirun --stats-json failed"
    expected=$(grep -o '"features":\[[^]]*\]' one.json | sort -u)
    [ "$expected" != '"features":[]' ] && [ "$(echo "$expected" | wc -l)" = 1 ] || fail "unexpected features: $expected"
    [ "$(grep -cF "$expected" mpi.json)" = 5 ] || fail "not every frame reports $expected: $(grep -o '"features":\[[^]]*\]' mpi.json)"
    ;;
killed_rank)
    # A render of many seconds; rank 1 is killed once it renders.
    "${mpirun[@]}" -np 3 "$render" "$scenes/ball-o-calypse.json" --width 2000 --height 2000 --samples 4 --threads 1 \
        --tile 32x32 -q -o out.png --aov-ids out.ids >mpi.txt 2>&1 &
    job=$!
    victim=""
    for _ in $(seq 100); do
        for p in $(pgrep -f "ball-o-calypse.json --width 2000"); do
            tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx OMPI_COMM_WORLD_RANK=1 && victim=$p
        done
        [ -n "$victim" ] && break
        sleep 0.1
    done
    [ -n "$victim" ] || { kill "$job"; fail "rank 1 never started"; }
    sleep 2
    kill -0 "$victim" 2>/dev/null || fail "rank 1 was gone before the kill: make the render longer"
    kill -9 "$victim"
    killed=$(date +%s%N)
    wait "$job"
    rc=$?
    took_ms=$(( ($(date +%s%N) - killed) / 1000000 ))
    [ "$rc" != 0 ] || fail "mpirun exited 0 after a rank was killed"
    [ "$took_ms" -lt 10000 ] || fail "the job took $took_ms ms to end after the kill"
    grep -Eq "rank 1 .*on node $(hostname)|rank 1 \($(hostname)\)" mpi.txt || fail "no message names rank 1 and its host"
    ls -a | grep -q "out\." && fail "an output file was left: $(ls -a)"
    echo "job ended $took_ms ms after the kill"
    ;;
bad_scene)
    printf '%s\n' '{"format": "kdrt-scene/1", "camera": {"position": [0,0,-5], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 40},' \
        ' "materials": {"m": {}}, "spheres": [{"center": [0,0,0], "radius": -1, "material": "m"}]}' >bad.json
    run_mpi -np 3 "$render" bad.json -o out.png >mpi.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "mpirun exited $rc, expected 1 (124: a hang)"
    [ "$(grep -c 'spheres\[0\]\.radius' mpi.txt)" = 1 ] || fail "the loader's message is not printed exactly once"
    run_mpi -np 3 "$render" no_such.json -o out.png >missing.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "a missing scene: mpirun exited $rc, expected 1"
    [ "$(grep -c 'no_such.json' missing.txt)" = 1 ] || fail "a missing scene is not reported once"
    [ ! -e out.png ] || fail "an output was written"
    # A tile whose pixels do not fit in one MPI message (2 GiB): refused before any render.
    run_mpi -np 3 "$render" "$scenes/lens.json" --width 16384 --height 16384 --tile 16384 -q -o out.png >big.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "a 16384x16384 tile: mpirun exited $rc, expected 1"
    [ "$(grep -c -- '--tile 16384x16384: .*more than an MPI message holds' big.txt)" = 1 ] ||
        fail "a 16384x16384 tile is not refused once by name"
    [ ! -e out.png ] || fail "an output was written"
    ;;
device_failure)
    run_mpi -np 2 "$render" "$scenes/lens.json" -q -o out.png : \
        -np 1 env KDRT_DEVICE=opencl:nosuch "$render" "$scenes/lens.json" -q -o out.png >mpi.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "mpirun exited $rc, expected 1"
    grep -q "rank 2 ($(hostname)): cannot open its device.*opencl:nosuch" mpi.txt || fail "rank 2's device failure is not named"
    [ ! -e out.png ] || fail "an output was written"
    # 'local-rank' where a device name is expected: the message says what was written, not only '0'.
    run_mpi -np 2 "$render" "$scenes/lens.json" -q -o out.png --device local-rank >local.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "--device local-rank: mpirun exited $rc, expected 1"
    grep -q "cannot open its device: --device local-rank (here 0): unknown device '0'" local.txt ||
        fail "--device local-rank: the message does not name the option as written"
    [ ! -e out.png ] || fail "an output was written"
    ;;
usage_error)
    # Each time: rank 0 alone checks the outputs, the others learn it at the broadcast and must
    # exit with rank 0's status, whichever of them ends first.
    for i in 1 2 3; do
        run_mpi -np 3 "$render" "$scenes/2x2x4.json" --width 8 --height 8 -q -o out.png --aov-ids nodir/out.ids \
            >mpi.txt 2>&1
        rc=$?
        [ "$rc" = 2 ] || fail "run $i: mpirun exited $rc, expected 2 (a usage error)"
        [ "$(grep -c 'aov-ids nodir/out.ids' mpi.txt)" = 1 ] || fail "run $i: the message is not printed exactly once"
    done
    [ ! -e out.png ] || fail "an output was written"
    ;;
mixed_options)
    args=("$scenes/lens.json" --width 40 --height 30 -q)
    run_mpi -np 1 "$render" "${args[@]}" --tile 8x8 -o out.png : -np 2 "$render" "${args[@]}" --tile 8x8 --samples 3 \
        -o out.png >mpi.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "mpirun exited $rc, expected 1"
    grep -q "rank [12] ($(hostname)): its command line renders another picture than rank 0's: --samples 3" mpi.txt ||
        fail "the differing option is not named"
    [ ! -e out.png ] || fail "an output was written"
    # Other speed options on some ranks (devices of one kind): the same picture as one process.
    "$render" "${args[@]}" -o one.png >one.txt 2>&1 || fail "one process failed"
    run_mpi -np 1 "$render" "${args[@]}" --tile 8x8 --threads 1 -o mpi.png : -np 2 "$render" "${args[@]}" --tile 8x8 \
        --threads 2 --local-size 32 --schedule plain -o mpi.png >mpi.txt 2>&1 || fail "mpirun with other speed options failed"
    same one.png mpi.png
    ;;
terminated)
    # Frames of 12 MB each are written back to back: the signal lands while one is being
    # written (a temporary beside its target) most of the time. mpirun sends SIGTERM to the ranks
    # odls_base_sigkill_timeout (1 s) after the signal and SIGKILL as long after that: a rank inside
    # the fsync of a frame (not interruptible) on this loaded machine could get the SIGKILL before
    # its handler ran. 5 s: the job ends about 10 s after the signal.
    for sig in TERM INT; do
        "${mpirun[@]}" --mca odls_base_sigkill_timeout 5 -np 3 "$render" "$scenes/2x2x4.json" --width 1000 --height 1000 --max-depth 1 --threads 1 \
            --frames 500 -q -o out.pfm --aov-ids out.ids >mpi.txt 2>&1 &
        job=$!
        written() { ls out_*.pfm 2>/dev/null | wc -l; }
        for _ in $(seq 300); do [ "$(written)" -ge 3 ] && break; sleep 0.1; done
        [ "$(written)" -ge 3 ] || { kill "$job"; wait "$job"; fail "$sig: no frame written"; }
        kill -"$sig" "$job"
        wait "$job"
        rc=$?
        [ "$rc" != 0 ] || fail "$sig: mpirun exited 0"
        [ ! -e out_0499.pfm ] || fail "$sig: the render ended before the signal: make it longer"
        grep -q "rank 0: ended by mpirun.*frame in progress was not written" mpi.txt || fail "$sig: rank 0 did not say so"
        left=$(ls -A | grep '\.tmp-')
        [ -z "$left" ] || fail "$sig: temporaries left: $left"
        rm -f out_*
    done
    ;;
command_line_agreement)
    args=("$scenes/lens.json" --width 16 --height 16 -q -o out.png)
    check() {  # check WHAT EXPECTED_RC REGEX (run_mpi's output in mpi.txt)
        local rc=$2
        [ "$rc" = "$3" ] || fail "$1: mpirun exited $rc, expected $3 (124: a hang)"
        [ "$(grep -Ec -- "$4" mpi.txt)" = 1 ] || fail "$1: '$4' is not printed exactly once"
    }
    run_mpi -np 1 "$render" "${args[@]}" : -np 2 "$render" "${args[@]}" --width 99999 >mpi.txt 2>&1
    check "a bad value on ranks 1 and 2" $? 2 "rank 1 \($(hostname)\): --width: Value 99999 not in range"
    run_mpi -np 1 "$render" "${args[@]}" --width 99999 : -np 2 "$render" "${args[@]}" >mpi.txt 2>&1
    check "a bad value on rank 0 alone" $? 2 "^kdrt-render: --width: Value 99999 not in range"
    run_mpi -np 2 "$render" "${args[@]}" : -np 1 "$render" "${args[@]}" --tile 0x0 >mpi.txt 2>&1
    check "--tile 0x0 on rank 2" $? 2 "rank 2 \($(hostname)\): --tile 0x0: expected WxH"
    run_mpi -np 2 "$render" "${args[@]}" : -np 1 "$render" --version >mpi.txt 2>&1
    check "--version on rank 2" $? 2 "rank 2 \($(hostname)\): its command line asks for --help or --version, rank 0's for a render"
    run_mpi -np 1 "$render" --help : -np 2 "$render" "${args[@]}" >mpi.txt 2>&1
    check "--help on rank 0" $? 2 "rank 1 \($(hostname)\): its command line asks for a render, rank 0's for --help or --version"
    run_mpi -np 3 "$render" --version >mpi.txt 2>&1
    check "--version everywhere" $? 0 "^kdrt-render [0-9]+\.[0-9]+"
    [ ! -e out.png ] || fail "an output was written"
    ;;
frame_outputs)
    echo previous >real.png
    ln -s real.png out_0001.png
    run_mpi -np 3 "$render" "$scenes/2x2x4.json" --width 8 --height 8 -q --frames 2 -o out.png >mpi.txt 2>&1
    rc=$?
    [ "$rc" = 2 ] || fail "mpirun exited $rc, expected 2"
    [ "$(grep -c -- '--output out_0001.png: is a symbolic link' mpi.txt)" = 1 ] || fail "the link is not named once"
    [ ! -e out_0000.png ] || fail "frame 0 was written"
    ;;
model_crash)
    # 100,000 nested glTF nodes overflowed Assimp's stack on rank 0; a helper that crashes stands for
    # what no bound foresees.
    python3 - <<'PY'
import json
nodes = [{"children": [i + 1]} for i in range(99999)] + [{"mesh": 0}]
json.dump({"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3"}], "nodes": nodes,
           "scenes": [{"nodes": [0]}], "scene": 0}, open("deep.gltf", "w"))
PY
    run_mpi -np 3 "$render" deep.gltf -q -o out.png >mpi.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "nested nodes: mpirun exited $rc, expected 1"
    [ "$(grep -c 'deep.gltf: glTF node hierarchy deeper than 512 levels' mpi.txt)" = 1 ] || fail "not named once"
    printf '#!/bin/sh\nkill -SEGV $$\n' >crash-helper && chmod +x crash-helper
    cp "$scenes/../tests/data/models/room.obj" "$scenes/../tests/data/models/room.mtl" .
    run_mpi -np 3 -x KDRT_IMPORT_HELPER="$PWD/crash-helper" "$render" room.obj -q -o out.png >mpi.txt 2>&1
    rc=$?
    [ "$rc" = 1 ] || fail "a crashing importer: mpirun exited $rc, expected 1"
    [ "$(grep -c 'room.obj: the importer (Assimp) crashed on this file (SIGSEGV' mpi.txt)" = 1 ] || fail "not named once"
    [ ! -e out.png ] || fail "an output was written"
    ;;
*)
    fail "unknown case"
    ;;
esac
echo "PASS [$case]"
