#!/bin/sh
# Nothing left behind breaks the next run: the kernel cache (corrupt, truncated, wrong
# header, FIFO, huge sparse file, symbolic links, a folder others may write), the output
# path (checked before the scene is read), signals during a write, the memory estimate, the
# range of scene numbers, environment errors, exit codes and escaped messages.
# Usage: tests/safety.sh BUILD_DIR (with clwhitted, imgtool and imgcmp in it)
set -u
B=$(cd "$1" && pwd)
BIN=$B/clwhitted
. "$(dirname "$0")/lib.sh"
chmod 755 "$T"
check_true() { # check_true NAME COMMAND...
    n=$1
    shift
    if "$@"; then ok; else bad "$n" "$T/err"; fi
}
count() { grep -c -- "$1" "$2"; }
now_ms() { date +%s%3N; }

# A small scene, one warning-free image of it rendered without a cache: the reference.
SCENE=$T/scene.json
cp scenes/default.json "$SCENE"
ARGS="-W 48 -H 36 -q"
CLWHITTED_CACHE_DIR= "$BIN" $ARGS -o "$T/ref.exr" "$SCENE" 2>"$T/err"
check "reference render" 0 $?
"$B/imgtool" raw "$T/ref.exr" "$T/ref.raw" >/dev/null

same_image() { # same_image EXR: the same pixels as the reference, bit for bit
    "$B/imgtool" raw "$1" "$T/test.raw" >/dev/null && cmp -s "$T/ref.raw" "$T/test.raw"
}

