#!/bin/sh
# tools/bench (make bench) and tools/gen-scene, small: the scene generator is deterministic
# and writes what it is asked for; the bench runs end to end with --quick on one tiny
# generated scene (32x32, 200 triangles) and prints every table; the Embree anchor
# (BUILD/embree-anchor) and POV-Ray take part when they are there; a missing anchor is a
# clear message; make bench writes into tracked files only with UPDATE_DOCS=1. Times are not
# checked (speed lives in the benchmark). Usage: tests/bench.sh BUILD (from the repository
# root).
set -u
BUILD=${1:-build}
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
    if "$@"; then pass=$((pass + 1)); else echo "FAIL: $n"; fails=$((fails + 1)); fi
}
has() { grep -qF -- "$1" "$T/log"; }

# The generator: the same arguments give the same file; the count and kind asked for.
tools/gen-scene --count 200 --res 32 "$T/tiny.nff" >"$T/log" 2>&1
check "gen-scene triangles" 0 $?
tools/gen-scene --count 200 --res 32 "$T/again.nff" >"$T/log" 2>&1
check_true "gen-scene is deterministic" cmp -s "$T/tiny.nff" "$T/again.nff"
check_true "200 triangles" test "$(grep -c '^p 3$' "$T/tiny.nff")" -eq 200
check_true "the resolution asked for" grep -q '^resolution 32 32$' "$T/tiny.nff"
tools/gen-scene --kind spheres --count 1k --seed 7 "$T/sph.nff" >"$T/log" 2>&1
check "gen-scene spheres" 0 $?
check_true "1k spheres" test "$(grep -c '^s ' "$T/sph.nff")" -eq 1000
tools/gen-scene --seed 8 --kind spheres --count 1k "$T/sph8.nff" >"$T/log" 2>&1
check_true "another seed, another scene" sh -c "! cmp -s '$T/sph.nff' '$T/sph8.nff'"
"$BUILD/clwhitted" -q -W 8 -H 8 "$T/sph.nff" -o "$T/sph.png" >"$T/log" 2>&1
check "clwhitted reads a generated scene" 0 $?
tools/gen-scene --count 0 "$T/zero.nff" >"$T/log" 2>&1
check "gen-scene --count 0" 2 $?
check_true "the message says what a count is" has "is not a count from 1 to 100M"

# The smoke run: every table, with the anchor and POV-Ray where they are there.
opts=""
if [ -x "$BUILD/embree-anchor" ]; then anchor=1; else
    anchor=0; opts="$opts --no-anchor"
    echo "bench.sh: $BUILD/embree-anchor is not built (make $BUILD/embree-anchor): without it"
fi
if command -v povray >/dev/null 2>&1 && [ -x "$BUILD/scene2pov" ]; then pov=1; else
    pov=0; opts="$opts --no-pov"
    echo "bench.sh: no povray or $BUILD/scene2pov: without POV-Ray"
fi
sed -n '1,/<!-- tools\/bench: generated section: begin -->/p' docs/benchmarks.md >"$T/doc.md"
printf 'old table\n' >>"$T/doc.md"
sed -n '/<!-- tools\/bench: generated section: end -->/,$p' docs/benchmarks.md >>"$T/doc.md"
cp "$T/doc.md" "$T/doc-before.md"
# shellcheck disable=SC2086
tools/bench --quick --no-cold --sizes 32 --pov-sizes 32 --scenes "$T/tiny.nff" \
    --scale-sizes 200 --scale-kinds triangles --scale-res 32 --out "$T/out" \
    --clwhitted "$BUILD/clwhitted" --anchor "$BUILD/embree-anchor" \
    --scene2pov "$BUILD/scene2pov" --update-docs "$T/doc.md" $opts >"$T/stdout" 2>"$T/err"
rc=$?
cat "$T/stdout" "$T/err" >"$T/log"
check "tools/bench --quick" 0 $rc
check_true "the SPD table's columns" has "| scene | device | clwhitted | anchor | POV-Ray | clwhitted/anchor | POV-Ray/clwhitted | clwhitted MB | anchor MB | POV-Ray MB |"
check_true "the scene's row" grep -Eq '^\| tiny \| pocl-pthread \| [0-9]+\.[0-9]{3} \| ' "$T/log"
check_true "the total" grep -Eq '^\| \*\*total\*\* \| pocl-pthread \| [0-9]+\.[0-9]{3} \| ' "$T/log"
check_true "the fixed costs' columns" has "| scene | OpenCL device | parse | device | build | compile | upload | trace | write | other | cold compile | anchor build_ms | anchor render_ms | anchor rest |"
check_true "the fixed costs' row" grep -Eq '^\| tiny \| pocl-pthread( \| [0-9.-]+){12} \|$' "$T/log"
# Intel's OpenCL runtime, where tools/install-deps installed it: its own rows
if tools/with-intel-ocl --print-env >/dev/null 2>&1; then
    check_true "the Intel device's row" grep -Eq '^\| tiny \| intel-cpu \| [0-9]+\.[0-9]{3} \| ' "$T/log"
    check_true "the Intel device's total" grep -Eq '^\| \*\*total\*\* \| intel-cpu \| [0-9]+\.[0-9]{3} \| ' "$T/log"
