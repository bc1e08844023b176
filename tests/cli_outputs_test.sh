#!/usr/bin/env bash
# kdrt-render's outputs under attack: links and special files at an output
# path (every frame's), outputs that are inputs or each other, full disks (a
# file-size limit with SIGXFSZ ignored: write() fails with EFBIG part way,
# like ENOSPC; and with the default SIGXFSZ), kill -9, SIGTERM and SIGHUP
# while a frame is written, SIGINT during an import, bad numbers, hostile
# and malformed device names, unusable caches (FIFOs in them too), the
# warnings of a scene's models.
# Usage: cli_outputs_test.sh KDRT_RENDER SCENES_DIR WORK_DIR CASE
set -u
render=$1 scenes=$2 work=$3 case=$4
models=$(cd "$(dirname "$0")" && pwd)/data/models
. "$(dirname "$0")/cli_test_common.sh"
same() { cmp -s "$1" "$2" || fail "$1 changed"; }
no_temporaries() {
    local left
    left=$(find . -name '.*.tmp-*' | head -1)
    [ -z "$left" ] || fail "temporary left behind: $left"
}

case $case in
symlink_output)
    echo previous >real.png && cp real.png real.orig
    ln -s real.png link.png
    expect 2 "link.png.*symbolic link" -- "${small[@]}" -o link.png
    [ -L link.png ] || fail "the link was replaced"
    same real.png real.orig
    ln -s /dev/full full.png
    expect 2 "full.png.*symbolic link" -- "${small[@]}" -o full.png
    ln -s real.png link.ids
    expect 2 "link.ids.*symbolic link" -- "${small[@]}" --aov-ids link.ids
    ;;
special_file_output)
    expect 2 "/dev/full.*not a regular file" -- "${small[@]}" -o /dev/full
    expect 2 "/dev/full.*not a regular file" -- "${small[@]}" --aov-ids /dev/full
    expect 2 "/dev/null.*not a regular file" -- "${small[@]}" --save-tree /dev/null
    expect 2 "/dev/full.*not a regular file" -- "${small[@]}" --save-tree /dev/full
    [ -c /dev/null ] && [ -c /dev/full ] || fail "a device node was replaced"
    mkfifo fifo.ppm
    expect 2 "fifo.ppm.*not a regular file" -- "${small[@]}" -o fifo.ppm
    mkdir dir.png
    expect 2 "dir.png.*directory" -- "${small[@]}" -o dir.png
    expect 2 "no_such_dir" -- "${small[@]}" -o no_such_dir/x.png
    ;;
output_is_input)
    cp scene.json scene.orig
    expect 2 "--aov-ids scene.json is the scene" -- "${small[@]}" --aov-ids scene.json
    expect 2 "--save-tree ./scene.json is the scene" -- "${small[@]}" --save-tree ./scene.json
    expect 2 "--output .*scene.json is the scene" -- "${small[@]}" -o "../$case/scene.json"
    same scene.json scene.orig
    "$render" "${small[@]}" --save-tree t.kdtree >out.txt 2>&1 || fail "cannot save a tree"
    cp t.kdtree t.orig
    expect 2 "--save-tree t.kdtree is --load-tree t.kdtree" -- "${small[@]}" --load-tree t.kdtree --save-tree t.kdtree
    same t.kdtree t.orig
    ;;
outputs_collide)
    expect 2 "--aov-ids a.png and --output a.png are the same file" -- "${small[@]}" -o a.png --aov-ids a.png
    expect 2 "--save-tree x.ppm and --output ./x.ppm are the same file" -- "${small[@]}" -o ./x.ppm --save-tree x.ppm
    [ ! -e a.png ] && [ ! -e x.ppm ] || fail "something was written"
    echo previous >b.png
    ln b.png c.png  # a hard link: the same file under two names
    expect 2 "are the same file" -- "${small[@]}" -o b.png --aov-ids c.png
    ;;
