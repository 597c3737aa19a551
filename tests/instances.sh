#!/bin/sh
# Meshes placed from JSON ("type": "mesh": a file, a transform, a material) and instances:
# a mesh placed several times is one copy on the device (--stats) and renders like its
# placements copied into world triangles (--flatten), on both strategies and the fast
# path; a placement renders like the same triangles transformed beforehand; the same file
# named two ways is read once; bad references fail with the JSON file and line.
# Usage: tests/instances.sh BUILD_DIR (with clwhitted and imgcmp in it)
set -u
B=$(cd "$1" && pwd)
BIN=$B/clwhitted
IMGCMP=$B/imgcmp
. "$(dirname "$0")/lib.sh"
D=tests/scenes/instances
mkdir -p build/test-output

# same NAME A.exr B.exr: imgcmp's default tolerance (a channel within 1e-3 on all but
# 0.5% of the pixels, mean difference of the others below 1e-4); a diff image on failure
same() {
    if "$IMGCMP" --diff "build/test-output/instances-$1-diff.png" "$2" "$3" >"$T/cmp" 2>&1; then
        ok
    else
        bad "$1: the images differ (build/test-output/instances-$1-diff.png)" "$T/cmp"
    fi
}

# 1. instanced against flattened, on each strategy and the fast path
for how in "pixel|--kernel pixel" "wavefront|--kernel wavefront" "fast|--precision fast"; do
    name=${how%%|*} opts=${how#*|}
    # shellcheck disable=SC2086
    "$BIN" -q --stats $opts -o "$T/i-$name.exr" $D/row.json >"$T/out" 2>"$T/err"
    check "$name: instanced render" 0 $?
    check_grep "$name: five placements of one mesh, its 80 triangles once" \
        "^scene: 0 spheres, 80 triangles, 1 polygon, 0 cones; 5 instances of 1 mesh;" "$T/out"
    # shellcheck disable=SC2086
    "$BIN" -q --stats --flatten $opts -o "$T/f-$name.exr" $D/row.json >"$T/out" 2>"$T/err"
    check "$name: flattened render" 0 $?
    check_grep "$name: --flatten copies them" \
        "^scene: 0 spheres, 400 triangles, 1 polygon, 0 cones; 0 instances of 0 meshes;" "$T/out"
    same "$name" "$T/f-$name.exr" "$T/i-$name.exr"
done

# 2. a placement renders like the mesh's triangles transformed beforehand (written as JSON
# triangles with their normals, in double precision)
python3 - "$D/gem.ply" "$T/pre.json" "$T/placed.json" <<'PY'
import json, math, sys
ply, pre, placed = sys.argv[1:4]
lines = open(ply).read().split("\n")
nv = int([l for l in lines if l.startswith("element vertex")][0].split()[2])
nf = int([l for l in lines if l.startswith("element face")][0].split()[2])
body = lines[lines.index("end_header") + 1:]
verts = [list(map(float, l.split())) for l in body[:nv]]
faces = [list(map(int, l.split()))[1:] for l in body[nv:nv + nf]]
# scale (1.3, 0.7, 1), rotate 40 degrees about y, translate (-0.5, 0, 0.3)
c, s = math.cos(math.radians(40)), math.sin(math.radians(40))
A = [[c * 1.3, 0, s * 1.0], [0, 0.7, 0], [-s * 1.3, 0, c * 1.0]]
t = [-0.5, 0, 0.3]
det = (A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0])
       + A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]))
inv = [[(A[(j + 1) % 3][(i + 1) % 3] * A[(j + 2) % 3][(i + 2) % 3] - A[(j + 1) % 3][(i + 2) % 3] * A[(j + 2) % 3][(i + 1) % 3]) / det
        for j in range(3)] for i in range(3)]
def point(p):
    return [sum(A[r][k] * p[k] for k in range(3)) + t[r] for r in range(3)]
def normal(n):
    v = [sum(inv[k][r] * n[k] for k in range(3)) for r in range(3)]
    l = math.sqrt(sum(x * x for x in v))
    return [x / l for x in v]
