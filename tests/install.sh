#!/bin/sh
# make install / make uninstall: the installed clwhitted renders from any folder (it reads
# nothing relative to the current folder), and uninstall removes what install put there.
# Usage, from the repository root: sh tests/install.sh
set -u
ROOT=$(pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0

check() { # check NAME EXPECTED_RC ACTUAL_RC [LOG]
    if [ "$2" -eq "$3" ]; then pass=$((pass + 1)); else
        echo "FAIL: $1: exit $3, expected $2"; [ -n "${4:-}" ] && sed 's/^/    /' "$4"
        fails=$((fails + 1)); fi
}
check_true() { # check_true NAME COMMAND...
    n=$1; shift
    if "$@"; then pass=$((pass + 1)); else echo "FAIL: $n"; fails=$((fails + 1)); fi
}
# An independent make (not the jobserver of a `make test` that runs this script).
mk() { MAKEFLAGS= MFLAGS= make -s -C "$ROOT" "$@"; }

PREFIX=/opt/clwhitted-test
DEST=$T/stage
BIN=$DEST$PREFIX/bin/clwhitted
MAN=$DEST$PREFIX/share/man/man1/clwhitted.1

mk install PREFIX=$PREFIX DESTDIR="$DEST" >"$T/log" 2>&1; check "make install" 0 $? "$T/log"
check_true "binary installed in PREFIX/bin" test -x "$BIN"
check_true "clwhitted-imgtool installed in PREFIX/bin" test -x "$DEST$PREFIX/bin/clwhitted-imgtool"
check_true "man page installed in PREFIX/share/man/man1" test -s "$MAN"
check_true "nothing else installed" test "$(find "$DEST" -type f | wc -l)" -eq 3

# Render from another folder, one holding decoy kernel sources that break the build if
# they were read: the installed binary must use the ones embedded in it.
mkdir -p "$T/elsewhere/kernels"
for f in "$ROOT"/kernels/*; do echo '#error decoy kernel source read from the current folder' \
    >"$T/elsewhere/kernels/$(basename "$f")"; done
cp "$ROOT/scenes/default.json" "$T/elsewhere/scene.json"
cd "$T/elsewhere" || exit 1
"$BIN" -q -W 32 -H 24 -o out.png scene.json >"$T/log" 2>&1; check "installed render (relative scene)" 0 $? "$T/log"
check_true "PNG written" sh -c "head -c 8 out.png | od -An -c | grep -q 'P   N   G'"
"$BIN" -q -W 16 -H 12 -o "$T/abs.exr" "$ROOT/scenes/default.json" >"$T/log" 2>&1
check "installed render (absolute scene, EXR)" 0 $? "$T/log"
check_true "EXR written" test -s "$T/abs.exr"
"$BIN" --version >"$T/log" 2>&1; check "installed --version" 0 $? "$T/log"
check_true "version printed" grep -q '^clwhitted [0-9]' "$T/log"
(PATH="$DEST$PREFIX/bin:$PATH" clwhitted --help) >"$T/log" 2>&1; check "clwhitted on the PATH" 0 $? "$T/log"
"$DEST$PREFIX/bin/clwhitted-imgtool" convert --exposure 1 "$T/abs.exr" "$T/abs.png" >"$T/log" 2>&1
check "installed clwhitted-imgtool re-exposes an EXR" 0 $? "$T/log"
cd "$ROOT" || exit 1

mk uninstall PREFIX=$PREFIX DESTDIR="$DEST" >"$T/log" 2>&1; check "make uninstall" 0 $? "$T/log"
check_true "binary removed" test ! -e "$BIN"
check_true "clwhitted-imgtool removed" test ! -e "$DEST$PREFIX/bin/clwhitted-imgtool"
check_true "man page removed" test ! -e "$MAN"
check_true "no files left" test "$(find "$DEST" -type f | wc -l)" -eq 0

# BINDIR and MANDIR override PREFIX's folders
mk install DESTDIR="$DEST" BINDIR=/tools MANDIR=/manuals >"$T/log" 2>&1; check "install BINDIR MANDIR" 0 $? "$T/log"
check_true "binary in BINDIR" test -x "$DEST/tools/clwhitted"
check_true "man page in MANDIR/man1" test -s "$DEST/manuals/man1/clwhitted.1"
mk uninstall DESTDIR="$DEST" BINDIR=/tools MANDIR=/manuals >"$T/log" 2>&1; check "uninstall BINDIR MANDIR" 0 $? "$T/log"
check_true "all removed" test "$(find "$DEST" -type f | wc -l)" -eq 0

# The packages: make render installs the build and run-time part only, make test the rest;
# the parts do not overlap, the development tools are not in the run-time part, and
# docs/testing.md lists both exactly.
sh tools/install-deps --runtime --list >"$T/runtime" && sh tools/install-deps --dev --list >"$T/dev"
check "install-deps --list" 0 $?
for p in povray oclgrind clang clang-format xvfb python3-matplotlib libembree-dev libcmocka-dev; do
    check_true "$p is not a run-time package" sh -c "! grep -qx '$p' '$T/runtime'"
    check_true "$p is a development package" grep -qx "$p" "$T/dev"
done
check_true "the parts do not overlap" test -z "$(sort "$T/runtime" "$T/dev" | uniq -d)"
check_true "no option: both parts" test "$(sh tools/install-deps --list | sort)" = "$(sort "$T/runtime" "$T/dev")"
mk -n render >"$T/plan" 2>&1
check_true "make render installs the run-time part only" sh -c "grep -q 'install-deps --runtime' '$T/plan' && ! grep -q 'install-deps --dev' '$T/plan'"
mk -n test >"$T/plan" 2>&1
check_true "make test installs the development part" grep -q 'install-deps --dev' "$T/plan"
for part in runtime dev; do
    sed -n "/^<!-- $part packages -->/,/^<!-- end -->/p" "$ROOT/docs/testing.md" >"$T/listed"
    for p in $(cat "$T/$part"); do
        check_true "docs/testing.md lists $p ($part)" grep -qF "\`$p\`" "$T/listed"
    done
done

echo "install.sh: $pass passed, $fails failed"
[ "$fails" -eq 0 ]
