#!/bin/sh
# Mesh files given directly (host/mesh_scene.c over assimp): bad files made here each give
# one clear error naming the file (exit 1, no image, nothing on stdout), a missing MTL a
# warning; then every OBJ, PLY, glTF (.gltf, .glb) and STL file of Debian's
# assimp-testmodels renders at 32x24 or is refused that way, never crashes (a signal or a
# sanitizer report), hangs (60 s) or leaves an image behind when it fails; the tally by
# format is printed.
# Usage: tests/meshes.sh BUILD_DIR (with clwhitted and imgtool in it) [MODELS_DIR]
set -u
B=$(cd "$1" && pwd)
BIN=$B/clwhitted
MODELS=${2:-/usr/share/assimp/models}
M=$(pwd)/tests/scenes/mesh
BAD_LINES=20
. "$(dirname "$0")/lib.sh"

# run FILE: renders FILE at 32x24 into an empty folder; sets rc, and leaves $T/out,
# $T/err and the folder's listing in $T/ls
run() {
    rm -rf "$T/o"
    mkdir "$T/o"
    timeout 60 "$BIN" -q -W 32 -H 24 -o "$T/o/out.png" "$1" >"$T/out" 2>"$T/err"
    rc=$?
    ls -A "$T/o" >"$T/ls"
}

sanitizer_report() { grep -q -e 'Sanitizer' -e 'runtime error' "$T/err"; }

# expect_error NAME FILE PATTERN: exit 1, one line "clwhitted: FILE: ..." matching
# PATTERN, nothing on stdout, no image
expect_error() {
    run "$2"
    if [ $rc -ne 1 ] || sanitizer_report; then
        bad "$1: exit $rc, expected 1" "$T/err"
    elif [ "$(wc -l <"$T/err")" -ne 1 ] || ! grep -q -- "^clwhitted: $2: " "$T/err"; then
        bad "$1: expected one line 'clwhitted: $2: ...'" "$T/err"
    elif ! grep -q -- "$3" "$T/err"; then
        bad "$1: '$3' not in the message" "$T/err"
    elif [ -s "$T/out" ] || [ -s "$T/ls" ]; then
        bad "$1: something on stdout or an image left" "$T/ls"
    else
        ok
    fi
}

# ---- bad files, made here from the test meshes -------------------------------------------
cd "$T"
head -c 1000 "$M/ico-binary.ply" >trunc.ply
expect_error "truncated binary PLY" trunc.ply "out of range\|unexpected end\|truncated"
# a face without vertices (made by fuzz_mesh): assimp's triangulation would abort
tail -c +5 "$OLDPWD/tests/fuzz/regressions/mesh/ply-face-without-vertices" >noverts.ply
expect_error "PLY face without vertices" noverts.ply "face 0 has no vertices"
# glTF: the second index of the first triangle set to 999 (the indices start at byte 1008)
cp "$M/ico.gltf" idx.gltf
cp "$M/ico.bin" ico.bin
printf '\347\003' | dd of=ico.bin bs=1 seek=1010 conv=notrunc 2>/dev/null
expect_error "glTF index out of range" idx.gltf "out-of-range indices"
cp "$M/ico.glb" magic.glb
printf 'glTX' | dd of=magic.glb bs=1 conv=notrunc 2>/dev/null
expect_error ".glb with a bad magic number" magic.glb "does not start with 'glTF'"
cp "$M/ico.glb" version.glb
printf '\003' | dd of=version.glb bs=1 seek=4 conv=notrunc 2>/dev/null
expect_error ".glb of version 3" version.glb "binary glTF version 3"
head -c 60 "$M/ico.glb" >short.glb
expect_error ".glb cut in its JSON chunk" short.glb "a length of 2456 bytes, the file has 60"
head -c 10 "$M/ico.glb" >tiny.glb
expect_error ".glb shorter than its header" tiny.glb "this one has 10 bytes"
# the JSON chunk's length set to 3.9 GB (found by fuzz_mesh: assimp allocated all of it)
cp "$M/ico.glb" chunk.glb
printf '\254\003\377\352' | dd of=chunk.glb bs=1 seek=12 conv=notrunc 2>/dev/null
expect_error ".glb with a huge chunk length" chunk.glb "not a JSON chunk within the file"
# a PLY header cut inside a property line, found by fuzz_mesh: assimp 5.2 reads past it and
# crashes (SIGSEGV); clwhitted's guard turns that into an error (a fixed assimp may refuse
# it in its own words)
expect_error "a PLY that crashes assimp" "$M/bad/assimp-crash.ply" "cannot read the mesh"
printf 'v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n' >nan.obj
expect_error "NaN vertex (OBJ)" nan.obj "vertex 2 is not finite"
printf 'v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n' >inf.obj
expect_error "infinite vertex (OBJ)" inf.obj "vertex 2 is not finite"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n' >nan.ply
expect_error "NaN vertex (PLY)" nan.ply "vertex 2 is not finite"
: >empty.obj
expect_error "empty OBJ" empty.obj "empty"
: >empty.glb
expect_error "empty .glb" empty.glb "empty"
: >empty.stl
expect_error "empty STL" empty.stl "empty"
mkdir dir.ply
expect_error "a directory" dir.ply "is a directory"
expect_error "a missing file" missing.stl "No such file"
printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n' >flat.obj
expect_error "only degenerate triangles" flat.obj "no triangles (1 degenerate"
printf 'v 0 0 0\nv 1 0 0\nl 1 2\n' >line.obj
expect_error "lines only" line.obj "no triangles"
# a missing MTL: a warning, the default material, an image
printf 'mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n' >nomtl.obj
run nomtl.obj
if [ $rc -ne 0 ] || [ "$(cat "$T/ls")" != out.png ]; then
    bad "missing MTL: exit $rc, expected 0 and an image" "$T/err"
