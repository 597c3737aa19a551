#!/bin/sh
# The build: header dependencies are complete (for every header, `make -n -W HEADER` rebuilds
# every object, test and the embedded kernel source that include it, as the compiler itself
# reports with -MM), and the installed binary holds no test-only or tool-only code.
# Usage, from the repository root after a build: sh tests/build.sh BUILD_DIR
set -u
B=${1:-build}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0
check_true() { # check_true NAME COMMAND...
    n=$1; shift
    if "$@"; then pass=$((pass + 1)); else echo "FAIL: $n"; fails=$((fails + 1)); fi
}
# An independent make (not the jobserver of a `make test` that runs this script).
mk() { MAKEFLAGS= MFLAGS= make -s "$@"; }

CPP="cc -D_POSIX_C_SOURCE=200809L -DCL_TARGET_OPENCL_VERSION=120 -Ihost -Ikernels -Itests -I$B $(pkg-config --cflags libpng libcjson OpenEXR glfw3 x11 2>/dev/null)"
# Which files include which headers, by the compiler: one line "TARGET: deps..." per source.
# clwhitted-mpi's sources need mpi.h: mpicc's, where clwhitted-mpi is built.
MPICPP="OMPI_CC=cc mpicc ${CPP#cc }"
mpi_target=
[ -x "$B/clwhitted-mpi" ] && mpi_target="$B/clwhitted-mpi"
for f in host/*.c tests/test_*.c; do
    cpp=$CPP
    case $f in
        host/mpi_*) [ -n "$mpi_target" ] || continue
            t="$B/$(basename "$f" .c).o"; cpp="env $MPICPP" ;;
        host/*) t="$B/$(basename "$f" .c).o" ;;
        tests/*) t="$B/$(basename "$f" .c)" ;;
    esac
    # shellcheck disable=SC2086
    deps=$($cpp -MM "$f" 2>/dev/null | tr -d '\\\n' | cut -d: -f2)
    echo "$t: $deps" >>"$T/deps"
done
# The kernel program: kernels/clwhitted.cl and every header it includes, as OpenCL C.
# shellcheck disable=SC2086
kdeps=$(cc -x c -D__OPENCL_VERSION__=120 -Ikernels -MM kernels/clwhitted.cl 2>/dev/null |
    tr -d '\\\n' | cut -d: -f2)
echo "$B/kernels_src.c: $kdeps" >>"$T/deps"
check_true "dependencies found" test "$(wc -l <"$T/deps")" -gt 20

targets="$B/clwhitted $mpi_target $(ls tests/test_*.c | sed "s|tests/\(.*\)\.c|$B/\1|")"
for h in host/*.h kernels/*.h; do
    # shellcheck disable=SC2086
    mk BUILD="$B" -n -W "$h" $targets >"$T/plan" 2>&1
    missing=
    for t in $(grep -F " $h" "$T/deps" | cut -d: -f1); do
        case $t in
            *.o) grep -q -- "-o $t\$" "$T/plan" || missing="$missing $t" ;;
            *kernels_src.c) grep -q "embed-kernels.sh" "$T/plan" || missing="$missing $t" ;;
            *) grep -q -- "-o $t\$" "$T/plan" || missing="$missing $t" ;;
        esac
    done
    check_true "touching $h rebuilds what includes it${missing:+ (not:$missing)}" test -z "$missing"
done

# The installed binary holds only what clwhitted uses: no test hooks, image comparison,
# image readers or the POV-Ray exporter (they live in the library for tests and tools).
nm "$B/clwhitted" >"$T/nm"
for sym in renderer_generate_rays renderer_intersect renderer_occluded renderer_build_options \
    image_compare image_write_diff image_read_exr image_read_png pov_write_scene; do
    check_true "clwhitted does not hold $sym" sh -c "! grep -q ' T $sym\$' '$T/nm'"
done
check_true "clwhitted holds the renderer" grep -q ' T renderer_render$' "$T/nm"

echo "build.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
