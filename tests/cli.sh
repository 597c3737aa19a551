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
# the scene loads while OpenCL starts, but its error still comes first and alone
"$BIN" --device no-such-device -o "$T/missing.png" "$T/missing.nff" >"$T/out" 2>"$T/err"
check "missing file and unknown device" 1 $?
check_grep "missing file and unknown device: the scene's error" "missing.nff" "$T/err"
check_true "missing file and unknown device: one line" test "$(wc -l <"$T/err")" -eq 1
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

# cones and transmission render, with no warning
printf 'v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\nl 1 1 5\nf 1 1 1 1 0 1 0.5 1.5\nc\n0 0 0 1\n0 1 0 0.5\ns 0 0 0 1\n' >"$T/cone.nff"
"$BIN" -o "$T/cone.png" "$T/cone.nff" >"$T/out" 2>"$T/err"; check "cone scene renders" 0 $?
check_true "no warning for cones or transmission" test ! -s "$T/err"
"$BIN" --device 0:0 -q -o "$T/dev.png" -W 8 -H 6 scenes/default.json >"$T/out" 2>"$T/err"
check "--device 0:0" 0 $?

# --version, --help: every option (from main.c's option table) in the help and the man page
"$BIN" --version >"$T/out" 2>"$T/err"; check "--version" 0 $?
check_grep "--version prints the version" "^clwhitted [0-9][0-9.]*$" "$T/out"
check_grep "--version names the libraries" "libpng .*OpenEXR" "$T/out"
"$BIN" --help >"$T/out" 2>"$T/err"
# Every long option --help lists is one clwhitted accepts (not "unrecognized"), and the
# man page lists it too.
opts=$(sed -n 's/^ *\(-[A-Za-z], \)\{0,1\}--\([a-z0-9-]*\).*/\2/p' "$T/out")
check_true "--help lists the options" test "$(echo "$opts" | wc -l)" -ge 18
for o in $opts; do
    "$BIN" --$o >/dev/null 2>"$T/opt_err" </dev/null
    check_true "--$o is an option clwhitted knows" sh -c "! grep -q 'unrecognized option' '$T/opt_err'"
    check_true "man page lists --$o" sh -c "tr -d '\\\\' <'$ROOT/docs/clwhitted.1' | grep -q -- '--$o'"
done
for o in output width height depth spp precision spd device exposure tonemap half stats quiet \
    threads crop png16; do
    check_true "--help gives the default of --$o" sh -c \
        "sed -n '/--$o /,/default/p' '$T/out' | grep -q '(default: [^)]*)'"
done
check_grep "--help: exposure default" "(default: 0)" "$T/out"
check_grep "--help: tonemap default" "(default: clamp)" "$T/out"
check_grep "--help: exit status" "Exit status: 0 success, 1 input or render error, 2 usage error" "$T/out"
for v in CLWHITTED_BUILD_OPTIONS CLWHITTED_PROGRESS CLWHITTED_SUMMARY POCL_DEVICES POCL_CACHE_DIR; do
    check_grep "--help documents $v" "^  $v " "$T/out"
    check_true "docs/usage.md documents $v" grep -q "^| \`$v\`" "$ROOT/docs/usage.md"
done