scene = {
    "image": {"width": 120, "height": 90}, "ambient": 0.1,
    "camera": {"eye": [0, 2, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
    "materials": {"m": {"ka": [0.6, 0.3, 0.2], "kd": [0.6, 0.3, 0.2], "ks": 0.4, "p": 30}},
    "lights": [{"position": [-4, 6, 5], "intensity": 0.8}],
}
tris = [{"type": "triangle", "material": "m",
         "vertices": [point(verts[i][:3]) for i in f],
         "normals": [normal(verts[i][3:6]) for i in f]} for f in faces]
json.dump(dict(scene, objects=tris), open(pre, "w"))
mesh = {"type": "mesh", "file": "GEM", "material": "m",
        "transform": [{"scale": [1.3, 0.7, 1]}, {"rotate": {"axis": [0, 1, 0], "degrees": 40}},
                      {"translate": t}]}
json.dump(dict(scene, objects=[mesh]), open(placed, "w"))
PY
check "the transformed copy is written" 0 $?
sed -i "s|\"GEM\"|\"$(pwd)/$D/gem.ply\"|" "$T/placed.json"
"$BIN" -q -o "$T/pre.exr" "$T/pre.json" 2>"$T/err"
check "the triangles transformed beforehand" 0 $?
"$BIN" -q -o "$T/placed.exr" "$T/placed.json" 2>"$T/err"
check "the mesh placed with the transform" 0 $?
same "placed-like-transformed" "$T/pre.exr" "$T/placed.exr"

# 3. the same file named two ways is one mesh; a file placed once is plain triangles
cp $D/gem.ply "$T/gem.ply"
cat >"$T/two.json" <<JSON
{"camera": {"eye": [0, 2, 6], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
 "materials": {"m": {"kd": 0.7}}, "lights": [{"position": [3, 5, 4], "intensity": 1}],
 "objects": [{"type": "mesh", "file": "gem.ply"},
             {"type": "mesh", "file": "./gem.ply", "transform": {"translate": [2, 0, 0]}},
             {"type": "mesh", "file": "$T/gem.ply", "transform": {"translate": [-2, 0, 0]}}]}
JSON
"$BIN" -q --stats -W 32 -H 24 -o "$T/two.png" "$T/two.json" >"$T/out" 2>"$T/err"
check "one file named three ways" 0 $?
check_grep "one file named three ways: one mesh" "; 3 instances of 1 mesh;" "$T/out"
cat >"$T/one.json" <<JSON
{"camera": {"eye": [0, 2, 6], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
 "materials": {"m": {"kd": 0.7}}, "lights": [{"position": [3, 5, 4], "intensity": 1}],
 "objects": [{"type": "mesh", "file": "gem.ply", "transform": {"translate": [1, 0, 0]}}]}
JSON
"$BIN" -q --stats -W 32 -H 24 -o "$T/one.png" "$T/one.json" >"$T/out" 2>"$T/err"
check "placed once" 0 $?
check_grep "placed once: plain triangles" "^scene: 0 spheres, 80 triangles, 0 polygons, 0 cones; 0 instances of 0 meshes;" "$T/out"

# 4. bad references: the JSON file and line, exit 1, no image
bad_scene() { # bad_scene NAME OBJECT PATTERN
    cat >"$T/bad.json" <<JSON
{"camera": {"eye": [0, 2, 6], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
 "materials": {"m": {"kd": 0.7}},
 "objects": [
  $2
 ]}
JSON
    rm -f "$T/bad.png"
    "$BIN" -q -W 8 -H 6 -o "$T/bad.png" "$T/bad.json" >"$T/out" 2>"$T/err"
    check "$1" 1 $?
    check_grep "$1: the message" "$3" "$T/err"
    if [ -e "$T/bad.png" ]; then bad "$1: an image was written"; else ok; fi
}
bad_scene "a missing mesh file" '{"type": "mesh", "file": "nope.ply"}' \
    "bad.json:4: objects\[0\].file \"nope.ply\": No such file or directory"
echo "not a mesh" >"$T/text.ply"
bad_scene "a file that is not a mesh" '{"type": "mesh", "file": "text.ply"}' \
    "bad.json:4: objects\[0\].file \"text.ply\": .*text.ply"
bad_scene "a mesh without a file" '{"type": "mesh"}' "bad.json:4: objects\[0\]: missing \"file\""
bad_scene "an unknown material" '{"type": "mesh", "file": "gem.ply", "material": "x"}' \
    "bad.json:4: objects\[0\].material: no material named \"x\""
bad_scene "a singular transform" '{"type": "mesh", "file": "gem.ply", "transform": {"scale": [1, 0, 1]}}' \
    "bad.json:4: objects\[0\].transform"
bad_scene "an unknown key" '{"type": "mesh", "file": "gem.ply", "scale": 2}' "bad.json:4: .*scale"

echo "instances.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
