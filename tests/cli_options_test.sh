#!/usr/bin/env bash
# kdrt-render's start-up, image formats, progress, Ctrl-C and help.
# Usage: cli_options_test.sh KDRT_RENDER OIIO_PLUGIN SCENES_DIR WORK_DIR CASE
set -u
render=$1 plugin=$2 scenes=$3 work=$4 case=$5
. "$(dirname "$0")/cli_test_common.sh"
# loads LIB ARGS...: the dynamic loader reports loading a library matching LIB.
loaded() {
    local lib=$1; shift
    LD_DEBUG=libs "$render" "$@" >libs.txt 2>&1
    grep -q "calling init: .*$lib" libs.txt
}
no_temporaries() {
    local left
    left=$(find . -name '.*.tmp-*' | head -1)
    [ -z "$left" ] || fail "temporary left behind: $left"
}
# A scene slow enough to interrupt: many spheres, a big image, many samples.
slow_scene() {
    {
        echo '{"format": "kdrt-scene/1", "name": "slow", "camera": {"position": [0,0,-30], "look_at": [0,0,0], "up": [0,1,0], "fov_y": 50},'
        echo ' "settings": {"width": 1000, "height": 1000, "samples": 8, "max_depth": 8},'
        echo ' "materials": {"m": {"reflect": 0.5}}, "lights": [{"position": [5,5,-20], "color": [1,1,1]}], "spheres": ['
        local first=1
        for x in $(seq -10 10); do for y in $(seq -10 10); do
            [ $first = 1 ] || echo ','
            first=0
            echo "{\"center\": [$x,$y,0], \"radius\": 0.45, \"material\": \"m\"}"
        done; done
        echo ']}'
    }
}

case $case in
lazy_openimageio)
    # OpenImageIO (hundreds of libraries) is loaded only for the formats kdrt does not write itself.
    ldd "$render" | grep -q OpenImageIO && fail "kdrt-render links OpenImageIO"
    loaded OpenImageIO --version && fail "--version loads OpenImageIO"
    grep -q "kdrt-render [0-9]" libs.txt || fail "no version printed"
    for ext in png ppm pfm; do
        loaded OpenImageIO "${small[@]}" -o "a.$ext" && fail "-o a.$ext loads OpenImageIO"
        [ -s "a.$ext" ] || fail "a.$ext not written"
    done
    loaded OpenImageIO "${small[@]}" -o a.exr || fail "-o a.exr does not load OpenImageIO"
    [ -s a.exr ] || fail "a.exr not written"
    ;;
plugin_missing)
    # Without the plugin: a clear error for the formats that need it, the others still work.
    export KDRT_OIIO_PLUGIN=$dir/no/libkdrt_oiio.so
    echo previous >a.exr && cp a.exr a.orig
    expect 1 "a.exr: writing .exr images needs OpenImageIO: libkdrt_oiio.so .*not installed.*no/libkdrt_oiio.so" -- \
        "${small[@]}" -o a.exr
    cmp -s a.exr a.orig || fail "a.exr changed"
    expect 0 "" -- "${small[@]}" -o a.png
    [ -s a.png ] || fail "a.png not written without the plugin"
    echo "not a library" >fake.so
    KDRT_OIIO_PLUGIN=$dir/fake.so expect 1 "fake.so cannot be loaded" -- "${small[@]}" -o a.tif
    ;;
plugin_installed)
    # The installed layout, PREFIX/bin/kdrt-render and PREFIX/lib/libkdrt_oiio.so, outside the
    # build tree (a program inside it would use the build tree's plugin).
    prefix=$(mktemp -d /tmp/kdrt-cli-prefix.XXXXXX) || fail "no temporary directory"
    trap 'rm -rf "$prefix"' EXIT
    mkdir -p "$prefix/bin" "$prefix/lib"
    cp "$render" "$prefix/bin/" && cp "$plugin" "$prefix/lib/" || fail "cannot copy"
    render=$prefix/bin/kdrt-render
    loaded "$prefix/lib/libkdrt_oiio.so" "${small[@]}" -o a.exr || fail "the plugin beside the install was not used"
    [ -s a.exr ] || fail "a.exr not written"
    rm "$prefix/lib/libkdrt_oiio.so"
    expect 1 "libkdrt_oiio.so .*not installed.*$prefix/lib/libkdrt_oiio.so" -- "${small[@]}" -o b.exr
    ;;
