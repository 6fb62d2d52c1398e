# tests/lib.sh - the harness the CLI test scripts (tests/*.sh) share; not a
# suite itself (tests/run_all passes it over). POSIX sh. A script runs as
#
#   . "$(dirname "$0")/lib.sh"
#   suite_begin NAME "${1:-build/mechc}"
#   ...checks...
#   suite_end
#
# which finds this file from any working folder.
#
#   suite_begin NAME MECHC  NAME names the suite in messages and in the
#                  closing line. Sets $mechc (MECHC made absolute; exit 2
#                  when it is not an executable), $root (the repository),
#                  $ex (its examples) and $tmp (a folder of its own, removed
#                  at exit: the only place a test writes to).
#   check DESC COMMAND...  runs COMMAND and counts it passed or failed.
#   ok, bad DESC   count a pass, or a failure said on stderr as "FAIL: DESC"
#                  with the first $err_shown (6) lines of $tmp/err.
#   skip WHY       says on stderr what is not checked, and why.
#   have TOOL      TOOL is on the PATH.
#   run_mechc ARGS...  runs mechc ARGS: stdout in $tmp/out, stderr in
#                  $tmp/err, the exit status in $rc; killed after
#                  $mechc_timeout seconds when that is set and `timeout`
#                  exists. `run` is the same unless the script redefines it.
#   status_is N, out_empty, out_has TEXT, out_lines N, err_empty,
#   err_has TEXT (fixed string), err_lacks TEXT, err_matches REGEX (grep's
#                  basic regex):
#                  predicates on the last run.
#   file_has FILE TEXT  a line of FILE holds the fixed string TEXT (grep -F).
#   py ARGS...     python3 ARGS: the interpreter python3 names, found at the
#                  first call and then started directly (a version manager's
#                  shim, pyenv's, costs ten times the interpreter's start).
#   csv_value_at T NAME FILE  the value of CSV column NAME in FILE's row
#                  whose t (first column) is T; nothing when there is none.
#   suite_end      prints "NAME: N passed, M failed" (CI reads these lines)
#                  and fails when M is not 0: the script's last command.

# shellcheck shell=sh

suite_begin() {
    suite=$1
    mechc=$2
    case $mechc in
        /*) ;;
        *) mechc=$(pwd)/$mechc ;;
    esac
    if [ ! -x "$mechc" ]; then
        echo "$suite: $mechc is not an executable" >&2
        exit 2
    fi
    root=$(cd "$(dirname "$0")/.." && pwd)
    # shellcheck disable=SC2034 # for the scripts
    ex=$root/examples
    tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_$suite.XXXXXX") || exit 2
    trap 'rm -rf "$tmp"' EXIT
    trap 'exit 2' INT TERM HUP
    pass=0
    fail=0
}

err_shown=6
mechc_timeout=

ok() { pass=$((pass + 1)); }

bad() {
    fail=$((fail + 1))
    echo "FAIL: $1" >&2
    if [ -s "$tmp/err" ]; then
        echo "  stderr was:" >&2
        sed -n "1,${err_shown}s/^/    /p" "$tmp/err" >&2
    fi
}

check() {
    desc=$1
    shift
    if "$@"; then ok; else bad "$desc"; fi
}

skip() { echo "skip: $1" >&2; }

have() { command -v "$1" > /dev/null 2>&1; }

run_mechc() {
    if [ -n "$mechc_timeout" ] && have timeout; then
        timeout "$mechc_timeout" "$mechc" "$@" > "$tmp/out" 2> "$tmp/err"
    else
        "$mechc" "$@" > "$tmp/out" 2> "$tmp/err"
    fi
    rc=$?
}

run() { run_mechc "$@"; }

status_is() { [ "$rc" = "$1" ]; }
out_empty() { [ ! -s "$tmp/out" ]; }
out_has() { file_has "$tmp/out" "$1"; }
out_lines() { [ "$(wc -l < "$tmp/out")" = "$1" ]; }
err_empty() { [ ! -s "$tmp/err" ]; }
err_has() { file_has "$tmp/err" "$1"; }
err_lacks() { ! file_has "$tmp/err" "$1"; }

# file_has FILE TEXT: what `grep -F -q -- TEXT FILE` says, without its
# process for a short file: starting one costs 5 to 8 ms of CPU here, the
# shell's read of a 40-line file 2 to 4 ms (it reads a byte at a time, so
# a longer file, or TEXT of several lines, goes to grep).
file_has() {
    case $2 in *'
'*) grep -F -q -- "$2" "$1"; return ;; esac
    fh_lines=0
    while IFS= read -r fh_line || [ -n "$fh_line" ]; do
        case $fh_line in *"$2"*) return 0 ;; esac
        fh_lines=$((fh_lines + 1))
        if [ "$fh_lines" = 40 ]; then
            grep -F -q -- "$2" "$1"
            return
        fi
    done < "$1"
    return 1
}
err_matches() { grep -q -- "$1" "$tmp/err"; }

py() {
    if [ -z "${py_exe:-}" ]; then
        py_exe=$(python3 -c 'import sys; print(sys.executable)') && [ -x "$py_exe" ] || py_exe=python3
    fi
    "$py_exe" "$@"
}

csv_value_at() {
    awk -F, -v t="$1" -v name="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i; next }
                                    $1 == t && c { print $c }' "$3"
}

suite_end() {
    echo "$suite: $pass passed, $fail failed"
    [ "$fail" = 0 ]
}
