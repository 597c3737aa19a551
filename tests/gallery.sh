#!/bin/sh
# tools/gallery (make gallery), small: seven copies of scenes/spd/tetra.nff stand in for the
# SPD scenes, rendered at 8x8 into a temporary folder. Usage: tests/gallery.sh BINARY
set -u
BIN=$1
ROOT=$(pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0
SCENES="balls gears mount rings teapot tetra tree"

check() { # check NAME EXPECTED_RC ACTUAL_RC
    if [ "$2" -eq "$3" ]; then pass=$((pass + 1)); else
        echo "FAIL: $1: exit $3, expected $2"; sed 's/^/    /' "$T/log"; fails=$((fails + 1)); fi
}
check_true() { # check_true NAME COMMAND...
    n=$1; shift
    if "$@"; then pass=$((pass + 1)); else echo "FAIL: $n"; fails=$((fails + 1)); fi
}

# No SPD scenes: a clear message, nothing written.
SPD_DIR="$T/nowhere" GALLERY_DIR="$T/g0" sh tools/gallery "$BIN" >"$T/log" 2>&1
check "missing SPD_DIR" 1 $?
check_true "the message names SPD_DIR" grep -q "SPD scenes are not in '$T/nowhere'.*SPD_DIR" "$T/log"
check_true "nothing written without scenes" test ! -e "$T/g0"

mkdir "$T/spd"
for s in $SCENES; do cp "$ROOT/scenes/spd/tetra.nff" "$T/spd/$s.nff"; done
SPD_DIR="$T/spd" GALLERY_DIR="$T/g" GALLERY_SIZE=8 sh tools/gallery "$BIN" >"$T/log" 2>&1
check "gallery" 0 $?
for s in $SCENES default; do
    check_true "$s.png written" sh -c "head -c 8 '$T/g/$s.png' | od -An -c | grep -q 'P   N   G'"
    check_true "$s row: command line, times, device" grep -Eq \
        "^\| $s \| <img src=\"$s.png\".* \| \`clwhitted .*-o $s.png .*\` \| [0-9.]+ s \| [0-9.]+ s \| [0-9.]+ \| [^|]+ \| " \
        "$T/g/README.md"
done
check_true "SPD command lines give the size" grep -q '`clwhitted -W 8 -H 8 -o tetra.png spd/tetra.nff`' "$T/g/README.md"
check_true "default scene at its own size" grep -q '`clwhitted -o default.png scenes/default.json`' "$T/g/README.md"
check_true "eight rows" test "$(grep -c '^| [a-z]* | <img' "$T/g/README.md")" -eq 8
[ $fails -eq 0 ] || sed 's/^/    /' "$T/g/README.md"

# make gallery writes into build/gallery/; the tracked docs/gallery/ only with UPDATE_DOCS=1
# (what make would run, without running it)
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u UPDATE_DOCS make -n gallery >"$T/log" 2>&1
check "make -n gallery" 0 $?
check_true "make gallery renders into build/gallery" grep -q "GALLERY_DIR='build/gallery'" "$T/log"
check_true "make gallery leaves docs/ alone" sh -c "! grep -q 'docs/' '$T/log'"
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u UPDATE_DOCS make -n gallery UPDATE_DOCS=1 >"$T/log" 2>&1
check "make -n gallery UPDATE_DOCS=1" 0 $?
check_true "UPDATE_DOCS=1 copies the gallery into docs/gallery" \
    grep -q '^cp build/gallery/README.md build/gallery/\*.png docs/gallery/$' "$T/log"

echo "gallery.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
