#!/bin/sh
# fuzz_dict.sh - every keyword of the .mech format is in the fuzzer's
# dictionary, tests/fuzz/mech.dict: the statement keywords of
# generator/parse/joints.def, the functions of generator/dag/ops.def, the
# dynamics keywords and keys of generator/parse/ast.c, the words the parser
# matches (lex_is_word, its words[] and keys[] tables), the member names
# and units of the model. A keyword added there and not to the dictionary
# fails here.
#
#   sh tests/fuzz_dict.sh [MECHC]     (MECHC is not used: run_all passes it)
#
# POSIX sh, grep and sed only.
set -u
cd "$(dirname "$0")/.." || exit 1
dict=tests/fuzz/mech.dict

literals() { grep -o '"[^"]*"' | tr -d '"'; }

keywords() {
    grep '^X(' generator/parse/joints.def | grep -v DIM_INTERNAL | sed 's/^X([A-Z_]*, *"\([^"]*\)".*/\1/'
    grep '^X(' generator/dag/ops.def | grep -v 'NULL)' | sed 's/^X([A-Z0-9_]*, *"\([^"]*\)".*/\1/'
    sed -n '/^const char \*const dyn_/,/^};/p' generator/parse/ast.c | literals
    cat generator/parse/*.c | grep -o 'lex_is_word([^;]*"[^"]*")' | literals
    grep -h 'static const char \*const \(words\|keys\)\[' generator/parse/*.c | sed 's/^[^{]*{//' | literals
    grep -h 'static const char \*const \(names\|suffix\|word\|diag_names\)\[[0-9]*\] = {' \
        generator/model/*.c | sed 's/^[^{]*{//' | literals
    sed -n '/units\[[0-9]*\] = {/,/^};/p' generator/model/*.c | grep '^ *{"' | sed 's/^ *{"\([^"]*\)".*/\1/'
}

words=$(keywords | sort -u)
count=$(echo "$words" | wc -l)
missing=""
set -f      # a word like * must not expand
for w in $words; do
    grep -q "^[A-Za-z0-9_]*=\"$w\"\$" "$dict" || missing="$missing $w"
done
if [ "$count" -lt 80 ]; then
    echo "FAIL fuzz_dict: only $count keywords found in the sources (did a table move?)"
    exit 1
fi
if [ -n "$missing" ]; then
    echo "FAIL fuzz_dict: keywords missing from $dict:$missing"
    exit 1
fi
echo "PASS fuzz_dict: all $count keywords of the format are in $dict"