progress)
    # Not a terminal: no progress unless --progress; --progress gives lines with an estimate.
    expect 0 "" -- scene.json --width 64 --height 64 -o a.png
    grep -q "progress" out.txt && fail "progress shown on a file without --progress"
    expect 0 "progress +[0-9]+%.*ETA" -- scene.json --width 64 --height 64 --progress -o a.png
    grep -q "progress 100%" out.txt || fail "no final 100% line"
    grep -q $'\r' out.txt && fail "carriage returns written to a file"
    expect 0 "" -- scene.json --width 64 --height 64 --no-progress -o a.png
    grep -q "progress" out.txt && fail "progress shown with --no-progress"
    expect 2 "excludes" -- "${small[@]}" --progress --no-progress -o a.png
    ;;
interrupt)
    # SIGINT during a render: exit 130, "interrupted", no output written, an existing output untouched.
    slow_scene >slow.json
    echo previous >old.png && cp old.png old.orig
    for target in new.png old.png; do
        # The last round's out.txt holds "progress" until the new job truncates it: a signal sent on
        # that stale line could reach kdrt-render before its handler is installed.
        rm -f out.txt
        set -m  # the job gets its own process group and a SIGINT that is not ignored
        "$render" slow.json --progress -o "$target" --aov-ids "$target.ids" >out.txt 2>&1 &
        pid=$!
        set +m
        for _ in $(seq 600); do grep -q "progress" out.txt && break; sleep 0.1; done
        grep -q "progress" out.txt || { kill -9 $pid; fail "no progress line within 60 s"; }
        kill -INT $pid
        wait $pid
        rc=$?
        [ $rc = 130 ] || fail "-o $target: exit $rc after SIGINT, expected 130"
        grep -q "kdrt-render: interrupted" out.txt || fail "no 'interrupted' message"
        [ ! -e "$target.ids" ] || fail "an id map was written"
        no_temporaries
    done
    [ ! -e new.png ] || fail "an image was written"
    cmp -s old.png old.orig || fail "the existing output changed"
    ;;
help)
    expect 0 "Exit codes:" -- --help
    for want in "130 +interrupted" "2 +usage error" "1 +bad input" "0 +success" "Examples:" "kdrt-render scenes/lens.json" \
                "--encoding TEXT:\{linear,srgb\}=linear" "--traversal TEXT.*=stack" "--progress" "--no-progress" \
                "--float" "--width .*=the scene's" "--sah-costs .*=1,0[.]3[|]0[.]6,0[.]6" "pfm" "--tile .*=64x64" \
                "--device cpu,opencl --tile" "--accel .*=bvh; kd with"; do
        grep -Eq -- "$want" out.txt || fail "--help lacks '$want'"
    done
    ;;
format_options)
    expect 2 "--encoding srgb is for 8-bit outputs; a.exr" -- "${small[@]}" --encoding srgb -o a.exr
    expect 2 "--encoding srgb is for 8-bit outputs; a.pfm" -- "${small[@]}" --encoding srgb -o a.pfm
    expect 2 "--float is for TIFF outputs.*a.png" -- "${small[@]}" --float -o a.png
    expect 2 "--encoding" -- "${small[@]}" --encoding gamma -o a.png
    [ ! -e a.exr ] && [ ! -e a.png ] && [ ! -e a.pfm ] || fail "something was written"
    expect 0 "" -- "${small[@]}" --encoding srgb -o s.png
    expect 0 "" -- "${small[@]}" -o l.png
    cmp -s s.png l.png && fail "sRGB and linear PNGs are the same"
    expect 0 "" -- "${small[@]}" --float -o f.tif
    expect 0 "" -- "${small[@]}" -o e.tif
    [ "$(stat -c %s f.tif)" -gt "$(stat -c %s e.tif)" ] || fail "the float TIFF is not larger than the 8-bit one"
    expect 0 "" -- "${small[@]}" -o f.pfm
    [ "$(head -c 2 f.pfm)" = "PF" ] || fail "not a PFM file"
    # --stats-json times the writing of the outputs apart from the render.
    expect 0 '"write_ms": ?[0-9.e+-]+,' -- "${small[@]}" -o w.png --stats-json
    [ "$(stat -c %s f.pfm)" = $((14 + 16 * 16 * 12)) ] || fail "f.pfm has the wrong size"
    ;;