# ---- kernel cache ----------------------------------------------------------------------
C=$T/cache
export CLWHITTED_CACHE_DIR="$C"
"$BIN" $ARGS -o "$T/a.exr" "$SCENE" 2>"$T/err"
check "cache: first run" 0 $?
ENTRY=$(ls "$C"/*.bin 2>/dev/null | head -n 1)
check_true "cache: one entry written" [ -n "$ENTRY" -a -f "$ENTRY" ]
check_true "cache: no temporary file left" [ "$(ls "$C" | wc -l)" -eq 1 ]
cp "$ENTRY" "$T/good.bin"
SIZE=$(wc -c <"$ENTRY")
"$BIN" $ARGS -o "$T/a.exr" "$SCENE" 2>"$T/err"
check "cache: second run" 0 $?
check_true "cache: a valid entry gives no warning" [ ! -s "$T/err" ]
check_true "cache: image from the cache" same_image "$T/a.exr"

flip() { # flip FILE OFFSET: inverts one byte
    b=$(od -An -tu1 -j "$2" -N1 "$1" | tr -d ' ')
    printf "\\$(printf %03o $((255 - b)))" | dd of="$1" bs=1 seek="$2" conv=notrunc 2>/dev/null
}

# Each case damages the entry, then: exit 0, one warning naming the cache file, the right
# image, and a valid entry after (the next run warns no more, and the entry is a file).
cache_case() { # cache_case NAME (the entry has been damaged)
    start=$(now_ms)
    timeout 120 "$BIN" $ARGS -o "$T/c.exr" "$SCENE" 2>"$T/err"
    rc=$?
    echo "  cache $1: $(($(now_ms) - start)) ms, $(count warning "$T/err") warning(s)"
    check "cache $1: exit" 0 $rc
    check_true "cache $1: one warning" [ "$(count "warning: ignoring the kernel cache file" "$T/err")" -eq 1 ]
    check_true "cache $1: the right image" same_image "$T/c.exr"
    check_true "cache $1: entry rewritten as a regular file" [ -f "$ENTRY" -a ! -L "$ENTRY" ]
    "$BIN" $ARGS -o "$T/c.exr" "$SCENE" 2>"$T/err"
    check "cache $1: next run" 0 $?
    check_true "cache $1: next run without warning" [ ! -s "$T/err" ]
    check_true "cache $1: no temporary file left" [ "$(ls "$C" | wc -l)" -eq 1 ]
}
head -c $((SIZE / 2)) "$T/good.bin" >"$ENTRY"
cache_case "truncated to half"
head -c 64 "$T/good.bin" >"$ENTRY"
cache_case "first 64 bytes"
cp "$T/good.bin" "$ENTRY"
for off in 100 $((SIZE / 3)) $((SIZE / 2)) $((SIZE - 10)); do flip "$ENTRY" $off; done
cache_case "bit flips in the binary"
cp "$T/good.bin" "$ENTRY"
flip "$ENTRY" 8
flip "$ENTRY" 32
cache_case "two header fields changed"
cp "$T/good.bin" "$ENTRY"
flip "$ENTRY" 20
cache_case "device identity changed"
cp "$T/good.bin" "$ENTRY"
printf 'x' >>"$ENTRY"
cache_case "one byte appended"
tail -c +49 "$T/good.bin" >"$ENTRY"
cache_case "a bare binary (no header)"
rm -f "$ENTRY"
mkfifo "$ENTRY"
cache_case "FIFO"
rm -f "$ENTRY"
truncate -s 4G "$ENTRY"
cache_case "4 GiB sparse file"
echo "keep me" >"$T/victim"
rm -f "$ENTRY"
ln -s "$T/victim" "$ENTRY"
cache_case "symbolic link to another file"
check_grep "cache: the link's target is untouched" "^keep me$" "$T/victim"
# The temporary file is made by mkstemp (O_CREAT|O_EXCL): links planted at every name the
# old code used (<entry>.<pid>.tmp) or at a fixed name are neither followed nor clobbered.
rm -f "$ENTRY"
for n in 1 2 3 4 5 6 7 8 9; do ln -s "$T/victim" "$ENTRY.tmp-$n$n$n$n$n$n"; done
"$BIN" $ARGS -o "$T/c.exr" "$SCENE" 2>"$T/err"
check "cache: links at temporary names" 0 $?
check_grep "cache: links at temporary names leave the target" "^keep me$" "$T/victim"
check_true "cache: entry written beside the links" [ -f "$ENTRY" -a ! -L "$ENTRY" ]
rm -f "$ENTRY".tmp-*
# A folder others may write to is used only when it is the user's own.
if [ "$(id -u)" -eq 0 ]; then
    mkdir "$T/shared"
    chmod 777 "$T/shared"
    chown nobody "$T/shared"
    CLWHITTED_CACHE_DIR="$T/shared" "$BIN" $ARGS -o "$T/c.exr" "$SCENE" 2>"$T/err"
    check "cache: a folder others write" 0 $?
    check_grep "cache: a folder others write is refused" "not using the kernel cache folder" "$T/err"
    check_true "cache: nothing written there" [ -z "$(ls "$T/shared")" ]
    check_true "cache: refused folder, right image" same_image "$T/c.exr"
fi

# ---- output path: checked before the scene is read -------------------------------------
# The scene is a FIFO that nobody writes: reading it would hang, so each case passing in
# time shows the output was refused before any parsing (the times are printed).
mkfifo "$T/hang.json"
out_case() { # out_case NAME PATTERN OUTPUT [RUNNER...]
    n=$1 pat=$2 out=$3
    shift 3
    start=$(now_ms)
    timeout 20 "$@" "$BIN" -q -o "$out" "$T/hang.json" >"$T/out" 2>"$T/err"
    rc=$?
    echo "  output $n: $(($(now_ms) - start)) ms"
    check "output $n: exit" 1 $rc
    check_grep "output $n: message" "$pat" "$T/err"
}
out_case "missing folder" "No such file or directory" "$T/nowhere/x.png"
mkdir "$T/dir.png"
out_case "path is a folder" "is a folder" "$T/dir.png"
touch "$T/afile"
out_case "folder is a file" "is not a folder" "$T/afile/x.png"
mkfifo "$T/fifo.png"
out_case "a FIFO" "not a regular file" "$T/fifo.png"
out_case "name too long" "file name too long" "$T/$(printf '%0252d' 0).png"
echo "old image" >"$T/ro.png"
chmod 444 "$T/ro.png"
out_case "read-only file" "read-only" "$T/ro.png"
check_grep "output: read-only file intact" "^old image$" "$T/ro.png"
mkdir "$T/rodir"
chmod 555 "$T/rodir"
if [ "$(id -u)" -ne 0 ]; then
    out_case "read-only folder" "cannot write in folder" "$T/rodir/x.png"
elif command -v setpriv >/dev/null; then
    out_case "read-only folder" "cannot write in folder" "$T/rodir/x.png" \
        setpriv --reuid=nobody --regid=nogroup --clear-groups
fi
check_true "output: no temporary file left" [ -z "$(ls "$T" | grep 'tmp-')" ]
# A 250-byte name: the temporary name is shortened to fit NAME_MAX.
LONG=$T/$(printf '%0246d' 0).png
"$BIN" $ARGS -o "$LONG" "$SCENE" 2>"$T/err"
check "output: 250-byte file name" 0 $?
check_true "output: 250-byte file name written" [ -s "$LONG" ]
# Replacing a file keeps its permission bits.
cp "$T/ref.exr" "$T/mode.exr"
chmod 640 "$T/mode.exr"
"$BIN" $ARGS -o "$T/mode.exr" "$SCENE" 2>"$T/err"
check "output: replace a 0640 file" 0 $?
check_true "output: 0640 kept" [ "$(stat -c %a "$T/mode.exr")" = 640 ]

# ---- signals during the write of a large image -----------------------------------------
# The previous image stays, the temporary file goes, the exit status is 128 + the signal.
# (env --default-signal: a shell starts background jobs with SIGINT ignored, and clwhitted
# leaves ignored signals ignored, as nohup wants.)
BIGARGS="-W 2048 -H 2048 -d 1 -q"
cp "$T/ref.exr" "$T/big.exr"
cksum "$T/big.exr" >"$T/big.sum"
for sig in INT TERM HUP; do
    env --default-signal=INT,TERM,HUP "$BIN" $BIGARGS -o "$T/big.exr" "$SCENE" 2>"$T/err" &
    pid=$!
    i=0
    while [ $i -lt 6000 ] && ! ls "$T" | grep -q '^big\.exr\.tmp-' && kill -0 $pid 2>/dev/null; do
        sleep 0.01
        i=$((i + 1))
    done
    kill -s $sig $pid 2>/dev/null
    wait $pid
    rc=$?
    num=$(kill -l $sig 2>/dev/null || echo 0)
    case $sig in INT) num=2 ;; TERM) num=15 ;; HUP) num=1 ;; esac
    check "signal $sig during the write: exit" $((128 + num)) $rc
    check_true "signal $sig: no temporary file left" [ -z "$(ls "$T" | grep 'tmp-')" ]
    check_true "signal $sig: previous image intact" cksum "$T/big.exr" | cmp -s - "$T/big.sum"
done
# Ctrl-C while the progress bar shows: the line is cleared (it ends in spaces and \r).
CLWHITTED_PROGRESS=always env --default-signal=INT "$BIN" -W 2048 -H 2048 -d 1 -o "$T/bar.exr" \
    "$SCENE" 2>"$T/bar" &
pid=$!
i=0
while [ $i -lt 6000 ] && ! grep -q '%' "$T/bar" 2>/dev/null; do
    sleep 0.01
    i=$((i + 1))
done
kill -s INT $pid
wait $pid
check "Ctrl-C during the render: exit" 130 $?
# the bar's text is overwritten: the output ends in \r, spaces, \r
last=$(tr '\r' '\n' <"$T/bar" | tail -n 1 | tr -d ' \n')
check_true "Ctrl-C: the progress line is cleared" [ -z "$last" -a "$(tail -c 1 "$T/bar" | od -An -c | tr -d ' ')" = '\r' ]
check_true "Ctrl-C: no image, no temporary file" [ ! -e "$T/bar.exr" -a -z "$(ls "$T" | grep 'tmp-')" ]

# ---- memory and sizes ------------------------------------------------------------------
# The largest image allowed needs about 11 GiB: refused under an address-space limit of
# 8 GiB (ulimit -v) whatever this machine's memory, before anything is allocated for it.
# (AddressSanitizer's shadow memory alone is more than any such limit: not in make asan.)
if [ -n "${ASAN_OPTIONS:-}" ]; then
    echo "  -W 16384 -H 16384 under ulimit -v: skipped in the sanitizer build"
else
    start=$(now_ms)
    (ulimit -v 8388608 && exec "$BIN" -W 16384 -H 16384 -o "$T/huge.exr" "$SCENE") >"$T/out" 2>"$T/err"
    rc=$?
    echo "  -W 16384 -H 16384 refused in $(($(now_ms) - start)) ms"
    check "16384x16384: exit" 1 $rc
    check_grep "16384x16384: says what is needed" "16384x16384 image needs" "$T/err"
    check_grep "16384x16384: says how to reduce it" "reduce -W/-H" "$T/err"
fi
"$BIN" -W 65536 -H 65536 -o "$T/huge.exr" "$SCENE" >"$T/out" 2>"$T/err"
check "65536x65536: a usage error" 2 $?
check_grep "65536x65536: message" "at most 268435456" "$T/err"

# ---- numbers that would not render correctly are refused -------------------------------
cat >"$T/scale.tmpl" <<'EOF'
{
  "image": {"width": 48, "height": 36},
  "background": [0.1, 0.12, 0.18],
  "ambient": 0.1,
  "camera": {"eye": [0, @1.4@, @5@], "look_at": [0, @0.7@, 0], "up": [0, 1, 0], "fov": 40},
  "materials": {
    "floor":  {"ka": 0.6, "kd": 0.6, "km": 0.15},
    "mirror": {"ka": 0.05, "kd": 0.05, "ks": 0.5, "km": 0.8, "p": 200},
    "red":    {"ka": [0.8, 0.1, 0.1], "kd": [0.8, 0.1, 0.1], "ks": 0.4, "p": 40}
  },
  "lights": [{"position": [@-4@, @6@, @5@], "intensity": 0.9}],
  "objects": [
    {"type": "polygon", "material": "floor",
     "vertices": [[@-5@, 0, @-5@], [@5@, 0, @-5@], [@5@, 0, @5@], [@-5@, 0, @5@]]},
    {"type": "sphere", "center": [@-0.7@, @0.8@, 0], "radius": @0.8@, "material": "mirror"},
    {"type": "sphere", "center": [@0.9@, @0.45@, @0.9@], "radius": @0.45@, "material": "red"}
  ]
}
EOF
scale() { # scale K: the scene above with every length times K/6 (the largest is K)
    awk -v k="$1" '{ while (match($0, /@[-0-9.]+@/)) {
        v = substr($0, RSTART + 1, RLENGTH - 2) * k / 6
        $0 = substr($0, 1, RSTART - 1) sprintf("%.9g", v) substr($0, RSTART + RLENGTH) } print }' \
        "$T/scale.tmpl"
}
for k in 1 1e18 1e20; do scale $k >"$T/scale$k.json"; done
"$BIN" -q -o "$T/scale1.exr" "$T/scale1.json" 2>"$T/err"
check "scale 1" 0 $?
"$BIN" -q -o "$T/scale1e18.exr" "$T/scale1e18.json" 2>"$T/err"
check "scale 1e18 (the largest accepted)" 0 $?
"$B/imgcmp" --tol 1e-4 --diff "$T/scale-diff.png" "$T/scale1.exr" "$T/scale1e18.exr" >"$T/cmp" 2>&1
check "scale 1e18 renders as scale 1 (within 1e-4)" 0 $?
[ -f "$T/scale-diff.png" ] && mkdir -p "$B/test-output" && cp "$T/scale-diff.png" "$B/test-output/"
"$BIN" -q -o "$T/scale1e20.exr" "$T/scale1e20.json" 2>"$T/err"
check "scale 1e20 refused" 1 $?
check_grep "scale 1e20: file:line and the bound" "scale1e20.json:5: camera.eye.*above 1e18" "$T/err"

# ---- environment ------------------------------------------------------------------------
POCL_DEVICES=nonexistent "$BIN" -q -o "$T/e.png" "$SCENE" >"$T/out" 2>"$T/err"
check "POCL_DEVICES hiding every device" 1 $?
check_grep "POCL_DEVICES named" "POCL_DEVICES='nonexistent'" "$T/err"
POCL_CACHE_DIR=/proc/clwhitted-no "$BIN" -q -o "$T/e.png" "$SCENE" >"$T/out" 2>"$T/err"
check "unwritable POCL_CACHE_DIR" 1 $?
check_grep "unwritable POCL_CACHE_DIR named" "PoCL cannot write its kernel cache folder /proc/clwhitted-no" "$T/err"

# ---- exit codes and messages -----------------------------------------------------------
{
    "$BIN" $ARGS -o "$T/pipe.exr" "$SCENE" 2>"$T/err"
    echo $? >"$T/rc"
} | true
check "closed stdout pipe after the image" 0 "$(cat "$T/rc")"
check_true "closed stdout pipe: image written" [ -s "$T/pipe.exr" ]
if [ -w /dev/full ]; then
    "$BIN" -W 48 -H 36 -o "$T/full.exr" "$SCENE" >/dev/full 2>"$T/err"
    check "summary to a full stdout" 1 $?
    check_grep "summary to a full stdout: message" "cannot write the summary" "$T/err"
fi
ESC=$(printf '\033')
"$BIN" -q -o "$T/no${ESC}[31mwhere/x.png" "$SCENE" >"$T/out" 2>"$T/err"
check "control characters in a path" 1 $?
check_grep "control characters escaped" 'no\\x1B\[31mwhere' "$T/err"
check_true "no raw escape on stderr" [ "$(tr -d -c '\033' <"$T/err" | wc -c)" -eq 0 ]
"$BIN" -q --tonemap "x${ESC}]0;t" -o "$T/x.png" "$SCENE" >"$T/out" 2>"$T/err"
check "control characters in an option" 2 $?
check_true "option value escaped" [ "$(tr -d -c '\033' <"$T/err" | wc -c)" -eq 0 ]
awk 'BEGIN { for (i = 0; i < 1200; i++) printf "["; for (i = 0; i < 1200; i++) printf "]"; print "" }' >"$T/deep.json"
"$BIN" -q -o "$T/deep.png" "$T/deep.json" >"$T/out" 2>"$T/err"
check "JSON nested 1200 levels" 1 $?
check_grep "nesting named" "deep.json:1: .*nest" "$T/err"

echo "safety.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