# usage errors: exit 2, one line naming the problem, then the hint
usage_error() { # usage_error NAME PATTERN ARGS...
    n=$1 pat=$2; shift 2
    "$BIN" "$@" >"$T/out" 2>"$T/err"; check "$n" 2 $?
    check_true "$n: two lines" test "$(wc -l <"$T/err")" -eq 2
    check_true "$n: reason" sh -c "head -n 1 '$T/err' | grep -q -- \"^clwhitted: .*$pat\""
    check_true "$n: hint" sh -c "tail -n 1 '$T/err' | grep -qx \"Try 'clwhitted --help'.\""
    check_true "$n: nothing on stdout" test ! -s "$T/out"
}
usage_error "unknown long option" "frobnicate" --frobnicate scenes/default.json
usage_error "unknown short option" "'x'" -x scenes/default.json
usage_error "ambiguous option" "--de" --de 3 scenes/default.json
usage_error "missing value" "'o'" scenes/default.json -o
usage_error "value for a flag" "--half" --half=1 scenes/default.json
usage_error "bad width" "--width expects an integer in 1..65536, got 'abc'" --width abc scenes/default.json
usage_error "bad spp" "--spp expects" --spp 0 scenes/default.json
usage_error "bad precision" "--precision expects" --precision exact scenes/default.json
usage_error "bad exposure" "--exposure expects a number" --exposure bright scenes/default.json
usage_error "exposure out of range" "--exposure expects a number in -64..64" --exposure 100 scenes/default.json
usage_error "bad tonemap" "--tonemap expects 'clamp', 'reinhard' or 'aces', got 'filmic'" --tonemap filmic scenes/default.json
usage_error "no scene" "no scene file given"
usage_error "two scenes with -o" "-o names one image" -o "$T/two.png" scenes/default.json scenes/default.json
usage_error "bad extension" "unsupported image extension" -o "$T/x.jpg" scenes/default.json

# options that make no sense together, and bad environment values: one line, exit 2
usage_error "--spd with --spp" "--spd traces the pixel corners: it takes no --spp" --spd --spp 4 scenes/default.json
usage_error "--spp with --spd" "--spd traces the pixel corners: it takes no --spp" --spp 1 --spd scenes/default.json
usage_error "--preview --spd" "--spd does not apply to --preview" --preview --spd scenes/default.json
usage_error "bad repeat" "--repeat expects an integer in 1..1000, got '0'" --repeat 0 scenes/default.json
usage_error "repeat out of range" "--repeat expects an integer in 1..1000, got '1001'" --repeat 1001 scenes/default.json
for o in "-o $T/p.png" "--exposure 1" "--tonemap aces" "--half" "--png16" "--stats" "--crop 0,2,0,2" "--repeat 2"; do
    # shellcheck disable=SC2086
    usage_error "--preview $o" "${o%% *} does not apply to --preview" --preview $o scenes/default.json
done
usage_error "--preview with two scenes" "more than one scene does not apply to --preview" --preview scenes/default.json scenes/default.json
usage_error "empty --device" "--device expects P:D or part of a device name, got ''" --device '' scenes/default.json
usage_error "--exposure on EXR" "--exposure applies to PNG output" --exposure 1 -o "$T/w.exr" scenes/default.json
usage_error "--tonemap on the default EXR" "--tonemap applies to PNG output" --tonemap aces scenes/default.json
usage_error "--png16 on EXR" "--png16 applies to PNG output" --png16 -o "$T/w.exr" scenes/default.json
usage_error "--half on PNG" "--half applies to EXR output" --half -o "$T/w.png" scenes/default.json
usage_error "bad --threads" "--threads expects an integer in 1..1024, got '0'" --threads 0 scenes/default.json
usage_error "bad --crop" "--crop expects X0,X1,Y0,Y1" --crop 1,2,3 scenes/default.json
usage_error "empty --crop window" "--crop expects X0,X1,Y0,Y1" --crop 4,4,0,2 scenes/default.json
usage_error "--crop outside the image" "--crop 0,17,0,12 is not inside the 16x12 image" -W 16 -H 12 --crop 0,17,0,12 -o "$T/c.png" scenes/default.json
check_true "nothing written for a crop outside the image" test ! -e "$T/c.png"
for v in bogus ALWAYS 2; do
    CLWHITTED_PROGRESS=$v usage_error "CLWHITTED_PROGRESS=$v" "CLWHITTED_PROGRESS expects 'auto', 'always', 'never' or 'log', got '$v'" -o "$T/e.png" scenes/default.json
done
CLWHITTED_PROGRESS= "$BIN" -q -W 8 -H 6 -o "$T/e.png" scenes/default.json >"$T/out" 2>"$T/err"
check "empty CLWHITTED_PROGRESS is auto" 0 $?

# --threads: the same image with 1 and 2 threads; PoCL's device gets that many compute
# units (its worker threads)
IMGTOOL=$(dirname "$BIN")/imgtool
for n in 1 2; do
    "$BIN" --stats --threads $n -W 40 -H 30 -o "$T/t$n.exr" scenes/default.json >"$T/out" 2>"$T/err"
    check "--threads $n" 0 $?
    check_grep "--threads $n: the device's compute units" "^device: .*, $n compute units\{0,1\}," "$T/out"
    "$IMGTOOL" raw "$T/t$n.exr" "$T/t$n.raw" >/dev/null 2>"$T/err"
