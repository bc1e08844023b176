#!/usr/bin/env bash
# kdrt-render's outputs under attack: links and special files at an output
# path, outputs that are inputs or each other, full disks (a file-size limit
# with SIGXFSZ ignored: write() fails with EFBIG part way, like ENOSPC),
# kill -9, bad numbers, hostile device names, unusable caches.
# Usage: cli_outputs_test.sh KDRT_RENDER SCENES_DIR WORK_DIR CASE
set -u
render=$1 scenes=$2 work=$3 case=$4
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
    "$render" "${small[@]}" --save-tree t.kdtree >out.txt 2>&1 || fail "cannot save a tree"
    expect 0 '"tree":"file","tree_file":"t.kdtree","tree_loaded":true' -- "${small[@]}" --load-tree t.kdtree --tree median --stats-json
    expect 0 '"tree":"median","tree_file":null' -- "${small[@]}" --tree median --stats-json
    # --traversal none still loads and checks the tree it is given.
    printf 'KDRTTREE not a tree' >bad.kdtree
    expect 1 "bad.kdtree" -- "${small[@]}" --traversal none --load-tree bad.kdtree -o a.png
    expect 0 '"traversal":"none".*"tree":"file".*"tree_loaded":true' -- "${small[@]}" --traversal none --load-tree t.kdtree --stats-json
    ;;
device_name_escaped)
    KDRT_DEVICE=$'opencl:\e[2J\nfake' "$render" "${small[@]}" -o a.png >out.txt 2>&1
    [ $? = 1 ] || fail "a bad KDRT_DEVICE did not fail"
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
*)
    echo "unknown case $case"; exit 1 ;;
esac
echo "ok: $case"