accel)
    # The BVH by default; the kd-tree where the command line asks for what only it has.
    expect 0 '"accel":"bvh"' -- "${small[@]}" --stats-json
    expect 0 '"accel":"kd","traversal":"ropes"' -- "${small[@]}" --traversal ropes --stats-json
    expect 0 '"accel":"kd"' -- "${small[@]}" --tree median --stats-json
    expect 0 '"accel":"kd"' -- "${small[@]}" --sah-costs 1,0.5,0.5 --stats-json
    expect 0 '"accel":"bvh","traversal":"none"' -- "${small[@]}" --traversal none --stats-json
    expect 2 "--traversal restart walks a kd-tree" -- "${small[@]}" --accel bvh --traversal restart -o a.png
    expect 2 "--tree, --tree-depth and --sah-costs build a kd-tree" -- "${small[@]}" --accel bvh --tree-depth 8 -o a.png
    [ ! -e a.png ] || fail "rendered anyway"
    ;;
several_devices)
    # Tiles shared by the cpu and the OpenCL device: one image, each device's share reported.
    expect 0 "" -- "${small[@]}" --device cpu,opencl --tile 4x8 -o multi.pfm
    [ "$(stat -c %s multi.pfm)" = $((14 + 16 * 16 * 12)) ] || fail "multi.pfm has the wrong size"
    expect 0 '"device_shares":\[\{"device":"cpu' -- "${small[@]}" --device cpu,opencl --tile 4x8 --stats-json
    grep -Eq '"tile":\{"width":4,"height":8\}' out.txt || fail "no tile size in the statistics"
    [ $(($(grep -Eo '"pixels":[0-9]+' out.txt | cut -d: -f2 | paste -sd+))) = 256 ] ||
        fail "the devices' pixels do not add up to the frame"
    [ $(($(grep -Eo '"tiles":[0-9]+' out.txt | cut -d: -f2 | paste -sd+))) = 8 ] ||
        fail "the devices' tiles do not add up to 8"
    # The frame in tiles reports its structure as one device's frame does.
    expect 0 '"tree":"bvh"' -- "${small[@]}" --device cpu,opencl --tile 4x8 --stats-json
    expect 0 '"nodes"' -- "${small[@]}" --device cpu,opencl --tile 4x8 --tree-stats
    expect 0 "cpu .* \+ opencl:0 .*multi2.png" -- scene.json --width 16 --height 16 --device cpu,opencl -o multi2.png
    grep -Eq "^  opencl:0 .*: [0-9]+ tiles, [0-9.]+% of the pixels, [0-9.]+ ms busy" out.txt || fail "no per-device line"
    # Bad lists and tile sizes: usage errors naming the problem, no image.
    expect 2 "names device cpu twice" -- "${small[@]}" --device cpu,cpu -o bad.png
    expect 2 "--device nosuch: unknown device" -- "${small[@]}" --device cpu,nosuch -o bad.png
    expect 2 "--device cpu,,opencl: an empty device name" -- "${small[@]}" --device cpu,,opencl -o bad.png
    expect 2 "--tile 0x4" -- "${small[@]}" --device cpu,opencl --tile 0x4 -o bad.png
    expect 2 "--tile 8by8" -- "${small[@]}" --device cpu,opencl --tile 8by8 -o bad.png
    expect 2 "--tile is for several devices" -- "${small[@]}" --device cpu --tile 8 -o bad.png
    [ ! -e bad.png ] || fail "a bad device list wrote an image"
    ;;
*)
    echo "unknown case $case"; exit 1 ;;
esac
echo "ok: $case"
