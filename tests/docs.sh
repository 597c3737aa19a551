#!/bin/sh
# The examples in README.md and docs/ work. Usage: tests/docs.sh BINARY [MARKDOWN...]
# (from the repository root; make test runs it on README.md and docs/**/*.md).
#
# Each Markdown file's fenced blocks are read in order, with a folder of their own where
# scenes/ and tests/ are the repository's and `clwhitted` and `build/clwhitted` are BINARY:
#   ```json NAME.json, ```nff NAME.nff
#       a scene, saved as NAME (default example-N.json / .nff) before any command of the
#       file runs, and rendered at 32x24: it must render. With the word `error` after the
#       name it must fail instead: exit status 1 and "clwhitted: NAME:LINE: ..." (show the
#       message in a ```console block).
#   ```sh
#       commands, one a line (`# comments`, `&&` chains, a leading `sudo`): clwhitted
#       commands run with -q -W 32 -H 24 appended and must succeed (--preview ones are not
#       run: no display); make commands must dry-run (make -n); others are not run.
#   ```console
#       `$ COMMAND` lines, run with sh; the lines after each, up to the next `$ `, must be
#       exactly what it prints (stdout and stderr together).
#   anything else (```text, ```c, indented blocks) is not checked.
# Relative links ([text](path)) must lead to files or folders.
set -u
BIN=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
shift
ROOT=$(pwd)
if [ $# -eq 0 ]; then
    set -- README.md docs/*.md docs/*/*.md
fi
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass=0
notrun=0
scenes=0
commands=0

ok() { pass=$((pass + 1)); }
fail() { # fail WHERE WHAT [FILE_TO_SHOW]
    echo "FAIL: $1: $2"
    [ $# -lt 3 ] || sed 's/^/    /' "$3"
    fails=$((fails + 1))
}

mkdir -p "$T/bin"
ln -s "$BIN" "$T/bin/clwhitted"
PATH="$T/bin:$PATH"
export PATH
unset CLWHITTED_PROGRESS

# Splits a Markdown file into $2/NNN.info ("LINE INFO-STRING") and $2/NNN.body.
split_blocks() {
    awk -v out="$2" '
        function strip(s, n) { while (n > 0 && substr(s, 1, 1) == " ") { s = substr(s, 2); n-- } return s }
        !inb && match($0, /^ *```/) {
            ind = RLENGTH - 3; info = substr($0, RLENGTH + 1)
            sub(/^[ \t]+/, "", info); sub(/[ \t]+$/, "", info)
            n++; f = sprintf("%s/%03d", out, n); start = NR; inb = 1
            print NR " " info > (f ".info"); close(f ".info")
            printf "" > (f ".body")
            next
        }
        inb && /^ *```[ \t]*$/ { inb = 0; close(f ".body"); next }
        inb { print strip($0, ind) >> (f ".body") }
        END { if (inb) { print FILENAME ":" start ": unclosed code block" > "/dev/stderr"; exit 1 } }
    ' "$1"
}

# The command word of a shell command: the first word after VAR=value assignments.
command_word() {
    for w in $1; do
        case $w in [A-Za-z_]*=*) ;; *) echo "$w"; return ;; esac
    done
}

# run_sh WHERE COMMAND: one command of a ```sh block, in the scene folder $W.
run_sh() {
    where=$1 cmd=$2
    case $(command_word "$cmd") in
    clwhitted | build/clwhitted)
        commands=$((commands + 1))
        case " $cmd " in
        *" --preview "*) notrun=$((notrun + 1)); return ;;
        *" --help "* | *" --version "* | *" --list-devices "* | *" -h "*) full=$cmd ;;
        *) full="$cmd -q -W 32 -H 24" ;;
        esac
        if (cd "$W" && sh -c "$full") </dev/null >"$T/out" 2>&1; then ok; else
            fail "$where" "'$cmd' failed" "$T/out"
        fi
        ;;
    make)
        commands=$((commands + 1))
        if (cd "$ROOT" && env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL \
            sh -c "make -n -s ${cmd#make}") </dev/null >"$T/out" 2>&1; then ok; else
            fail "$where" "'$cmd' is not a working make command" "$T/out"
        fi
        ;;
    *) notrun=$((notrun + 1)) ;;
    esac
}

# run_console WHERE BODY: the $ commands of a ```console block and their output.
run_console() {
    where=$1
    awk -v out="$T/con" '
        /^\$ / { n++; print substr($0, 3) > (out "." n ".cmd"); close(out "." n ".cmd")
                 printf "" > (out "." n ".want"); next }
        n { print >> (out "." n ".want") }
        END { print n + 0 > (out ".count") }
    ' "$2"
    k=1
    while [ "$k" -le "$(cat "$T/con.count")" ]; do
        cmd=$(cat "$T/con.$k.cmd")
        commands=$((commands + 1))
        (cd "$W" && sh -c "$cmd") </dev/null >"$T/con.got" 2>&1
        if cmp -s "$T/con.$k.want" "$T/con.got"; then ok; else
            diff "$T/con.$k.want" "$T/con.got" >"$T/con.diff"
            fail "$where" "'$cmd' printed something else (< documented, > printed)" "$T/con.diff"
        fi
        k=$((k + 1))
    done
    rm -f "$T"/con.*
}

