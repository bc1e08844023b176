# Sourced by the CLI test scripts after they set render, scenes, work and case:
# a fresh working directory with a small copy of lens, and the helpers
# fail (report and exit 1) and expect (run kdrt-render, check exit code and output).
dir="$work/$case"
rm -rf "$dir" && mkdir -p "$dir" || exit 1
cd "$dir" || exit 1
cp "$scenes/lens.json" scene.json
small=(scene.json --width 16 --height 16 -q)

fail() { echo "FAIL [$case]: $*"; echo "--- output:"; cat out.txt 2>/dev/null; exit 1; }
# expect RC REGEX -- ARGS...: runs kdrt-render, checks the exit code and, unless
# REGEX is empty, that the output matches.
expect() {
    local want=$1 regex=$2; shift 3
    "$render" "$@" >out.txt 2>&1
    local rc=$?
    [ "$rc" = "$want" ] || fail "kdrt-render $* exited $rc, expected $want"
    [ -z "$regex" ] || grep -Eq -- "$regex" out.txt || fail "kdrt-render $*: output does not match '$regex'"
}