full_disk)
    # A limit of 2 KiB (ulimit -f counts KiB): every output below is larger, so every write fails part way.
    for ext in png hdr bmp ppm exr tif jpg sgi; do  # sgi: a writer without an I/O proxy
        echo previous >"img.$ext" && cp "img.$ext" prev.orig
        ( trap '' XFSZ; ulimit -f 2; exec "$render" scene.json --width 256 --height 256 -q -o "img.$ext" ) >out.txt 2>&1
        rc=$?
        [ $rc = 1 ] || fail "-o img.$ext on a full disk exited $rc, expected 1"
        grep -q "img.$ext" out.txt || fail "-o img.$ext: the message does not name the file"
        # The OS error, or for a writer that hides it (sgi), the failed read-back.
        grep -Eq "File too large|does not read back" out.txt || fail "-o img.$ext: the message gives no cause"
        same "img.$ext" prev.orig
    done
    echo previous >ids.bin && cp ids.bin prev.orig
    ( trap '' XFSZ; ulimit -f 2; exec "$render" scene.json --width 256 --height 256 -q --aov-ids ids.bin ) >out.txt 2>&1
    [ $? = 1 ] || fail "--aov-ids on a full disk did not fail"
    grep -q "ids.bin.*File too large" out.txt || fail "--aov-ids: no file or OS error in the message"
    same ids.bin prev.orig
    # The image fits, the id map does not: neither replaces its previous file.
    echo previous >img.png && echo previous >ids.bin && cp img.png prev.orig
    ( trap '' XFSZ; ulimit -f 2; exec "$render" scene.json --width 32 --height 32 -q -o img.png --aov-ids ids.bin ) >out.txt 2>&1
    [ $? = 1 ] || fail "-o with a failing --aov-ids did not fail"
    same img.png prev.orig
    same ids.bin prev.orig
    echo previous >t.kdtree && cp t.kdtree prev.orig
    ( trap '' XFSZ; ulimit -f 2; exec "$render" "$scenes/ball-o-calypse.json" -q --save-tree t.kdtree ) >out.txt 2>&1
    [ $? = 1 ] || fail "--save-tree on a full disk did not fail"
    grep -q "t.kdtree.*File too large" out.txt || fail "--save-tree: no file or OS error in the message"
    same t.kdtree prev.orig
    no_temporaries
    ;;
kill_during_render)
    "$render" "${small[@]}" -o out.png >out.txt 2>&1 || fail "first render failed"
    cp out.png out.orig
    "$render" scene.json --width 1500 --height 1500 --samples 16 -q -o out.png --aov-ids out.ids &
    pid=$!
    sleep 2
    kill -9 $pid 2>/dev/null
    wait $pid 2>/dev/null
    same out.png out.orig
    [ ! -e out.ids ] || fail "a partial id map was left"
    no_temporaries
    ;;
bad_numbers)
    expect 2 "--max-launch-ms.*finite" -- "${small[@]}" --max-launch-ms nan -o a.png
    expect 2 "--epsilon.*finite" -- "${small[@]}" --self-intersection fixed --epsilon nan -o a.png
    expect 2 "--epsilon.*finite" -- "${small[@]}" --self-intersection fixed --epsilon inf -o a.png
    expect 2 "--max-launch-ms" -- "${small[@]}" --max-launch-ms -inf -o a.png
    [ ! -e a.png ] || fail "rendered anyway"
    ;;
list_devices_alone)
    expect 2 "--list-devices.*renders nothing" -- --list-devices scene.json -o a.png
    expect 2 "--list-devices" -- --list-devices --stats-json
    [ ! -e a.png ] || fail "rendered anyway"
    ;;
loaded_tree_reported)
    "$render" "${small[@]}" --accel kd --save-tree t.kdtree >out.txt 2>&1 || fail "cannot save a tree"
    expect 0 '"tree":"file","tree_file":"t.kdtree","tree_loaded":true' -- "${small[@]}" --load-tree t.kdtree --tree median --stats-json
    expect 0 '"tree":"median","tree_file":null' -- "${small[@]}" --tree median --stats-json
    # --traversal none still loads and checks the tree it is given.
    printf 'KDRTTREE not a tree' >bad.kdtree
    expect 1 "bad.kdtree" -- "${small[@]}" --accel kd --traversal none --load-tree bad.kdtree -o a.png
    expect 0 '"traversal":"none".*"tree":"file".*"tree_loaded":true' -- "${small[@]}" --accel kd --traversal none --load-tree t.kdtree --stats-json
    ;;
