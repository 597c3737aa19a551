# Shared by the shell tests (sourced after `B` and `BIN` are set): a scratch folder $T
# removed on exit, the pass and fail counters, progress output off, and the checks.
# BAD_LINES (default: all) caps the lines of a FILE that bad shows.
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0
export CLWHITTED_PROGRESS=never

ok() { pass=$((pass + 1)); }
bad() { # bad NAME [FILE to show]
    echo "FAIL: $1"
    [ $# -gt 1 ] && [ -f "$2" ] && sed 's/^/    /' "$2" | head -n "${BAD_LINES:-1000000}"
    fails=$((fails + 1))
}
check() { # check NAME EXPECTED_RC ACTUAL_RC
    if [ "$2" -eq "$3" ]; then ok; else bad "$1: exit $3, expected $2" "$T/err"; fi
}
check_grep() { # check_grep NAME PATTERN FILE
    if grep -q -- "$2" "$3"; then ok; else bad "$1: '$2' not in:" "$3"; fi
}
