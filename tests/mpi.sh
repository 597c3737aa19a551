#!/bin/sh
# clwhitted-mpi (docs/mpi.md) under Open MPI on this machine: mpirun --oversubscribe with
# 1, 2 and 3 ranks renders every image bit for bit like clwhitted (EXR and PNG pixels,
# --spp, --spd, --precision fast, --half; tiles of a few rows so that every rank gets some,
# and the default tiles); the metadata names the ranks; --stats sums the ray counts to
# clwhitted's and lists every rank; failures (a bad scene, a missing device or another
# image size on one rank; a rank killed by SIGKILL mid-render; a stopped rank and the
# watchdog) end the job with a non-zero exit, the rank's message and no image, within time
# limits; tools/bench-mpi --quick runs. Skipped, saying so, when mpirun or BUILD/clwhitted-mpi is missing.
# Usage: tests/mpi.sh BUILD (from the repository root).
set -u
BUILD=${1:-build}
MPI="$BUILD/clwhitted-mpi"
if ! command -v mpirun >/dev/null 2>&1; then
    echo "mpi.sh: SKIPPED: no mpirun (sh tools/install-deps installs Open MPI)"
    exit 0
fi
if [ ! -x "$MPI" ]; then
    echo "mpi.sh: SKIPPED: $MPI is not built (make builds it where mpicc is found)"
    exit 0
fi
RUN="mpirun --oversubscribe --allow-run-as-root"
# Under make asan: Open MPI unloads its components in MPI_Finalize, so LeakSanitizer can
# neither name nor suppress what they keep; the MPI runs check memory errors and undefined
# behaviour there, not leaks (clwhitted's own leaks are checked by the other tests).
if [ -n "${ASAN_OPTIONS:-}" ]; then
    ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0"
    export ASAN_OPTIONS
fi
OUTDIR="$BUILD/test-output/mpi"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0

check() { # check NAME EXPECTED_RC ACTUAL_RC
    if [ "$2" -eq "$3" ]; then pass=$((pass + 1)); else
        echo "FAIL: $1: exit $3, expected $2"; sed 's/^/    /' "$T/log"; fails=$((fails + 1)); fi
}
check_true() { # check_true NAME COMMAND...
    n=$1; shift
    if "$@"; then pass=$((pass + 1)); else
        echo "FAIL: $n"; tr '\r' '\n' <"$T/log" | tail -n 20 | sed 's/^/    /'; fails=$((fails + 1)); fi
}
has() { grep -qF -- "$1" "$T/log"; }
# same_pixels A B: the decoded pixels (linear floats from EXR, sRGB-decoded PNG) bit for bit
same_pixels() {
    "$BUILD/imgtool" raw "$1" "$T/a.raw" >/dev/null 2>&1 &&
        "$BUILD/imgtool" raw "$2" "$T/b.raw" >/dev/null 2>&1 && cmp -s "$T/a.raw" "$T/b.raw"
}

# ---- the same image as clwhitted ---------------------------------------------------------
# case: NAME SCENE EXT OPTIONS (W x H small; TILE rows per tile, 0: the default tiling)
printf '{"image": {"width": 40, "height": 30}, "max_depth": 3,\n "camera": {"eye": [1, 2, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 45}}\n' >"$T/cam.json"
n=0
while read -r name scene ext tile opts; do
    n=$((n + 1))
    # shellcheck disable=SC2086
    "$BUILD/clwhitted" -q $opts -o "$T/ref$n.$ext" "$scene" >"$T/log" 2>&1
    check "$name: clwhitted" 0 $?
    for np in 1 2 3; do
        rm -f "$T/mpi.$ext"
        # shellcheck disable=SC2086
        # (stdin from /dev/null: mpirun forwards its stdin to rank 0, which would eat the
        # rest of the case list)
        CLWHITTED_MPI_TILE_ROWS=$tile timeout 120 $RUN -np $np "$MPI" -q $opts \
            -o "$T/mpi.$ext" "$scene" </dev/null >"$T/log" 2>&1
        check "$name: $np ranks" 0 $?
        if same_pixels "$T/ref$n.$ext" "$T/mpi.$ext"; then pass=$((pass + 1)); else
            mkdir -p "$OUTDIR"
            cp "$T/ref$n.$ext" "$OUTDIR/$name-clwhitted.$ext"
            cp "$T/mpi.$ext" "$OUTDIR/$name-$np-ranks.$ext" 2>/dev/null
            [ -x "$BUILD/imgcmp" ] && "$BUILD/imgcmp" --tol 0 --max-over 0 --min-over 0 \
                --max-mean 0 --diff-always --diff "$OUTDIR/$name-$np-diff.png" \
                "$T/ref$n.$ext" "$T/mpi.$ext"
            echo "FAIL: $name: $np ranks: not clwhitted's pixels (the images: $OUTDIR/$name-*)"
            fails=$((fails + 1))
        fi
    done