device_name_escaped)
    KDRT_DEVICE=$'opencl:\e[2J\nfake' "$render" "${small[@]}" -o a.png >out.txt 2>&1
    [ $? = 2 ] || fail "a bad KDRT_DEVICE is not a usage error"
    grep -q $'\e' out.txt && fail "an escape character reached the terminal"
    grep -Fq 'opencl:\e[2J\nfake' out.txt || fail "the device name is not shown escaped"
    KDRT_DEVICE=$'cpu\e]0;title\a' "$render" "${small[@]}" -o a.png >out.txt 2>&1
    grep -q $'\e' out.txt && fail "an escape character reached the terminal"
    grep -Fq 'cpu\e]0;title\x07' out.txt || fail "the device name is not shown escaped"
    ;;
unusable_caches)
    # A path under a regular file can be neither created nor read, even by root.
    echo x >file
    expect 0 "warning: tree cache: .*file/cache.*(Not a directory|not a directory)" -- "${small[@]}" --tree-cache file/cache -o a.png
    [ -s a.png ] || fail "no image without a tree cache"
    rm -f a.png
    expect 0 "warning: kernel cache .*file/kernels.*Not a directory" -- "${small[@]}" --device opencl --kernel-cache file/kernels -o a.png
    [ -s a.png ] || fail "no image without a kernel cache"
    mkdir open && chmod 777 open
    expect 0 "warning: kernel cache .*open.*writable by other users" -- "${small[@]}" --device opencl --kernel-cache open -o b.png
    ;;
messages)
    sed 's/"samples": 1/"samples": 5000/' scene.json >many.json
    expect 1 "scene 'lens': settings.samples is 5000, at most 4096" -- many.json --width 8 --height 8 -o a.png
    expect 2 "--samples" -- "${small[@]}" --samples 5000 -o a.png
    cat >far.json <<'JSON'
{"format": "kdrt-scene/1", "camera": {"position": [0,0,-1e300], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 40},
 "materials": {"m": {}}, "spheres": [{"center": [0,0,0], "radius": 1, "material": "m"}]}
JSON
    expect 1 "camera.look_at.*1e\+300.*float range" -- far.json -o a.png
    grep -q "parallel" out.txt && fail "a far camera is diagnosed as a parallel up vector"
    cat >huge.json <<'JSON'
{"format": "kdrt-scene/1", "name": "huge", "camera": {"position": [0,0,-5], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 40},
 "materials": {"m": {}}, "spheres": [{"center": [0,0,0], "radius": 1e299, "material": "m"}]}
JSON
    expect 1 "scene 'huge': the objects span 2e\+299 units" -- huge.json -o a.png
    grep -Eq "[0-9]{40}" out.txt && fail "a number printed with all its digits"
    ;;
frame_outputs)
    # Every frame's outputs are checked before the first frame is rendered.
    cp scene.json scene.orig
    echo previous >real.png && cp real.png real.orig
    ln -s real.png out_0001.png
    expect 2 "--output out_0001.png: is a symbolic link" -- "${small[@]}" --frames 2 -o out.png
    [ ! -e out_0000.png ] || fail "frame 0 was written before frame 1's output was checked"
    [ -L out_0001.png ] || fail "the link was replaced"
    same real.png real.orig
    rm out_0001.png
    expect 2 "--save-tree out_0001.png and --output out_0001.png are the same file" -- \
        "${small[@]}" --frames 2 -o out.png --save-tree out_0001.png
    # The id map of frame 1 would be the scene itself.
    cp scene.json ids_0001.bin
    expect 2 "--aov-ids ids_0001.bin is the scene ids_0001.bin" -- ids_0001.bin --width 16 --height 16 -q --frames 2 \
        --aov-ids ids.bin
    same ids_0001.bin scene.orig
    # A hard link to the scene as frame 2's image, and two options naming the same frames.
    ln scene.json hard_0002.png
    expect 2 "--output hard_0002.png is the scene scene.json" -- "${small[@]}" --frames 3 -o hard.png
    same scene.json scene.orig
    expect 2 "--aov-ids x_0000.png and --output x_0000.png are the same file" -- "${small[@]}" --frames 2 -o x.png \
        --aov-ids x.png
    [ -z "$(ls out_0000.png ids_0000.bin hard_0000.png x_0000.png 2>/dev/null)" ] || fail "a frame was written"
    ;;