done
check_true "--threads 1 and 2: the same pixels" cmp -s "$T/t1.raw" "$T/t2.raw"

# PoCL's threads are pinned one per CPU (POCL_AFFINITY=1, host/main.c) only where that covers
# every CPU the process may use: the default here when nothing narrows this shell's CPUs;
# never with fewer or more threads than CPUs (PoCL pins thread i to CPU i and aborts where
# that CPU is missing), under a narrowed CPU set, or over the user's own POCL_AFFINITY
NCPU=$(getconf _NPROCESSORS_ONLN)
if [ "$NCPU" = 1 ]; then all_cpus=0; else all_cpus="0-$((NCPU - 1))"; fi
if [ "$(nproc)" = "$NCPU" ] && [ "$(cat /sys/devices/system/cpu/online)" = "$all_cpus" ]; then
    want_pin="pinned one per CPU (POCL_AFFINITY=1)"
else
    want_pin="not pinned (not one thread per CPU, or a narrowed CPU set)"
fi
"$BIN" --stats -W 8 -H 6 -o "$T/pin.png" scenes/default.json >"$T/out" 2>"$T/err"
check "default pinning" 0 $?
check_grep "--stats: PoCL's threads $want_pin" "^threads: $want_pin$" "$T/out"
POCL_MAX_PTHREAD_COUNT=$((NCPU + 1)) "$BIN" --stats -W 8 -H 6 -o "$T/pin.png" scenes/default.json \
    >"$T/out" 2>"$T/err"
check "more threads than CPUs: not pinned, no PoCL abort" 0 $?
check_grep "more threads than CPUs: not pinned" "^threads: not pinned" "$T/out"
rm -f "$T/pin.png"
POCL_AFFINITY=1 POCL_MAX_PTHREAD_COUNT=$((NCPU + 1)) "$BIN" -W 8 -H 6 -o "$T/pin.png" \
    scenes/default.json >"$T/out" 2>"$T/err"
check "the user's POCL_AFFINITY=1 with more threads than CPUs: an error, not PoCL's abort" 1 $?
check_grep "POCL_AFFINITY=1 with more threads than CPUs: says why" \
    "POCL_AFFINITY=1 pins PoCL's thread i to CPU i, and $((NCPU + 1)) threads .* more than the $NCPU CPUs here: use at most $NCPU threads or unset POCL_AFFINITY" "$T/err"
check_true "POCL_AFFINITY=1 with more threads than CPUs: no image" [ ! -e "$T/pin.png" ]
POCL_AFFINITY=1 "$BIN" --threads $((NCPU + 1)) -W 8 -H 6 -o "$T/pin.png" scenes/default.json \
    >"$T/out" 2>"$T/err"
check "the user's POCL_AFFINITY=1 with --threads above the CPUs: an error" 1 $?
POCL_AFFINITY=0 "$BIN" --stats -W 8 -H 6 -o "$T/pin.png" scenes/default.json >"$T/out" 2>"$T/err"
check "the user's POCL_AFFINITY" 0 $?
check_grep "the user's POCL_AFFINITY is left alone" "^threads: POCL_AFFINITY as the environment set it$" "$T/out"
if [ "$NCPU" -gt 1 ]; then
    "$BIN" --stats --threads 1 -W 8 -H 6 -o "$T/pin.png" scenes/default.json >"$T/out" 2>"$T/err"
    check "--threads 1 of $NCPU CPUs" 0 $?
    check_grep "--threads 1 of $NCPU CPUs: not pinned" "^threads: not pinned" "$T/out"
    taskset -c 1 "$BIN" --stats -W 8 -H 6 -o "$T/pin.png" scenes/default.json >"$T/out" 2>"$T/err"
    check "taskset -c 1: renders" 0 $?
    check_grep "taskset -c 1: not pinned" "^threads: not pinned" "$T/out"
