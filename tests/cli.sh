#!/bin/sh
# Command-line behaviour: exit codes, messages, outputs. Usage: tests/cli.sh BINARY
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
ROOT=$(pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0

check() { # check NAME EXPECTED_RC ACTUAL_RC
    if [ "$2" -eq "$3" ]; then pass=$((pass + 1)); else
        echo "FAIL: $1: exit $3, expected $2"; sed 's/^/    /' "$T/err" 2>/dev/null; fails=$((fails + 1)); fi
}
check_grep() { # check_grep NAME PATTERN FILE
    if grep -q -- "$2" "$3"; then pass=$((pass + 1)); else
        echo "FAIL: $1: '$2' not in:"; sed 's/^/    /' "$3"; fails=$((fails + 1)); fi
}
check_true() { # check_true NAME COMMAND...
    n=$1; shift
    if "$@"; then pass=$((pass + 1)); else echo "FAIL: $n"; fails=$((fails + 1)); fi
}

"$BIN" --help >"$T/out" 2>"$T/err"; check "--help" 0 $?
check_grep "--help lists --output" "--output" "$T/out"
check_grep "--help lists --device" "--device" "$T/out"
"$BIN" >"$T/out" 2>"$T/err"; check "no scene" 2 $?
check_grep "no scene message" "no scene file" "$T/err"
"$BIN" --frobnicate x.nff >"$T/out" 2>"$T/err"; check "unknown option" 2 $?
"$BIN" --width abc scenes/default.json >"$T/out" 2>"$T/err"; check "bad width" 2 $?
check_grep "bad width message" "--width expects an integer" "$T/err"
"$BIN" --depth 0 scenes/default.json >"$T/out" 2>"$T/err"; check "bad depth" 2 $?
"$BIN" --list-devices >"$T/out" 2>"$T/err"; check "--list-devices" 0 $?
check_grep "--list-devices shows a device" "device 0:0" "$T/out"
"$BIN" --device no-such-device -o "$T/x.png" scenes/default.json >"$T/out" 2>"$T/err"
check "unknown device" 1 $?
check_grep "unknown device message" "no OpenCL device matches" "$T/err"

# bad input: file:line message, exit 1, no image written
"$BIN" -o "$T/missing.png" "$T/missing.nff" >"$T/out" 2>"$T/err"; check "missing file" 1 $?
check_grep "missing file named" "missing.nff" "$T/err"
printf 'b 0 0 0\nq 1 2 3\n' >"$T/bad.nff"
"$BIN" -o "$T/bad.png" "$T/bad.nff" >"$T/out" 2>"$T/err"; check "unknown entity" 1 $?
check_grep "unknown entity names file:line" "bad.nff:2:" "$T/err"
check_true "no image after bad input" test ! -e "$T/bad.png"
printf '{\n  "camera": {\n    "eye": [0, 0, 1],\n    "look_at": [0, 0, 1],\n    "up": [0, 1, 0], "fov": 40\n  }\n}\n' >"$T/bad.json"
"$BIN" -o "$T/badj.png" "$T/bad.json" >"$T/out" 2>"$T/err"; check "degenerate camera" 1 $?
check_grep "json error names the file" "bad.json:" "$T/err"
"$BIN" -o "$T/x.tiff" -W 8 -H 6 scenes/default.json >"$T/out" 2>"$T/err"; check "bad extension" 2 $?
check_grep "bad extension message" "unsupported image extension" "$T/err"
check_true "nothing left for a bad extension" test -z "$(ls "$T" | grep -v -e '^bad' -e '^out$' -e '^err$')"
"$BIN" -o "$T/no/such/dir/x.png" -W 8 -H 6 scenes/default.json >"$T/out" 2>"$T/err"
check "unwritable output" 1 $?

# a kernel build failure prints the build log and exits 1 (an invalid feature flag hits #error)
CLWHITTED_BUILD_OPTIONS=-DCW_HAS_MIRRORS=2 \
    "$BIN" -o "$T/build.png" -W 8 -H 6 scenes/default.json >"$T/out" 2>"$T/err"
check "kernel build failure" 1 $?
check_grep "build log printed" "kernel build log" "$T/err"
check_grep "build log has the #error" "must be 0 or 1" "$T/err"
check_grep "the failed call is named" "clBuildProgram" "$T/err"
check_true "no image after a build failure" test ! -e "$T/build.png"

# good renders
"$BIN" -q -o "$T/small.png" -W 32 -H 24 scenes/default.json >"$T/out" 2>"$T/err"; check "png render" 0 $?
check_true "png written" test -s "$T/small.png"
check_true "png magic" sh -c "head -c 8 '$T/small.png' | od -An -c | grep -q 'P   N   G'"
check_true "quiet prints nothing" test ! -s "$T/out"
(cd "$T" && "$BIN" -W 16 -H 12 -d 2 "$ROOT/scenes/default.json" >"$T/out" 2>"$T/err"); check "default output" 0 $?
check_true "default output is NAME.exr in the current folder" test -s "$T/default.exr"
check_grep "summary names the output" "wrote default.exr" "$T/out"
check_true "no temporary files left" test -z "$(ls "$T" | grep tmp)"

# parsed but not rendered yet: cones and transmission are announced
printf 'v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\nl 1 1 5\nf 1 1 1 1 0 1 0.5 1.5\nc\n0 0 0 1\n0 1 0 0.5\ns 0 0 0 1\n' >"$T/cone.nff"
"$BIN" -o "$T/cone.png" "$T/cone.nff" >"$T/out" 2>"$T/err"; check "cone scene renders" 0 $?
check_grep "cones announced" "cone(s)/cylinder(s) are parsed but not rendered yet" "$T/err"
check_grep "transmission announced" "refraction is not rendered yet" "$T/err"
"$BIN" --device 0:0 -q -o "$T/dev.png" -W 8 -H 6 scenes/default.json >"$T/out" 2>"$T/err"
check "--device 0:0" 0 $?

# bad input of every kind: exit 1, the file (and line) named, no image written
mkdir "$T/dir.nff"
"$BIN" -o "$T/dir.png" "$T/dir.nff" >"$T/out" 2>"$T/err"; check "directory as scene" 1 $?
check_grep "directory named" "dir.nff: cannot read: Is a directory" "$T/err"
printf '\211PNG\r\n\032\n\000\000\000\rIHDR' >"$T/png.nff"
"$BIN" -o "$T/png.png" "$T/png.nff" >"$T/out" 2>"$T/err"; check "binary garbage" 1 $?
check_grep "binary garbage: file:line" "png.nff:3: unexpected NUL byte" "$T/err"
printf 'v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 65536 65536\n' >"$T/huge.nff"
"$BIN" -o "$T/huge.png" "$T/huge.nff" >"$T/out" 2>"$T/err"; check "huge resolution in a file" 1 $?
check_grep "huge resolution: file:line" "huge.nff:7: 'resolution' 65536x65536 has more than 2^28 pixels" "$T/err"
"$BIN" -o "$T/big.png" -W 65536 -H 4097 scenes/default.json >"$T/out" 2>"$T/err"
check "image size over 2^28 pixels" 1 $?
check_grep "image size message" "image size 65536x4097 out of range" "$T/err"
: >"$T/empty.json"
"$BIN" -o "$T/empty.png" "$T/empty.json" >"$T/out" 2>"$T/err"; check "empty file" 1 $?
check_grep "empty file: file:line" "empty.json:1: empty file" "$T/err"
printf 'v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n\033[2J\n' >"$T/esc.nff"
"$BIN" -o "$T/esc.png" "$T/esc.nff" >"$T/out" 2>"$T/err"; check "control characters" 1 $?
check_grep "control characters escaped" "esc.nff:8: unknown entity '.x1B\[2J'" "$T/err"
check_true "no control characters printed" sh -c "! grep -q \"$(printf '\033')\" '$T/err'"
"$BIN" -o "$T/zero.png" /dev/zero >"$T/out" 2>"$T/err"; check "device without extension" 1 $?
check_true "no image after any bad input" \
    test -z "$(ls "$T" | grep -e '^dir.png' -e '^png.png' -e '^huge.png' -e '^big.png' -e '^empty.png' -e '^esc.png' -e '^zero.png')"

echo "cli.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