file_size_limit)
    # No trap for SIGXFSZ here: kdrt-render itself turns the limit into a failed write naming the file.
    for ext in png exr; do
        echo previous >"img.$ext" && cp "img.$ext" prev.orig
        ( ulimit -f 2; exec "$render" scene.json --width 256 --height 256 -q -o "img.$ext" --aov-ids ids.bin ) >out.txt 2>&1
        rc=$?
        [ $rc = 1 ] || fail "-o img.$ext under a file-size limit exited $rc, expected 1 (153: killed by SIGXFSZ)"
        grep -Eq "(img.$ext|ids.bin).*(File too large|does not read back)" out.txt || fail "the message names no file and cause"
        same "img.$ext" prev.orig
        no_temporaries
    done
    ;;
stop_signals)
    # SIGTERM and SIGHUP while a frame is being written (its temporary beside its target): the run
    # ends as after Ctrl-C, with 128 + the signal's number, that frame unwritten, no temporary left.
    for sig in TERM HUP; do
        "$render" scene.json --width 1000 --height 1000 --max-depth 1 --threads 1 --frames 500 -q -o out.pfm \
            --aov-ids out.ids >out.txt 2>&1 &
        pid=$!
        for _ in $(seq 600); do ls -a | grep -q '^\.out_.*\.tmp-' && break; sleep 0.02; done
        kill -"$sig" $pid
        wait $pid
        rc=$?
        want=$((128 + $(kill -l "$sig")))
        [ $rc = $want ] || fail "SIG$sig exited $rc, expected $want"
        grep -Eq "^kdrt-render: (terminated|hung up)$" out.txt || fail "SIG$sig: no message"
        [ ! -e out_0499.pfm ] || fail "the render ended before SIG$sig: make it longer"
        no_temporaries
        rm -f out_*
    done
    ;;
interrupt_import)
    # Ctrl-C while a model is imported stops the import helper and the run within a second.
    # The helper stands in for a long import (100,000 nodes sharing a mesh once took many minutes).
    printf '#!/bin/sh\nexec sleep 61.5\n' >slow-helper && chmod +x slow-helper
    python3 - <<'PY'
import json
n = 100000
nodes = [{"children": list(range(1, n + 1))}] + [{"mesh": 0, "translation": [i * 0.001, 0, 0]} for i in range(n)]
json.dump({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,"
           "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
           "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0],
                          "max": [1, 1, 0]}, {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}], "nodes": nodes,
           "scenes": [{"nodes": [0]}], "scene": 0}, open("instances.gltf", "w"))
PY
    set -m  # the job gets its own process group and a SIGINT that is not ignored
    KDRT_IMPORT_HELPER=$PWD/slow-helper "$render" instances.gltf --width 16 --height 16 -q -o out.png >out.txt 2>&1 &
    pid=$!
    set +m
    sleep 1
    kill -INT $pid
    start=$(date +%s%N)
    for _ in $(seq 100); do kill -0 $pid 2>/dev/null || break; sleep 0.05; done
    took_ms=$(( ($(date +%s%N) - start) / 1000000 ))
    kill -0 $pid 2>/dev/null && { kill -9 $pid; fail "still importing 5 s after SIGINT"; }
    wait $pid
    rc=$?
    [ $rc = 130 ] || fail "exited $rc after SIGINT during the import, expected 130"
    [ "$took_ms" -lt 2000 ] || fail "took $took_ms ms to stop"
    pgrep -f "sleep 61.5" >/dev/null && fail "the import helper was left running"
    [ ! -e out.png ] || fail "an output was written"
    ;;
device_values)
    expect 2 "--device ,: an empty device name" -- "${small[@]}" --device , -o a.png
    expect 2 "--device cpu,cpu names device cpu twice" -- "${small[@]}" --device cpu,cpu -o a.png
    expect 2 "opencl:999.*out of range" -- "${small[@]}" --device opencl:999 -o a.png
    expect 2 "--device opencl,opencl:0 names device opencl:0 twice" -- "${small[@]}" --device opencl,opencl:0 -o a.png
    [ ! -e a.png ] || fail "rendered anyway"
    # $KDRT_DEVICE is --device's default, lists and "all" included.
    KDRT_DEVICE=all expect 0 "" -- "${small[@]}" -o a.png
    [ -s a.png ] || fail "KDRT_DEVICE=all rendered nothing"
    KDRT_DEVICE=cpu,cpu expect 2 "names device cpu twice" -- "${small[@]}" -o b.png
    ;;