fi

# --crop on the command line: the window's pixels of the full render (tests/test_crop.c
# checks every strategy and mode); the metadata names the crop
"$BIN" -q -W 40 -H 30 -o "$T/full.exr" scenes/default.json >"$T/out" 2>"$T/err"; check "full render" 0 $?
"$BIN" -W 40 -H 30 --crop 10,25,4,30 -o "$T/crop.exr" scenes/default.json >"$T/out" 2>"$T/err"
check "--crop render" 0 $?
check_grep "--crop: the summary gives the crop's size" "wrote $T/crop.exr (15x26)" "$T/out"
check_true "--crop: the metadata names the crop" sh -c "tr '\\0' ' ' <'$T/crop.exr' | grep -aq '40x30, crop 10,25,4,30, depth'"
"$IMGTOOL" convert --crop 10,25,4,30 "$T/full.exr" "$T/fullcut.exr" >"$T/out" 2>"$T/err"
check "imgtool convert --crop" 0 $?
"$IMGTOOL" raw "$T/fullcut.exr" "$T/a.raw" >/dev/null 2>&1; "$IMGTOOL" raw "$T/crop.exr" "$T/b.raw" >/dev/null 2>&1
check_true "--crop: exactly the full render's pixels" cmp -s "$T/a.raw" "$T/b.raw"

# JSON says what NFF says: the NFF scenes of tests/scenes/inside/ (spheres visible from inside
# only, seen from inside and outside; NFF's camera angle) and their JSON copies give the same
# pixels
for name in room bowl; do
    for ext in nff json; do
        "$BIN" -q -o "$T/$name-$ext.exr" "tests/scenes/inside/$name.$ext" >"$T/out" 2>"$T/err"
        check "tests/scenes/inside/$name.$ext" 0 $?
        "$IMGTOOL" raw "$T/$name-$ext.exr" "$T/$name-$ext.raw" >/dev/null 2>&1
    done
    check_true "$name.json: the pixels of $name.nff" cmp -s "$T/$name-nff.raw" "$T/$name-json.raw"
done

# --png16: a 16-bit PNG (tests/test_image.c round-trips the values)
"$BIN" -q -W 16 -H 12 --png16 -o "$T/p16.png" scenes/default.json >"$T/out" 2>"$T/err"; check "--png16" 0 $?
check_true "--png16: IHDR says 16 bits" sh -c "od -An -tu1 -j24 -N1 '$T/p16.png' | grep -qw 16"
check_true "--png16: metadata says so" sh -c "tr '\\0' ' ' <'$T/p16.png' | grep -aq 'tonemap clamp, 16-bit'"

# several scenes in one call: each NAME.exr, a summary line each; a bad one is reported and
# the others still render (exit 1)
printf 'v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 6\nl 1 1 5\nf 1 0 0 1 0 0 0 0\ns 0 0 0 1\n' >"$T/ball.nff"
(cd "$T" && "$BIN" -W 16 -H 12 "$ROOT/scenes/default.json" ball.nff >"$T/out" 2>"$T/err"); check "two scenes" 0 $?
check_true "two scenes: both images" test -s "$T/default.exr" -a -s "$T/ball.exr"
check_true "two scenes: two summary lines" test "$(grep -c '^clwhitted: wrote' "$T/out")" -eq 2
rm -f "$T/ball.exr"
(cd "$T" && "$BIN" -W 16 -H 12 missing.nff ball.nff >"$T/out" 2>"$T/err"); check "a bad scene among several" 1 $?
check_grep "a bad scene among several: named" "missing.nff" "$T/err"
check_true "a bad scene among several: the next still renders" test -s "$T/ball.exr"