done <<CASES
default-exr scenes/default.json exr 5 -W 96 -H 64
default-png scenes/default.json png 7 -W 96 -H 64 --exposure 0.5 --tonemap aces
default-half scenes/default.json exr 0 -W 96 -H 64 --half
spp4 scenes/default.json exr 3 -W 64 -H 48 --spp 4
spd scenes/spd/tetra.nff exr 4 -W 64 -H 64 --spd
spd-png scenes/oblique.json png 2 -W 48 -H 40 --spd
fast scenes/orthographic.json exr 6 -W 80 -H 60 --precision fast
camera scenes/spd/tetra.nff exr 4 --camera $T/cam.json --look-from 1.5,2,3.5 --fov 35
CASES

# The comparison can fail: another depth gives other pixels.
"$BUILD/clwhitted" -q -W 96 -H 64 -d 1 -o "$T/other.exr" scenes/default.json >"$T/log" 2>&1
check_true "another depth gives other pixels" sh -c \
    "'$BUILD/imgtool' raw '$T/ref1.exr' '$T/a.raw' >/dev/null && \
    '$BUILD/imgtool' raw '$T/other.exr' '$T/b.raw' >/dev/null && ! cmp -s '$T/a.raw' '$T/b.raw'"

# ---- metadata and --stats ----------------------------------------------------------------
CLWHITTED_MPI_TILE_ROWS=4 timeout 120 $RUN -np 3 "$MPI" --stats -W 64 -H 48 --spp 2 \
    -o "$T/stats.exr" scenes/default.json >"$T/log" 2>&1
check "--stats on 3 ranks" 0 $?
check_true "the metadata names the ranks" grep -qa "3 MPI ranks" "$T/stats.exr"
check_true "one line per rank" test "$(grep -c '^rank [0-2]: ' "$T/log")" -eq 3
check_true "the tiles add up to the image's 12" test "$(sed -n 's/^rank [0-9]*: \([0-9]*\) tiles.*/\1/p' \
    "$T/log" | awk '{s += $1} END {print s}')" -eq 12
grep '^rays:' "$T/log" >"$T/rays-mpi"
"$BUILD/clwhitted" --stats -W 64 -H 48 --spp 2 -o "$T/stats1.exr" scenes/default.json \
    >"$T/log" 2>&1
grep '^rays:' "$T/log" >"$T/rays-one"
check_true "the ray counts summed over the ranks are clwhitted's" \
    sh -c "test -s '$T/rays-one' && cmp -s '$T/rays-one' '$T/rays-mpi'"

# ---- usage -----------------------------------------------------------------------------------
timeout 60 $RUN -np 2 "$MPI" --help >"$T/log" 2>&1
check "--help" 0 $?
check_true "--help once, on rank 0" test "$(grep -c '^usage: mpirun' "$T/log")" -eq 1
timeout 60 $RUN -np 2 "$MPI" --preview scenes/default.json >"$T/log" 2>&1
check_true "--preview is a usage error" has "--preview is not available over MPI"
timeout 60 $RUN -np 2 "$MPI" --crop 0,8,0,8 -o "$T/c.exr" scenes/default.json >"$T/log" 2>&1
check "--crop: exit 2" 2 $?
check_true "--crop is a usage error" has "--crop is not available over MPI"
timeout 60 $RUN -np 2 "$MPI" --repeat 2 -o "$T/r.exr" scenes/default.json >"$T/log" 2>&1
check "--repeat: exit 2" 2 $?
check_true "--repeat is a usage error" has "--repeat is not available over MPI"

# ---- several scenes: one after the other, each to its own NAME.exr, clwhitted's pixels -----
ROOT=$(pwd)
mkdir "$T/multi" "$T/multi1"
(cd "$T/multi" && timeout 120 $RUN -np 2 "$ROOT/$MPI" -q -W 40 -H 30 "$ROOT/scenes/default.json" \
    "$ROOT/scenes/oblique.json" </dev/null >"$T/log" 2>&1)
check "two scenes on 2 ranks" 0 $?
(cd "$T/multi1" && "$ROOT/$BUILD/clwhitted" -q -W 40 -H 30 "$ROOT/scenes/default.json" \
    "$ROOT/scenes/oblique.json" >"$T/log" 2>&1)
check "two scenes: clwhitted" 0 $?
for name in default oblique; do
    check_true "two scenes: $name.exr has clwhitted's pixels" \
        same_pixels "$T/multi1/$name.exr" "$T/multi/$name.exr"
