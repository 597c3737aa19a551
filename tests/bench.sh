#!/bin/sh
# tools/bench (make bench), tools/gen-scene and tools/gen-mesh, small: the generators are
# deterministic and write what they are asked for (the mesh's PLY read back); the bench runs
# end to end with --quick on one tiny generated scene (32x32, 200 triangles) and prints
# every table; the Embree anchor
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

# The mesh generator: exactly N triangles, the same file for the same arguments, a PLY whose
# sizes and indices hold together (a small reader below), and the same mesh as NFF.
tools/gen-mesh --count 1001 "$T/mesh.ply" >"$T/log" 2>&1
check "gen-mesh ply" 0 $?
tools/gen-mesh --count 1001 "$T/again.ply" >"$T/log" 2>&1
check_true "gen-mesh is deterministic" cmp -s "$T/mesh.ply" "$T/again.ply"
tools/gen-mesh --count 1001 --seed 2 "$T/seed2.ply" >"$T/log" 2>&1
check_true "another seed, another mesh" sh -c "! cmp -s '$T/mesh.ply' '$T/seed2.ply'"
python3 - "$T/mesh.ply" 1001 >"$T/log" 2>&1 <<'PY'
import struct, sys
d = open(sys.argv[1], "rb").read()
end = d.index(b"end_header\n") + len(b"end_header\n")
head = d[:end].decode("ascii").split("\n")
assert head[:2] == ["ply", "format binary_little_endian 1.0"], head[:2]
nv = int([h for h in head if h.startswith("element vertex ")][0].split()[2])
nf = int([h for h in head if h.startswith("element face ")][0].split()[2])
assert nf == int(sys.argv[2]), (nf, sys.argv[2])
assert "property list uchar int vertex_indices" in head
assert len(d) == end + 12 * nv + 13 * nf, "file size"
xyz = struct.unpack_from("<%df" % (3 * nv), d, end)
assert all(0.5 < (xyz[k] ** 2 + xyz[k + 1] ** 2 + xyz[k + 2] ** 2) ** 0.5 < 1.5
           for k in range(0, len(xyz), 3)), "a vertex off the bumpy sphere"
for i in range(nf):
    c, a, b, e = struct.unpack_from("<B3i", d, end + 12 * nv + 13 * i)
    assert c == 3 and 0 <= min(a, b, e) and max(a, b, e) < nv and len({a, b, e}) == 3, i
PY
check "the PLY's header, sizes and indices" 0 $?
tools/gen-mesh --count 1001 --format nff --res 16 "$T/mesh.nff" >"$T/log" 2>&1
check "gen-mesh nff" 0 $?
check_true "1001 NFF triangles" test "$(grep -c '^p 3$' "$T/mesh.nff")" -eq 1001
"$BUILD/clwhitted" -q -W 16 -H 16 "$T/mesh.nff" -o "$T/mesh.png" >"$T/log" 2>&1
check "clwhitted reads the NFF mesh" 0 $?
tools/gen-mesh --count 0 "$T/zero.ply" >"$T/log" 2>&1
check "gen-mesh --count 0" 2 $?
check_true "its message says what a count is" has "is not a count from 1 to 200M"

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
check_true "the start-up floor's columns" has "| scene | OpenCL device | OpenCL open | clwhitted 2x2 | anchor 2x2 | clwhitted 32 | anchor 32 | floor: clwhitted 2x2 / anchor 32 | clwhitted/anchor | beyond the floor: clwhitted/anchor |"
# its OpenCL open and clwhitted 2x2 times are measured (the anchor's where it runs)
check_true "the start-up floor's row" grep -Eq '^\| tiny \| pocl-pthread \| [0-9]+\.[0-9] \| [0-9]+\.[0-9] \| ' "$T/log"
check_true "the floor's runs in results.csv" grep -q 'open_wall' "$T/out/results.csv"
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

# A missing start-up floor program: a clear message that says how to build it, no run.
mkdir -p "$T/nostart"
ln -s "$(cd "$(dirname "$BUILD/clwhitted")" && pwd)/clwhitted" "$T/nostart/clwhitted"
tools/bench --quick --no-anchor --no-pov --no-scale --scenes "$T/tiny.nff" --out "$T/out4" \
    --clwhitted "$T/nostart/clwhitted" >"$T/log" 2>&1
check "missing clstartup" 1 $?
check_true "the message names clstartup and the way out" has "nostart/clstartup is missing: run make"
check_true "nothing run" test ! -e "$T/out4"

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