# --camera FILE: the camera, size and depth of a camera file, for NFF scenes too; -W wins
printf '{"image": {"width": 20, "height": 10}, "max_depth": 2,\n "camera": {"eye": [0, 3, 6], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 50}}\n' >"$T/cam.json"
"$BIN" --camera "$T/cam.json" -o "$T/cam.png" scenes/default.json >"$T/out" 2>"$T/err"; check "--camera" 0 $?
check_grep "--camera: its image size" "wrote $T/cam.png (20x10)" "$T/out"
check_true "--camera: its depth in the metadata" sh -c "tr '\\0' ' ' <'$T/cam.png' | grep -aq '20x10, depth 2,'"
"$BIN" --camera "$T/cam.json" -W 16 -o "$T/cam2.png" "$T/ball.nff" >"$T/out" 2>"$T/err"; check "--camera on an NFF scene" 0 $?
check_grep "--camera: -W wins" "wrote $T/cam2.png (16x10)" "$T/out"
"$BIN" -q -W 20 -H 10 -d 2 -o "$T/cam3.png" scenes/default.json >"$T/out" 2>"$T/err"
"$IMGTOOL" diff "$T/cam.png" "$T/cam3.png" >"$T/out" 2>"$T/err"; check "--camera changes the view" 1 $?
printf '{"camera": {"eye": [0, 0, 1]},\n "lights": []}\n' >"$T/badcam.json"
"$BIN" --camera "$T/badcam.json" -o "$T/bc.png" scenes/default.json >"$T/out" 2>"$T/err"; check "bad camera file" 1 $?
check_grep "bad camera file: file:line" "badcam.json:2: camera file: unknown key \"lights\"" "$T/err"
"$BIN" --camera "$T/cam.nff" -o "$T/bc.png" scenes/default.json >"$T/out" 2>"$T/err"; check "camera file not JSON" 1 $?
check_grep "camera file not JSON: message" "a camera file is JSON" "$T/err"

# --look-from, --look-at, --up, --fov: the camera of the command line, after the scene and
# --camera, for NFF and JSON scenes alike: the same pixels as a scene file with that camera
R=tests/scenes/inside
sed 's/"camera": .*/"camera": {"eye": [1, 2, 4], "look_at": [0, 0.5, 0], "up": [1, 1, 0], "fov": 50},/' \
    "$R/room.json" >"$T/room-cam.json"
"$BIN" -q -o "$T/cam-file.exr" "$T/room-cam.json" >"$T/out" 2>"$T/err"; check "room with another camera" 0 $?
"$IMGTOOL" raw "$T/cam-file.exr" "$T/cam-file.raw" >/dev/null 2>&1
for scene in "$R/room.nff" "$R/room.json"; do
    "$BIN" -q -o "$T/cam-cli.exr" --camera "$T/cam.json" --look-from 1,2,4 --look-at 0,0.5,0 \
        --up 1,1,0 --fov 50 -W 64 -H 48 -d 5 "$scene" >"$T/out" 2>"$T/err"
    check "camera overrides on $scene" 0 $?
    "$IMGTOOL" raw "$T/cam-cli.exr" "$T/cam-cli.raw" >/dev/null 2>&1
    check_true "camera overrides on $scene: the pixels of the scene with that camera" \
        cmp -s "$T/cam-cli.raw" "$T/cam-file.raw"
done
# --look-from alone keeps the view direction (0, -0.5, -3) of room.nff, moved back along it
sed 's/"camera": .*/"camera": {"eye": [0, 2, 9], "look_at": [0, 1.5, 6], "up": [0, 1, 0], "angle": 60},/' \
    "$R/room.json" >"$T/room-back.json"
"$BIN" -q -o "$T/back-file.exr" "$T/room-back.json" >"$T/out" 2>"$T/err"; check "room seen from further back" 0 $?
"$BIN" -q -o "$T/back-cli.exr" --look-from 0,2,9 "$R/room.nff" >"$T/out" 2>"$T/err"
check "--look-from alone" 0 $?
"$IMGTOOL" raw "$T/back-file.exr" "$T/a.raw" >/dev/null 2>&1; "$IMGTOOL" raw "$T/back-cli.exr" "$T/b.raw" >/dev/null 2>&1
check_true "--look-from alone: the view direction kept" cmp -s "$T/a.raw" "$T/b.raw"
check_true "--look-from alone: another picture" sh -c "! cmp -s '$T/a.raw' '$T/cam-file.raw'"
# bad values: usage errors (exit 2, one line and the hint, nothing rendered)
for bad in "--look-from 1,2" "--look-from 1,2,3,4" "--look-at a,b,c" "--look-at 1,,2" "--up 0,0,0" \
    "--up 1,2,1e19" "--fov 0" "--fov 180" "--fov -5" "--fov wide"; do
    # shellcheck disable=SC2086
    "$BIN" -o "$T/bad-view.png" $bad "$R/room.nff" >"$T/out" 2>"$T/err"; check "usage error: $bad" 2 $?
    check_grep "usage error: $bad: the option named" "^clwhitted: ${bad%% *} expects" "$T/err"
    check_true "usage error: $bad: one line and the hint" test "$(wc -l <"$T/err")" -eq 2
