#!/bin/sh
# Smoke test of tools/quality-report: its FLIP against NVIDIA's reference values, then a
# two-setting grid on the default scene at 32x24 (the second setting is the reference itself).
# Usage: tests/quality.sh CLWHITTED IMGTOOL   (from the repository root)
set -u
BIN=$1
IMGTOOL=$2
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0

ok() { pass=$((pass + 1)); }
fail() { echo "FAIL: $1"; fails=$((fails + 1)); }

if tools/quality-report --self-test >"$T/self" 2>&1; then ok; else
    fail "quality-report --self-test"; sed 's/^/    /' "$T/self"; fi

# imgtool: usage errors and unreadable input
"$IMGTOOL" >/dev/null 2>&1
if [ $? -eq 2 ]; then ok; else fail "imgtool without arguments: exit 2 expected"; fi
"$IMGTOOL" raw "$T/missing.exr" "$T/x.f32" >/dev/null 2>&1
if [ $? -eq 1 ]; then ok; else fail "imgtool on a missing file: exit 1 expected"; fi

tools/quality-report --clwhitted "$BIN" --imgtool "$IMGTOOL" -o "$T/q" -W 32 -H 24 \
    --spp 4 --depth 1,5 --precision robust --ref-spp 4 --ref-depth 5 --repeat 1 \
    --figure "$T/all.png" --table "$T/all.md" scenes/default.json >"$T/out" 2>"$T/err"
rc=$?
if [ $rc -eq 0 ]; then ok; else fail "quality-report exit $rc"; sed 's/^/    /' "$T/err"; fi
CSV=$T/q/default/quality.csv
for f in "$CSV" "$T/q/default/quality.png" "$T/q/default/reference.exr" "$T/all.png" \
    "$T/all.md"; do
    if [ -s "$f" ]; then ok; else fail "quality-report wrote no $(basename "$f")"; fi
done
if [ -s "$CSV" ]; then
    # header + one row per setting, in grid order
    if [ "$(wc -l <"$CSV")" -eq 3 ]; then ok; else fail "CSV: 3 lines expected"; cat "$CSV"; fi
    if head -1 "$CSV" | grep -q '^scene,setting,spp,depth,precision,.*wall_s,render_s,.*rmse,.*flip'
    then ok; else fail "CSV header"; head -1 "$CSV"; fi
    # the reference's own setting: rendering is deterministic, so no error at all
    if awk -F, 'NR > 1 && $2 == "spp4-d5-robust" && $12 == 0 && $13 == 0 && $14 == 0 { n++ }
                END { exit n != 1 }' "$CSV"; then ok; else
        fail "the reference setting against the reference: RMSE and FLIP 0 expected"; cat "$CSV"; fi
    # depth 1: no mirror bounces, so an error, and a larger one than the reference's
    if awk -F, 'NR > 1 && $2 == "spp4-d1-robust" && $12 > 1e-4 && $14 > 1e-3 && $9 > 0 { n++ }
                END { exit n != 1 }' "$CSV"; then ok; else
        fail "depth 1 against the reference: RMSE and FLIP > 0 expected"; cat "$CSV"; fi
    # clwhitted's own render and setup times were read from its summary line
    if awk -F, 'NR > 1 && $10 + 0 > 0 && $11 + 0 > 0 { n++ } END { exit n != 2 }' "$CSV"
    then ok; else fail "CSV: render_s and setup_s > 0 expected in every row"; cat "$CSV"; fi
    # the error-free setting is on both Pareto fronts
    if awk -F, 'NR > 1 && $2 == "spp4-d5-robust" && $15 == 1 && $16 == 1 { n++ }
                END { exit n != 1 }' "$CSV"; then ok; else fail "Pareto flags"; cat "$CSV"; fi
fi
if grep -q '^| 4 | 1 | robust |' "$T/out"; then ok; else fail "table not printed"; cat "$T/out"; fi
if [ "$(head -n 1 "$T/all.md" 2>/dev/null)" = "# Speed against error: the measurements" ] &&
    grep -q '^| 4 | 1 | robust |' "$T/all.md"; then ok; else
    fail "--table: a title and the table expected"; cat "$T/all.md"; fi

# bad input: exit 1 or 2 with a message
tools/quality-report --clwhitted "$BIN" --imgtool "$IMGTOOL" -o "$T/q" "$T/missing.nff" \
    >"$T/out" 2>"$T/err"
if [ $? -eq 1 ] && grep -q "no such scene" "$T/err"; then ok; else fail "missing scene"; fi
tools/quality-report --spp 0 scenes/default.json >"$T/out" 2>"$T/err"
if [ $? -eq 2 ]; then ok; else fail "--spp 0: usage error expected"; fi
# no option rewrites a file in place (the README's table is gone)
tools/quality-report --readme README.md scenes/default.json >"$T/out" 2>"$T/err"
if [ $? -eq 2 ]; then ok; else fail "--readme: usage error expected"; fi

# make quality writes into build/quality/; the tracked docs/quality/ only with UPDATE_DOCS=1,
# and never README.md (what make would run, without running it)
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u UPDATE_DOCS make -n quality >"$T/out" 2>&1
if [ $? -eq 0 ] && grep -q -- '-o build/quality --figure build/quality/quality.png' "$T/out" &&
    ! grep -q -e 'docs/' -e 'README' "$T/out"; then ok; else
    fail "make quality: build/quality/ only expected"; sed 's/^/    /' "$T/out"; fi
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u UPDATE_DOCS make -n quality UPDATE_DOCS=1 >"$T/out" 2>&1
if [ $? -eq 0 ] &&
    grep -q '^cp build/quality/quality.png build/quality/quality.md docs/quality/$' "$T/out" &&
    ! grep -q 'README' "$T/out"; then ok; else
    fail "make quality UPDATE_DOCS=1: a copy into docs/quality/ expected"
    sed 's/^/    /' "$T/out"
fi

echo "quality.sh: $pass passed, $fails failed"
[ $fails -eq 0 ]
