#!/bin/sh
# tests/python.sh MECHC - the Python module's pytest suite (tests/python/),
# over the libmechc.so next to MECHC (build/libmechc.so), with Debian's
# interpreter ($MECHC_PYTHON, default /usr/bin/python3: the one that sees
# python3-numpy, python3-cffi and python3-pytest, which `.ci/deps python`
# installs). Where that interpreter or those packages are missing the suite
# says so on a "skip:" line and passes: the rest of make check stands.
#
#   sh tests/python.sh build/mechc
#
# The last line is "python: N passed, M failed"; the exit status is
# non-zero when a test fails.
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin python "${1:-build/mechc}"

py=${MECHC_PYTHON:-/usr/bin/python3}
so=$(dirname "$mechc")/libmechc.so
if [ ! -x "$py" ]; then
    skip "no $py: the Python module is not tested (install python3, or set MECHC_PYTHON)"
    suite_end; exit
fi
if ! "$py" -c 'import numpy, cffi, pytest' 2> "$tmp/err"; then
    skip "$py lacks NumPy, cffi or pytest ($(tail -n 1 "$tmp/err")): the Python module is not tested (sh .ci/deps python, as root)"
    suite_end; exit
fi
if [ ! -f "$so" ]; then
    skip "no $so: the Python module is not tested (make $so)"
    suite_end; exit
fi
# A sanitized library needs its runtime loaded first into the interpreter,
# which the sanitizer builds' interpreters are not: make check's plain build
# is the one the module is tested with.
if nm -D "$so" 2> /dev/null | grep -q '__asan_\|__ubsan_'; then
    skip "$so is built with a sanitizer: the Python module is tested by make check's plain build"
    suite_end; exit
fi

# No .pyc files or pytest cache in the tree; the library and the command
# are the build's.
PYTHONDONTWRITEBYTECODE=1 PYTHONPATH=$root/python MECHC_LIBRARY=$so MECHC=$mechc \
    "$py" -m pytest -q -p no:cacheprovider "$root/tests/python" > "$tmp/out" 2>&1
rc=$?
cat "$tmp/out"
# pytest's summary, "12 passed, 1 failed in 3.2s", as the harness's counts
summary=$(grep -E '[0-9]+ (passed|failed|error)' "$tmp/out" | tail -n 1)
pass=$(echo "$summary" | grep -oE '[0-9]+ passed' | cut -d' ' -f1)
fail=$(echo "$summary" | grep -oE '[0-9]+ (failed|errors?)' | awk '{ s += $1 } END { print s + 0 }')
pass=${pass:-0}
[ "$rc" != 0 ] && [ "$fail" = 0 ] && fail=1
suite_end