done
check_true "usage errors: no image" test ! -e "$T/bad-view.png"
# a degenerate view: a scene error (exit 1) naming the scene, for either program
for bad in "--look-at 0,1,3" "--look-from 1,1,1 --look-at 1,1,1" "--look-at 0,1,-5 --up 0,0,1" \
    "--look-at 0,5,3"; do
    # shellcheck disable=SC2086
    "$BIN" -o "$T/bad-view.png" $bad "$R/room.nff" >"$T/out" 2>"$T/err"; check "degenerate view: $bad" 1 $?
    check_grep "degenerate view: $bad: the scene named" "^clwhitted: $R/room.nff: the camera of the command line: " "$T/err"
done
check_grep "the scene's up, parallel: the hint" "give --up" "$T/err"
"$BIN" -o "$T/bad-view.png" --fov 30 scenes/orthographic.json >"$T/out" 2>"$T/err"; check "--fov on an orthographic camera" 1 $?
check_grep "--fov on an orthographic camera: message" "perspective camera; the scene's is orthographic" "$T/err"
check_true "degenerate views: no image" test ! -e "$T/bad-view.png"

# the log progress mode: plain lines, no carriage returns (one every 5 s: a short render
# prints none, so only their form is checked here; tests/test_progress.c checks the lines)
CLWHITTED_PROGRESS=log "$BIN" -W 16 -H 12 -o "$T/log.png" scenes/default.json >"$T/out" 2>"$T/err"
check "CLWHITTED_PROGRESS=log" 0 $?
check_true "log mode: no carriage return" sh -c "! grep -q \"$(printf '\r')\" '$T/err'"

# --list-devices: platform, device, type, compute units, memory, OpenCL C, fp64
"$BIN" --list-devices >"$T/out" 2>"$T/err"; check "--list-devices details" 0 $?
check_grep "--list-devices: platform and version" "^platform 0: .* (OpenCL [0-9]" "$T/out"
check_grep "--list-devices: P:D, type, name" "^  device 0:0  \(CPU\|GPU\|accelerator\|custom\|other\)  ." "$T/out"
check_grep "--list-devices: units, memory, max alloc, OpenCL C, fp64" \
    "^ *[0-9][0-9]* compute units, [0-9.]* [MG]iB memory (max alloc [0-9.]* [MG]iB), OpenCL C [0-9]\.[0-9].*, fp64 \(yes\|no\)$" "$T/out"

# the summary line: output, size, time, (the kernel compile apart,) Mrays/s; short enough
# for an 80-column terminal with a short output name. A fresh kernel cache: the compile
# is reported apart.
CLWHITTED_CACHE_DIR="$T/kcache" POCL_CACHE_DIR="$T/pcache" \
    "$BIN" -W 16 -H 12 -o "$T/sum.png" scenes/default.json >"$T/out" 2>"$T/err"; check "summary render" 0 $?
check_grep "summary line" \
    "^clwhitted: wrote $T/sum.png (16x12) in [0-9.]* s, [0-9.]* Mrays/s\(; compile [0-9.]* s\)\{0,1\}$" "$T/out"