else
    echo "bench.sh: Intel's OpenCL runtime is not installed (tools/install-deps): its rows not checked"
fi
check_true "the scaling table's columns" has "| scene | NFF MB | parse | build | render | whole process | peak MB | render cw/anchor | whole cw/anchor | rays cw / anchor | anchor -q |"
check_true "the scaling row" grep -Eq '^\| triangles-200 \| [0-9.]+ \| [0-9.]+ / ' "$T/log"
check_true "the generated scene kept in the gen folder" test -s "$T/out/gen/triangles-200-32.nff"
check_true "table.md: what stdout showed" cmp -s "$T/out/table.md" "$T/stdout"
check_true "results.csv: every run" grep -q 'cw_wall' "$T/out/results.csv"
check_true "progress on stderr, tables on stdout" sh -c "! grep -q '^| ' '$T/err'"
check_true "--update-docs: the generated section replaced" grep -q '^| triangles-200 |' "$T/doc.md"
check_true "--update-docs: the old section gone" sh -c "! grep -q '^old table$' '$T/doc.md'"
check_true "--update-docs: the rest of the page kept" sh -c \
    "sed '/generated section: begin/,/generated section: end/d' '$T/doc.md' >'$T/a'; \
     sed '/generated section: begin/,/generated section: end/d' '$T/doc-before.md' >'$T/b'; \
     cmp -s '$T/a' '$T/b'"
if [ $anchor -eq 1 ]; then
    check_true "the anchor's times" grep -Eq '^\| tiny \| pocl-pthread \| [0-9.]+ \| [0-9]+\.[0-9]{3} \| ' "$T/log"
    check_true "the ray counts of both" grep -Eq '^\| tiny \| [0-9]+ / [0-9]+ \(' "$T/log"
    check_true "the anchor's -q in the scaling row" grep -Eq '^\| triangles-200 .* \| high \|$' "$T/log"
fi
if [ $pov -eq 1 ]; then
    check_true "POV-Ray's times" grep -Eq '^\| tiny \| pocl-pthread( \| [0-9.-]+){2} \| [0-9]+\.[0-9]{3} \| ' "$T/log"
fi
[ $fails -eq 0 ] || sed 's/^/    /' "$T/log"

# --dry-run: the devices and scenes, nothing run
tools/bench --dry-run --no-anchor --scenes "$T/tiny.nff" --devices pocl \
    --clwhitted "$BUILD/clwhitted" --out "$T/dry" >"$T/log" 2>&1
check "tools/bench --dry-run" 0 $?
check_true "--dry-run names the device and the scene" sh -c \
    "grep -q '^devices: pocl-pthread' '$T/log' && grep -q '^scenes: tiny$' '$T/log'"
check_true "--dry-run runs nothing" test ! -e "$T/dry"

# A missing anchor: a clear message before any run, no Python traceback.
tools/bench --quick --no-cold --no-spd --scale-sizes 10 --scale-kinds spheres \
    --out "$T/out2" --clwhitted "$BUILD/clwhitted" --anchor "$T/nowhere/embree-anchor" \
    >"$T/log" 2>&1
check "missing anchor" 1 $?
check_true "the message names the anchor and the ways out" grep -q \
    "the Embree anchor $T/nowhere/embree-anchor is missing: build it with \`make build/embree-anchor\`.*--no-anchor" "$T/log"
check_true "no traceback" sh -c "! grep -q Traceback '$T/log'"
check_true "nothing run" test ! -e "$T/out2/gen"

# A page without the generated section: refused before any run.
tools/bench --quick --no-anchor --no-spd --out "$T/out3" --clwhitted "$BUILD/clwhitted" \
    --update-docs README.md >"$T/log" 2>&1
check "--update-docs without the section" 1 $?
check_true "the message names the markers" has "README.md has no generated section"
check_true "nothing run" test ! -e "$T/out3"

# make bench writes into build/bench/; docs/benchmarks.md only with UPDATE_DOCS=1 (what
# make would run, without running it), and the anchor is built from ANCHOR_DIR.
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u UPDATE_DOCS make -n bench >"$T/log" 2>&1
check "make -n bench" 0 $?
check_true "make bench runs tools/bench with the anchor" has "tools/bench --anchor build/embree-anchor"
check_true "make bench leaves docs/ alone" sh -c "! grep -q 'docs/' '$T/log'"
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -n bench UPDATE_DOCS=1 >"$T/log" 2>&1
check "make -n bench UPDATE_DOCS=1" 0 $?
check_true "UPDATE_DOCS=1 writes docs/benchmarks.md" has "--update-docs docs/benchmarks.md"
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make BUILD="$T/b" ANCHOR_DIR="$T/nowhere" \
    "$T/b/embree-anchor" >"$T/log" 2>&1
check "anchor without its source" 2 $?
check_true "the message names ANCHOR_DIR" has "$T/nowhere/embree_anchor.c not found (set ANCHOR_DIR or SHARED_DIR)"

echo "bench.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