scene_model_warnings)
    # A model's warnings are printed also when a scene places it.
    printf 'mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n' >lonely.obj
    cat >placed.json <<'JSON'
{"format": "kdrt-scene/1", "camera": {"position": [0.3,0.3,3], "look_at": [0.3,0.3,0], "up": [0,1,0], "fov_y": 40},
 "lights": [{"position": [0,0,5], "color": [1,1,1]}], "meshes": [{"model": "lonely.obj"}]}
JSON
    expect 0 "warning: placed.json: meshes\[0\].model: .*lonely.obj: referenced files not found \(gone.mtl" -- \
        placed.json --width 8 --height 8 -q -o a.png
    ;;
fifo_caches)
    # A FIFO where a cache keeps a file is a warning, and the render goes on (124: it hung).
    mkdir -m 700 kernels
    mkfifo kernels/cache-secret
    timeout 120 "$render" "${small[@]}" --device opencl --kernel-cache kernels -o a.png >out.txt 2>&1
    rc=$?
    [ $rc = 0 ] || fail "a FIFO as the kernel cache's secret: exit $rc"
    grep -q "warning: kernel cache: .*cache-secret" out.txt || fail "no warning about the secret"
    rm kernels/cache-secret
    "$render" "${small[@]}" --device opencl --kernel-cache kernels -o b.png >out.txt 2>&1 || fail "cannot fill the cache"
    for entry in kernels/*.clbin; do mkfifo "$entry.loading"; done
    timeout 120 "$render" "${small[@]}" --device opencl --kernel-cache kernels -o c.png >out.txt 2>&1
    rc=$?
    [ $rc = 0 ] || fail "a FIFO as a loading marker: exit $rc"
    grep -q "warning: kernel cache: .*\.clbin\.loading is not a regular file" out.txt || fail "no warning about the marker"
    "$render" "${small[@]}" --tree-cache trees -o d.png >out.txt 2>&1 || fail "cannot fill the tree cache"
    for entry in trees/*.bvh trees/*.kdtree; do [ -e "$entry" ] && rm "$entry" && mkfifo "$entry"; done
    timeout 120 "$render" "${small[@]}" --tree-cache trees -o e.png >out.txt 2>&1
    rc=$?
    [ $rc = 0 ] || fail "a FIFO as a tree cache entry: exit $rc"
    grep -q "warning: tree cache: .*not a regular file" out.txt || fail "no warning about the tree cache"
    [ -s a.png ] && [ -s c.png ] && [ -s e.png ] || fail "an image is missing"
    ;;
model_crash)
    # 100,000 nested glTF nodes overflowed Assimp's stack (exit 139), rendered directly or placed by a scene;
    # a helper that crashes stands for what no bound foresees.
    python3 - <<'PY'
import json
nodes = [{"children": [i + 1]} for i in range(99999)] + [{"mesh": 0}]
json.dump({"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3"}], "nodes": nodes,
           "scenes": [{"nodes": [0]}], "scene": 0}, open("deep.gltf", "w"))
PY
    expect 1 "deep.gltf: glTF node hierarchy deeper than 512 levels" -- deep.gltf -q -o a.png
    cat >placed.json <<'JSON'
{"format": "kdrt-scene/1", "camera": {"position": [0,0,5], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 40},
 "meshes": [{"model": "deep.gltf"}]}
JSON
    expect 1 "placed.json: meshes\[0\].model: .*deep.gltf: glTF node hierarchy deeper" -- placed.json -q -o a.png
    printf '#!/bin/sh\nkill -SEGV $$\n' >crash-helper && chmod +x crash-helper
    cp "$models/room.obj" "$models/room.mtl" .
    KDRT_IMPORT_HELPER=$PWD/crash-helper expect 1 "room.obj: the importer \(Assimp\) crashed on this file \(SIGSEGV" -- \
        room.obj -q -o a.png
    [ ! -e a.png ] || fail "an output was written"
    ;;
*)
    echo "unknown case $case"; exit 1 ;;
esac
echo "ok: $case"