check_grep "summary line: a fresh cache reports the compile apart" "; compile [0-9.]* s$" "$T/out"
check_true "one summary line" test "$(wc -l <"$T/out")" -eq 1
check_true "summary fits 80 columns" test "$(sed "s|$T/||" "$T/out" | wc -L)" -le 80
"$BIN" --stats -W 16 -H 12 -o "$T/stats.png" scenes/default.json >"$T/out" 2>"$T/err"
check "--stats render" 0 $?
check_grep "--stats: device" "^device: .*, [0-9]* compute units\{0,1\}, \(pixel\|wavefront\) kernel; image 16x12, depth [0-9]*$" "$T/out"
check_grep "--stats: what the scene uploaded" "^scene: 5 spheres, 1 triangle, 2 polygons, 0 cones; 0 instances of 0 meshes; BVH [0-9]* nodes$" "$T/out"
check_grep "--stats: phase times" "^time: parse [0-9.]* s, build [0-9.]* s, compile [0-9.]* s, upload [0-9.]* s, trace [0-9.]* s ([0-9]* passes), first launch [0-9.]* s$" "$T/out"
check_grep "--stats: fixed costs" "^fixed: opencl [0-9.]* s (beside the parse), write [0-9.]* s$" "$T/out"
# on PoCL's CPU device the scene arrays are the buffers' memory: nothing of them is copied
check_grep "--stats: the scene arrays used in place" "^upload: 0\.0*[1-9][0-9]* MB of scene arrays used in place, 0\.[0-9]* MB copied$" "$T/out"
check_true "no progress bar when stderr is a file" test ! -s "$T/err"
# --repeat 3: the summary, then one line with the three renders' times, their least and median;
# the image is the one a single render writes
"$BIN" --repeat 3 -W 16 -H 12 -o "$T/rep.exr" scenes/default.json >"$T/out" 2>"$T/err"
check "--repeat 3" 0 $?
check_true "--repeat: summary and repeat lines" test "$(wc -l <"$T/out")" -eq 2
check_grep "--repeat: the times" \
    "^repeat: 3 renders, render least [0-9.]* s, median [0-9.]* s: [0-9.]* [0-9.]* [0-9.]*$" "$T/out"
check_true "--repeat: least <= median <= greatest" awk '/^repeat:/ {
    l = $6; m = $9; g = $11; if ($12 > g) g = $12; if ($13 > g) g = $13
    exit !(l + 0 <= m + 0 && m + 0 <= g + 0 && (l == $11 || l == $12 || l == $13)) }' "$T/out"
"$BIN" -W 16 -H 12 -o "$T/once.exr" scenes/default.json >/dev/null 2>&1
check_true "--repeat: the same image as one render" "$ROOT/build/imgcmp" --tol 0 --max-over 0 --min-over 0 "$T/once.exr" "$T/rep.exr"
"$BIN" -q --repeat 2 -W 16 -H 12 -o "$T/repq.exr" scenes/default.json >"$T/out" 2>"$T/err"
check "--repeat -q" 0 $?
check_true "--repeat -q: nothing on stdout" test ! -s "$T/out"
# CLWHITTED_SUMMARY=long: the phases and the device, for scripts (tools/gallery, tools/bench)
CLWHITTED_SUMMARY=long "$BIN" -W 16 -H 12 -o "$T/long.png" scenes/default.json >"$T/out" 2>"$T/err"
check "CLWHITTED_SUMMARY=long" 0 $?
check_grep "the long summary line" \
    "^clwhitted: wrote $T/long.png (16x12, depth [0-9]*) in [0-9.]* s on .*: load [0-9.]* s, setup [0-9.]* s, render [0-9.]* s, [0-9.]* Mrays/s$" "$T/out"
CLWHITTED_SUMMARY=bogus usage_error "CLWHITTED_SUMMARY=bogus" "CLWHITTED_SUMMARY expects 'short' or 'long', got 'bogus'" -o "$T/e.png" scenes/default.json