# The anchors of a Markdown file's headings, as GitHub makes them (outside code blocks).
anchors() {
    awk '/^ *```/ { code = !code; next }
         !code && /^#+ / {
             s = tolower($0); sub(/^#+ +/, "", s); gsub(/[^a-z0-9 _-]/, "", s); gsub(/ /, "-", s)
             print s
         }' "$1"
}

# check_links MD: every relative link of MD leads to a file or folder (and to a heading
# there, for a #anchor into a Markdown file).
check_links() {
    md=$1
    dir=$(dirname "$md")
    grep -n -o '\]([^)]*)' "$md" | sed 's/](\(.*\))$/ \1/; s/ "[^"]*"$//' >"$T/links"
    while read -r lineno target; do
        case $target in '' | http:* | https:* | mailto:*) continue ;; esac
        path=${target%%#*}
        anchor=
        case $target in *'#'*) anchor=${target#*#} ;; esac
        if [ -z "$path" ]; then
            file=$md
        else
            file=$(realpath -m --relative-to="$ROOT" "$ROOT/$dir/$path")
        fi
        if [ ! -e "$file" ]; then
            fail "$md:${lineno%:}" "the link '$target' leads nowhere"
            continue
        fi
        if [ -n "$anchor" ] && [ "${file%.md}" != "$file" ] && ! anchors "$file" | grep -qx -- "$anchor"
        then
            fail "$md:${lineno%:}" "the link '$target': no such heading in $file"
            continue
        fi
        ok
    done <"$T/links"
}

md_index=0
for md in "$@"; do
    [ -f "$md" ] || { fail "$md" "no such file"; continue; }
    check_links "$md"
    md_index=$((md_index + 1))
    B=$T/blocks/$md_index
    W=$T/work/$md_index
    mkdir -p "$B" "$W/build"
    ln -s "$ROOT/scenes" "$W/scenes"
    ln -s "$ROOT/tests" "$W/tests"
    ln -s "$BIN" "$W/build/clwhitted"
    if ! split_blocks "$md" "$B" 2>"$T/out"; then fail "$md" "cannot be read" "$T/out"; fi

    # The scenes first: commands may name scenes shown further down.
    for info in "$B"/*.info; do
        [ -f "$info" ] || continue
        set -- $(cat "$info")
        line=$1 lang=${2:-}
        case $lang in json | nff) ;; *) continue ;; esac
        n=$(basename "$info" .info)
        name=${3:-example-$n.$lang}
        case $name in error) name=example-$n.$lang ;; esac
        case $name in
        */* | .*) fail "$md:$line" "scene name '$name' must be a plain file name"; continue ;;
        esac
        cp "${info%.info}.body" "$W/$name"
    done

    for info in "$B"/*.info; do
        [ -f "$info" ] || continue
        body=${info%.info}.body
        n=$(basename "$info" .info)
        set -- $(cat "$info")
        line=$1 lang=${2:-}
        where=$md:$line
        case $lang in
        json | nff)
            scenes=$((scenes + 1))
            name=${3:-example-$n.$lang}
            expect=ok
            for w in "$@"; do [ "$w" = error ] && expect=error; done
            case $name in error) name=example-$n.$lang ;; esac
            (cd "$W" && "$BIN" -q -W 32 -H 24 -o "render-$n.png" "$name") >"$T/out" 2>&1
            rc=$?
            if [ $expect = ok ]; then
                if [ $rc -eq 0 ] && [ -s "$W/render-$n.png" ]; then ok; else
                    fail "$where" "the scene does not render (exit $rc)" "$T/out"
                fi
            elif [ $rc -eq 1 ] && grep -q "^clwhitted: $name:[0-9][0-9]*: " "$T/out" &&
                [ ! -e "$W/render-$n.png" ]; then
                ok
            else
                fail "$where" "the scene marked 'error' should fail with 'clwhitted: $name:LINE: ...' and exit status 1 (exit $rc)" "$T/out"
            fi
            ;;
        sh)
            k=0
            while IFS= read -r cmdline || [ -n "$cmdline" ]; do
                k=$((k + 1))
                cmdline=$(echo "$cmdline" | sed -e 's/^[[:space:]]*#.*$//' -e 's/[[:space:]]#.*$//')
                [ -n "$(echo "$cmdline" | tr -d '[:space:]')" ] || continue
                echo "$cmdline" | awk '{ n = split($0, a, "&&"); for (i = 1; i <= n; i++) print a[i] }' \
                    >"$T/parts"
                while IFS= read -r part; do
                    part=$(echo "$part" | sed -e 's/^[[:space:]]*//' -e 's/[[:space:]]*$//' -e 's/^sudo //')
                    run_sh "$md:$((line + k))" "$part"
                done <"$T/parts"
            done <"$body"
            ;;
        console)
            run_console "$where" "$body"
            ;;
        esac
    done
done
echo "docs.sh: $pass passed, $fails failed ($scenes scenes, $commands commands checked;" \
    "$notrun commands not run)"
[ "$fails" -eq 0 ]
