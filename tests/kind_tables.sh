#!/bin/sh
# tests/kind_tables.sh MECHC - a kind is a table row plus its maths: a row
# added to generator/parse/joints.def or forces.def without its builder or
# formulas fails the build, naming what is missing. Copies generator/ to a
# temporary folder, adds the rows there and compiles (syntax only) the one
# file that dispatches each table: a second or so, no mechc run.
#
#   sh tests/kind_tables.sh build/mechc
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin kind_tables "${1:-build/mechc}"

cc=${CC:-cc}
if ! have "$cc"; then
    skip "no C compiler ($cc)"
    suite_end
    exit
fi
tree=$tmp/tree
mkdir -p "$tree"
cp -R "$root/generator" "$tree/"

# compiles FILE (under generator/) with the tool's language and switch
# warnings; its messages in $tmp/err
compiles() {
    "$cc" -std=c11 -D_DEFAULT_SOURCE -Wall -Werror=switch -fsyntax-only \
        "$tree/generator/$1" 2> "$tmp/err"
}

# fails_naming FILE NAME: the compile fails and says NAME
fails_naming() {
    ! compiles "$1" && grep -q "$2" "$tmp/err"
}

tables="model/joints.c eval/generic_joints.c diff/dynamics.c eval/generic_dynamics.c model/dynamics.c"
for f in $tables; do
    check "$f compiles as it is" compiles "$f"
done

# A spatial joint kind: the row alone, no lower_S_KNOT, no formula_S_KNOT.
echo 'X(S_KNOT, "knot", DIM_SPATIAL, 2, ATTACH_ANY, ATTACH_ANY, 0, OPTION_NONE, 1, LEVEL_POSITION, "")' \
    >> "$tree/generator/parse/joints.def"
check "a spatial kind without its builder: joints.c names lower_S_KNOT" \
    fails_naming model/joints.c "lower_S_KNOT"
check "a spatial kind without its formulas: generic_joints.c names formula_S_KNOT" \
    fails_naming eval/generic_joints.c "formula_S_KNOT"

# A force element: the row alone, no add_TWIST, no apply_TWIST, no build_TWIST.
echo 'X(TWIST, "twist", 1, 1, 1, 0)' >> "$tree/generator/parse/forces.def"
check "a force without its symbolic maths: diff/dynamics.c names add_TWIST" \
    fails_naming diff/dynamics.c "add_TWIST"
check "a force without its generic maths: generic_dynamics.c names apply_TWIST" \
    fails_naming eval/generic_dynamics.c "apply_TWIST"
check "a force without its builder: model/dynamics.c names build_TWIST" \
    fails_naming model/dynamics.c "build_TWIST"

suite_end