# the progress bar: forced on a file, it draws in place and clears the line at the end
CLWHITTED_PROGRESS=always "$BIN" -W 32 -H 24 --spp 2 -o "$T/p.png" scenes/default.json >"$T/out" 2>"$T/err"
check "forced progress" 0 $?
check_true "bar drawn with \\r" sh -c "tr '\\r' '\\n' <'$T/err' | grep -Eq '^\\[[#-]+\\] +[0-9]+%  [0-9.]+ Mrays  [0-9:]+ elapsed  ETA [0-9:-]+  [0-9.-]+ Mrays/s\$'"
check_true "no newline in the bar" test "$(wc -l <"$T/err")" -eq 0
check_true "line cleared at the end" sh -c "tail -c 2 '$T/err' | od -An -c | grep -q ' *\\\\r'"
check_true "line cleared with spaces" sh -c "tr '\\r' '\\n' <'$T/err' | tail -n 1 | grep -q '^ *\$'"
check_grep "summary still on stdout" "^clwhitted: wrote" "$T/out"
CLWHITTED_PROGRESS=always "$BIN" -q -W 16 -H 12 -o "$T/pq.png" scenes/default.json >"$T/out" 2>"$T/err"
check "forced progress, quiet" 0 $?
check_true "--quiet: no bar" test ! -s "$T/err"
check_true "--quiet: no summary" test ! -s "$T/out"
if script -qec true /dev/null >/dev/null 2>&1; then
    # on a terminal (a pty from script): the bar appears, and CLWHITTED_PROGRESS=never hides it
    script -qec "'$BIN' -W 32 -H 24 -o '$T/tty.png' scenes/default.json" /dev/null >"$T/out" 2>&1
    check "render on a terminal" 0 $?
    check_true "bar on a terminal" grep -q " elapsed  ETA " "$T/out"
    check_true "bar on a terminal uses \\r" sh -c "tr '\\r' '\\n' <'$T/out' | grep -Eq '^\\[[#-]+\\] +[0-9]+%'"
    CLWHITTED_PROGRESS=never script -qec "'$BIN' -W 32 -H 24 -o '$T/tty.png' scenes/default.json" /dev/null >"$T/out" 2>&1
    check_true "CLWHITTED_PROGRESS=never on a terminal" sh -c "! grep -q ' elapsed ' '$T/out'"
    script -qec "'$BIN' -q -W 32 -H 24 -o '$T/tty.png' scenes/default.json" /dev/null >"$T/out" 2>&1
    check_true "--quiet on a terminal: nothing" sh -c "! tr -d '\\r\\n' <'$T/out' | grep -q ."
else
    echo "cli.sh: no 'script' (util-linux): terminal checks skipped"
fi

# output options and metadata
"$BIN" -q -W 16 -H 12 --exposure 1 --tonemap reinhard -o "$T/m.png" scenes/default.json >"$T/out" 2>"$T/err"
check "exposure and tonemap" 0 $?
check_true "PNG Software" sh -c "grep -aq 'Softwareclwhitted [0-9]' '$T/m.png' || tr '\\0' ' ' <'$T/m.png' | grep -aq 'Software clwhitted [0-9]'"
check_true "PNG Title is the scene" sh -c "tr '\\0' ' ' <'$T/m.png' | grep -aq 'Title default.json'"
check_true "PNG Comment has the settings" sh -c "tr '\\0' ' ' <'$T/m.png' | grep -aq 'Comment 16x12, depth [0-9]*, spp 1, precision robust, exposure +1 EV, tonemap reinhard'"
check_true "PNG Render Time" sh -c "tr '\\0' ' ' <'$T/m.png' | grep -aq 'Render Time [0-9.]* s'"
"$BIN" -q -W 16 -H 12 -o "$T/f.exr" scenes/default.json >"$T/out" 2>"$T/err"; check "float EXR" 0 $?
"$BIN" -q -W 16 -H 12 --half -o "$T/h.exr" scenes/default.json >"$T/out" 2>"$T/err"; check "half EXR" 0 $?
check_true "half EXR is smaller" test "$(wc -c <"$T/h.exr")" -lt "$(wc -c <"$T/f.exr")"
check_true "EXR software attribute" sh -c "tr '\\0' ' ' <'$T/h.exr' | grep -aq 'software string .*clwhitted [0-9]'"
check_true "EXR comments: the settings" sh -c "tr '\\0' ' ' <'$T/h.exr' | grep -aq '16x12, depth [0-9]*, spp 1, precision robust, half floats'"
check_true "EXR renderTime attribute" grep -aq renderTime "$T/h.exr"
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
check "image size over 2^28 pixels: a usage error" 2 $?
check_grep "image size message" "\-W 65536 -H 4097 is 268500992 pixels; an image may have at most 268435456" "$T/err"
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
