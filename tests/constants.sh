#!/bin/sh
# constants.sh - files whose constants a double (or, with --real float, a
# float) cannot hold: one file per case in tests/constants/, each saying in
# its comments what every command must do with it:
#
#   # expect: ARGS | STATUS | TEXT     mechc ARGS FILE exits STATUS and its
#                                      stderr holds TEXT (none when empty)
#
#   sh tests/constants.sh [MECHC]
. "$(dirname "$0")/lib.sh"
suite_begin constants "${1:-build/mechc}"

for f in "$root"/tests/constants/*.mech; do
    name=${f##*/}
    grep '^# expect: ' "$f" > "$tmp/expect"
    [ -s "$tmp/expect" ] || { bad "$name has no '# expect:' line"; continue; }
    while IFS='|' read -r args status text; do
        args=$(echo "${args#\# expect: }" | sed 's/ *$//')
        status=$(echo "$status" | tr -d ' ')
        text=$(echo "$text" | sed 's/^ //')
        # shellcheck disable=SC2086 # ARGS are words
        (cd "$root/tests/constants" && "$mechc" $args "$name" > "$tmp/out" 2> "$tmp/err")
        rc=$?
        if [ "$rc" != "$status" ]; then
            bad "mechc $args $name: exit $rc, not $status"
        elif [ -n "$text" ] && ! grep -qF -- "$text" "$tmp/err"; then
            bad "mechc $args $name: stderr lacks '$text'"
        elif [ "$status" = 0 ] && [ -s "$tmp/err" ]; then
            bad "mechc $args $name: exit 0 with a message"
        else
            ok
        fi
    done < "$tmp/expect"
done
suite_end
