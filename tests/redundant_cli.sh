#!/bin/sh
# tests/redundant_cli.sh MECHC - more holonomic rows than coordinates from the
# outside: `run`, `run --forces`, `sim` and `check` name the redundant rows
# once (as `info` does), run on the others and check them all; a redundancy
# that contradicts the other rows, or leaves a degree of freedom undriven, is
# an error that names them. Values are in tests/test_redundant.c.
#
#   sh tests/redundant_cli.sh build/mechc
#
# The last line is "redundant_cli: N passed, M failed"; the exit status is
# non-zero on any failure.
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin redundant_cli "${1:-build/mechc}"

fb=$ex/four_bar_spatial_redundant.mech
rows="redundant rows: O4.z (joint O4), O4.f (joint O4), O4.g (joint O4)"

# ---- info names them; run names the same, once, and runs ----
run info "$fb"
check "info: the redundant rows" out_has "  $rows"
run run "$fb" --csv "$tmp/fb.csv"
check "run: exit 0" status_is 0
check "run: the note" err_has "four_bar_spatial_redundant.mech: note: 24 holonomic rows for 21 coordinates: $rows; solved on the other 21 rows, the redundant ones checked at every state"
check "run: said once" sh -c '[ "$(grep -c "redundant rows" "$1")" = 1 ]' _ "$tmp/err"
check "run: no error or warning" sh -c '! grep -q "error\|warning" "$1"' _ "$tmp/err"
run run "$ex/four_bar.mech" --csv "$tmp/planar.csv"
same_as_planar() {
    for t in 0 0.25 0.5 0.99; do
        for c in coupler.x coupler.y; do
            a=$(csv_value_at "$t" "$c" "$tmp/fb.csv") b=$(csv_value_at "$t" "$c" "$tmp/planar.csv")
            awk -v a="$a" -v b="$b" 'BEGIN { d = a - b; exit !(a != "" && d < 1e-10 && d > -1e-10) }' \
                || return 1
        done
    done
}
check "run: the coupler point is four_bar.mech's" same_as_planar
run run "$fb" --linear sparse --steps 10
check "run --linear sparse: exit 0" status_is 0
check "run --linear sparse: the note" err_has "$rows"
run run "$fb" --engine generic --steps 10
check "run --engine generic: exit 0" status_is 0

# ---- the Bricard linkage driven: its limit, as any driven mechanism's ----
{ cat "$ex/bricard.mech"; echo "driver D: angle(J1) = t"; } > "$tmp/bricard_driven.mech"
run run "$tmp/bricard_driven.mech" --t1 3 --steps 30
check "driven Bricard: exit 1" status_is 1
check "driven Bricard: its redundant row" err_has "note: 36 holonomic rows for 35 coordinates: redundant row: J6.g (joint J6);"
check "driven Bricard: the limit" err_has "error: t = 2.75625: the mechanism cannot reach the driven position: driver 'D' pushes it past a limit position"
check "driven Bricard: the states before it" err_has "note: the 28 states before t = 2.75625 are written"

# ---- parallelogram_redundant.mech with a driver (13 rows for 12) runs ----
{ cat "$ex/parallelogram_redundant.mech"; echo "driver drive: c1.phi = pi/3 + t"; } > "$tmp/par.mech"
run run "$tmp/par.mech" --steps 10
check "driven parallelogram: exit 0" status_is 0
check "driven parallelogram: A2.y redundant" err_has "note: 13 holonomic rows for 12 coordinates: redundant row: A2.y (joint A2);"

# ---- contradicting redundancies: exit 1, named, with the time ----
sed 's/ground(d, 0, 0)/ground(d, 0, 1e-3)/' "$fb" > "$tmp/lifted.mech"
run run "$tmp/lifted.mech"
check "O4 lifted: exit 1" status_is 1
check "O4 lifted: says which row and why" err_has "lifted.mech: error: t = 0: the redundant rows contradict the others: row O4.z (joint O4) is violated at the position level (residual 0.001, tolerance 1e-06), so no motion satisfies every row; $rows"
{ cat "$fb"; echo "driver D2: angle(O2) = 2*omega*t"; } > "$tmp/twice.mech"
run run "$tmp/twice.mech"
check "driven twice: exit 1" status_is 1
check "driven twice: at the velocity level" err_has "error: t = 0: the redundant rows contradict the others: row D2 (joint D2) is violated at the velocity level"

# ---- redundant rows, and a degree of freedom not driven: exit 2 ----
grep -v '^driver' "$fb" > "$tmp/free.mech"
run run "$tmp/free.mech"
check "undriven: exit 2" status_is 2
check "undriven: says so, naming the redundant rows" err_has "error: 1 degree of freedom is not driven (21 coordinates, 23 rows of which 3 are redundant: O4.z (joint O4), O4.f (joint O4), O4.g (joint O4)): add a driver"

# ---- dynamics: sim and run --forces ----
masses='mass crank   m = 1    J = (0.01, 1/12, 1/12)
mass coupler m = 3    J = (0.01, 3*b^2/12, 3*b^2/12)
mass rocker  m = 2.5  J = (0.01, 2.5*c^2/12, 2.5*c^2/12)
gravity (0, -9.81, 0)'
{ cat "$tmp/free.mech"; echo "$masses"; } > "$tmp/free_mass.mech"
run sim "$tmp/free_mass.mech" --steps 4
check "sim: exit 0" status_is 0
check "sim: the rows" err_has "note: 23 holonomic rows for 21 coordinates: $rows; solved on the other 20 rows"
check "sim: the reactions not unique" err_has "note: the reactions of the redundant rows and of the rows they repeat are not unique: reported as the independent rows' (0 on O4.z (joint O4), O4.f (joint O4), O4.g (joint O4))"
check "sim: the states" out_lines 6
{ cat "$fb"; echo "$masses"; } > "$tmp/driven_mass.mech"
run run "$tmp/driven_mass.mech" --forces --steps 4 --csv -
check "run --forces: exit 0" status_is 0
check "run --forces: the reactions not unique" err_has "note: the reactions of the redundant rows and of the rows they repeat are not unique"
check "run --forces: every row's multiplier" out_has "lambda(O4.g)"

# ---- check: around the configuration assembled on the kept rows ----
run check "$fb" --samples 3 --no-aot
check "check: exit 0" status_is 0
check "check: assembled" out_has "3 samples around the configuration assembled at t = 0"
check "check: the note" err_has "$rows"

suite_end