elif ! grep -q "^clwhitted: warning: nomtl.obj: material library 'nowhere.mtl' not found" "$T/err"; then
    bad "missing MTL: no warning" "$T/err"
else
    ok
fi
# textures: one warning for the file, however many triangles and materials
run "$MODELS/OBJ/spider.obj"
if [ -d "$MODELS" ] && [ "$(grep -c 'textures are not part of the model' "$T/err")" -ne 1 ]; then
    bad "textures: expected one warning" "$T/err"
else
    ok
fi
cd "$OLDPWD"

# ---- every test model of assimp-testmodels ----------------------------------------------
if [ ! -d "$MODELS" ]; then
    echo "meshes.sh: $MODELS not found (Debian's assimp-testmodels): the sweep is skipped"
else
    find "$MODELS" -type f \( -iname '*.obj' -o -iname '*.ply' -o -iname '*.gltf' \
        -o -iname '*.glb' -o -iname '*.stl' \) | LC_ALL=C sort >"$T/list"
    : >"$T/tally"
    while read -r f; do
        ext=$(echo "${f##*.}" | tr 'A-Z' 'a-z')
        run "$f"
        if [ $rc -eq 0 ] && ! sanitizer_report && [ "$(cat "$T/ls")" = out.png ] &&
            "$B/imgtool" info "$T/o/out.png" >/dev/null 2>&1 && [ ! -s "$T/out" ]; then
            echo "$ext rendered" >>"$T/tally"
            ok
        elif [ $rc -eq 1 ] && ! sanitizer_report && [ ! -s "$T/ls" ] && [ ! -s "$T/out" ] &&
            [ "$(wc -l <"$T/err")" -eq 1 ] && grep -q -- "^clwhitted: $f: " "$T/err"; then
            echo "$ext refused" >>"$T/tally"
            echo "  refused ${f#"$MODELS"/}: $(sed "s|^clwhitted: $f: ||" "$T/err" | cut -c1-100)"
            ok
        else
            echo "$ext broken" >>"$T/tally"
            bad "${f#"$MODELS"/}: exit $rc (a signal, a sanitizer report, output on stdout, a bad image or an image left behind)" "$T/err"
        fi
    done <"$T/list"
    echo "meshes.sh: assimp-testmodels sweep: $(grep -c rendered "$T/tally") rendered," \
        "$(grep -c refused "$T/tally") refused, $(grep -c broken "$T/tally") broken" \
        "of $(wc -l <"$T/list") files"
    for ext in obj ply gltf glb stl; do
        echo "  $ext: $(grep -c "^$ext rendered" "$T/tally") rendered," \
            "$(grep -c "^$ext refused" "$T/tally") refused"
    done
    [ "$(wc -l <"$T/list")" -ge 50 ] || bad "the sweep found only $(wc -l <"$T/list") files"
fi

echo "meshes.sh: $pass passed, $fails failed"
[ $fails -eq 0 ]