done
rm -f "$T/multi/default.exr"
(cd "$T/multi" && timeout 120 $RUN -np 2 "$ROOT/$MPI" -q -W 40 -H 30 missing.nff \
    "$ROOT/scenes/default.json" </dev/null >"$T/log" 2>&1)
check "a bad scene among several: exit 1" 1 $?
check_true "a bad scene among several: named" has "missing.nff"
check_true "a bad scene among several: the next still renders" test -s "$T/multi/default.exr"

# ---- failures: a non-zero exit, the rank's message on rank 0, no image ---------------------
fail_case() { # fail_case NAME MESSAGE MPIRUN-ARGS...
    name=$1 msg=$2; shift 2
    rm -f "$T/f.exr"
    timeout 60 $RUN "$@" >"$T/log" 2>&1
    rc=$?
    check_true "$name: a non-zero exit, not the time limit" test $rc -ne 0 -a $rc -ne 124
    check_true "$name: the message" has "$msg"
    check_true "$name: no image" test ! -e "$T/f.exr"
}
fail_case "bad scene on rank 1" "clwhitted-mpi: rank 1: $T/nope.json: cannot open" \
    -np 1 "$MPI" -o "$T/f.exr" scenes/default.json : -np 1 "$MPI" -o "$T/f.exr" "$T/nope.json"
fail_case "no such device on ranks 1 and 2" "rank 2: no OpenCL device matches 'nosuch'" \
    -np 1 "$MPI" -o "$T/f.exr" scenes/default.json : \
    -np 2 "$MPI" --device nosuch -o "$T/f.exr" scenes/default.json
fail_case "another size on rank 1" "give every rank the same scene and options" \
    -np 1 "$MPI" -o "$T/f.exr" scenes/default.json : \
    -np 1 "$MPI" -W 10 -o "$T/f.exr" scenes/default.json
fail_case "a bad scene everywhere" "rank 0: $T/nope.json: cannot open" \
    -np 2 "$MPI" -o "$T/f.exr" "$T/nope.json"

# A rank stopped or killed mid-render (a render of several seconds): wait for the progress
# bar, then signal rank 1. The job must end soon after, with no image and no temporary file.
mid_render() { # mid_render NAME SIGNAL LIMIT MESSAGE
    name=$1 sig=$2 limit=$3 msg=$4
    mkdir -p "$T/out"
    rm -f "$T/out/"*
    : >"$T/log" # emptied here: the job's own redirection may come after the wait below
    CLWHITTED_PROGRESS=always CLWHITTED_MPI_TIMEOUT=3 $RUN -np 2 "$MPI" -W 640 -H 960 \
        --spp 64 -o "$T/out/k.exr" scenes/default.json >"$T/log" 2>&1 &
    job=$!
    i=0
    victim=""
    while [ $i -lt 600 ] && [ -z "$victim" ]; do
        sleep 0.1
        i=$((i + 1))
        has "Mrays" || continue
        for p in $(pgrep -P $job); do
            if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx OMPI_COMM_WORLD_RANK=1
            then victim=$p; fi
        done
    done
    check_true "$name: rank 1 found rendering" test -n "$victim"
    [ -n "$victim" ] && kill "-$sig" "$victim"
    t0=$(date +%s)
    ( sleep "$limit"; kill -KILL "$job" 2>/dev/null; [ -n "$victim" ] && kill -KILL "$victim" ) \
        2>/dev/null &
    guard=$!
    wait "$job"
    rc=$?
    t1=$(date +%s)
    pkill -P "$guard" 2>/dev/null; kill "$guard" 2>/dev/null
    check_true "$name: a non-zero exit" test $rc -ne 0
    check_true "$name: ended within $limit s ($((t1 - t0)) s)" test $((t1 - t0)) -lt "$limit"
    check_true "$name: no image, no temporary file" test -z "$(ls -A "$T/out")"
    [ -n "$msg" ] && check_true "$name: the message" has "$msg"
}
mid_render "rank 1 killed" KILL 20 ""
mid_render "rank 1 stopped" STOP 30 "clwhitted-mpi: rank 1 sent nothing for 3 s"

# The benchmark runs end to end (its figures are not checked: speed lives in benchmarks).
timeout 300 tools/bench-mpi --quick --build "$BUILD" --out "$T/bench" >"$T/log" 2>&1
check "tools/bench-mpi --quick" 0 $?
check_true "bench-mpi prints the table and the overhead" sh -c \
    "grep -q '^| clwhitted-mpi | 2 | 1 |' '$T/log' && grep -q '^Overhead of the MPI path at 1 rank' '$T/log'"

echo "mpi.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
