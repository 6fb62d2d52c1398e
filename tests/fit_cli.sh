#!/bin/sh
# tests/fit_cli.sh MECHC - design parameters from the outside: `mechc fit`
# (exit statuses, the CSV's FILE:LINE:COL errors with their caret, the
# Freudenstein case's JSON; the examples freudenstein, coupler_synthesis,
# with its curve drawn, and stewart_calibration), `--design` on other
# commands, `run --sens` (its refusals, its columns against finite
# differences of runs at --design p +- h), and `gen` of a design file built
# by cc -Werror and run: PREFIX_phi_p against central differences of
# PREFIX_phi in p.
#
#   sh tests/fit_cli.sh build/mechc
#
# The last line is "fit_cli: N passed, M failed". Checks needing cc are
# skipped (and say so) when it is missing or under MECHC_SKIP_GCC_ONLY.
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin fit_cli "${1:-build/mechc}"

# near A B TOL: |A - B| <= TOL (1 + |B|); says the error on stderr when not.
near() {
    awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN {
        d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b
        ok = a != "" && b != "" && d <= tol * (1 + s)
        if (!ok) printf "  got %s, want %s (tolerance %s)\n", a, b, tol > "/dev/stderr"
        exit !ok }'
}

# A four-bar of ground link d = 3 with designed crank a, coupler b and
# rocker c, driven by crank.phi = t (Freudenstein's function generator).
cat > "$tmp/fr.mech" <<'EOF'
mechanism freudenstein
design a = 1
design b = 3
design c = 2.5
param d = 3
body crank   x = 0.44  y = 0.24  phi = 0.5
body coupler x = 1.9   y = 1.4   phi = 0.9
body rocker  x = 2.8   y = 1.24  phi = 1.7
revolute O2: ground(0, 0)     crank(-a/2, 0)
revolute A:  crank(a/2, 0)    coupler(-b/2, 0)
revolute B:  coupler(b/2, 0)  rocker(c/2, 0)
revolute O4: ground(d, 0)     rocker(-c/2, 0)
driver input: crank.phi = t
output P: coupler(0.5, 0.2)
EOF
fr=$tmp/fr.mech

# psi = rocker.phi of the linkage a = 1.2, b = 2.8, c = 2.3 at theta = 0.5,
# 1, 1.5 (the closed form of Freudenstein's equation); the closed-form
# solution of the linear equations in K1, K2, K3 through them is that
# linkage itself.
cat > "$tmp/fr.csv" <<'EOF'
t,rocker.phi
0.5,1.4525472019214092
1,1.5118730782920675
1.5,1.7153735894075408
EOF

# ---- mechc fit -----------------------------------------------------------
run_mechc fit "$fr" --data "$tmp/fr.csv" --json
check "fit --json: exit 0" status_is 0
check "fit --json: \"ok\": true" out_has '"ok": true'
for pair in a:1.2 b:2.8 c:2.3; do
    name=${pair%%:*} want=${pair#*:}
    got=$(sed -n "s/.*\"name\": \"$name\", \"start\": [^,]*, \"estimate\": \([^,]*\),.*/\1/p" "$tmp/out")
    check "fit --json: $name = $want" near "$got" "$want" 1e-12
done
check "fit --json: the design" out_has '"design": {"a": '

run_mechc fit "$fr" --data "$tmp/fr.csv"
check "fit: exit 0" status_is 0
check "fit: converged" out_has "converged:"
check "fit: the --design line" out_has "design: --design a="
# the design it prints, given back to run, meets the data
design=$(sed -n 's/^design: --design //p' "$tmp/out")
run_mechc run "$fr" --design "$design" --t0 0.5 --t1 1.5 --steps 2 --tol 1e-13 --csv "$tmp/fitted.csv"
check "fit's design, run: rocker.phi at t = 1" \
    near "$(csv_value_at 1 rocker.phi "$tmp/fitted.csv")" 1.5118730782920675 1e-12

run_mechc fit "$fr" --data "$tmp/fr.csv" --max-iter 1
check "fit, no convergence: exit 1" status_is 1
check "fit, no convergence: said" err_has "no convergence in 1 iterations"

run_mechc fit "$fr" --data "$tmp/fr.csv" --design b=0.1 --json
check "fit from a design that does not close: exit 1" status_is 1
check "fit from a design that does not close: JSON ok and error alone" \
    grep -q '^{"ok": false, "error": "at the starting design: t = 0.5: could not assemble.*"}$' "$tmp/out"
check "fit from a design that does not close: said" err_has "error: fit: at the starting design"
run_mechc fit "$fr" --data "$tmp/fr.csv" --design b=0.1
check "fit from a design that does not close: no report" out_empty

run_mechc fit "$fr"
check "fit without --data: exit 2" status_is 2
check "fit without --data: said" err_has "--data FILE.csv is required"

printf 't,rocker.phi\n0.5,1.45\n1,1.4x\n' > "$tmp/bad.csv"
run_mechc fit "$fr" --data "$tmp/bad.csv"
check "fit, a bad number: exit 2" status_is 2
check "fit, a bad number: FILE:LINE:COL" err_has "$tmp/bad.csv:3:3: error: '1.4x' is not a finite number"
check "fit, a bad number: the line" err_has "    1,1.4x"
check "fit, a bad number: the caret" err_matches '^      \^$'

# a NUL byte ended the field there: "1.4<NUL>" was read as 1.4 and the fit
# ran (exit 1, no convergence); now refused where it is (the outside corpus)
printf 't,rocker.phi\n0.5,1.4\000\n1,1.6\n1.5,1.7\n' > "$tmp/nul.csv"
run_mechc fit "$fr" --data "$tmp/nul.csv"
check "fit, a NUL byte: exit 2" status_is 2
check "fit, a NUL byte: FILE:LINE:COL" err_has "$tmp/nul.csv:2:8: error: a NUL byte: a data file is text (is this a binary file?)"
check "fit, a NUL byte: the caret" err_matches '^           \^$'
run_mechc info "$ex/four_bar.mech" --state "$tmp/nul.csv"
check "info --state, a NUL byte: exit 2" status_is 2
check "info --state, a NUL byte: FILE:LINE:COL" err_has "$tmp/nul.csv:2:8: error: a NUL byte"

printf 'rocker.phi\n1.45\n' > "$tmp/not.csv"
run_mechc fit "$fr" --data "$tmp/not.csv"
check "fit, no t column: exit 2" status_is 2
check "fit, no t column: said" err_has "not.csv:1:1: error: the header has no column t"

printf 't,rocker.phi\n0.5,1.45\n' > "$tmp/one.csv"
run_mechc fit "$fr" --data "$tmp/one.csv"
check "fit, one value for three: exit 2" status_is 2
check "fit, one value for three: said" err_has "1 measured value cannot determine 3 parameters"

printf 't,crank.x\n0.5,0.5\n1,0.3\n1.5,0.05\n' > "$tmp/crank.csv"
run_mechc fit "$fr" --data "$tmp/crank.csv" --vary a,b
check "fit, b not identified: exit 2" status_is 2
check "fit, b not identified: named" err_has "do not identify the combination +1 b"
run_mechc fit "$fr" --data "$tmp/crank.csv" --vary a
check "fit, a alone: exit 0" status_is 0

run_mechc fit "$fr" --data "$tmp/fr.csv" --vary a,zz
check "fit --vary zz: exit 2" status_is 2
check "fit --vary zz: said" err_has "'zz' is not a design parameter"
for b in a=2:1 a=:1 a=-1: a=x:1 a=0:1x zz=0:1; do
    run_mechc fit "$fr" --data "$tmp/fr.csv" --bound "$b"
    check "fit --bound $b: exit 2" status_is 2
    check "fit --bound $b: said" err_has "--bound takes P=LO:HI"
done
run_mechc fit "$fr" --data "$tmp/fr.csv" --bound a=0.9:1.1 --json
check "fit --bound a=0.9:1.1: exit 0" status_is 0
a=$(sed -n 's/.*"name": "a", "start": [^,]*, "estimate": \([^,]*\),.*/\1/p' "$tmp/out")
check "fit --bound a=0.9:1.1: a on the bound" near "$a" 1.1 1e-9
run_mechc fit "$ex/four_bar.mech" --data "$tmp/fr.csv"
check "fit, no design parameters: exit 2" status_is 2

# ---- the examples ----------------------------------------------------------
# examples/freudenstein.mech: Freudenstein's linear equations through its
# three pairs give a = 1.2, b = 2.8, c = 2.3 (tests/test_fit.c solves them).
run_mechc fit "$ex/freudenstein.mech" --data "$ex/freudenstein.csv" --json
check "freudenstein example: exit 0" status_is 0
for pair in a:1.2 b:2.8 c:2.3; do
    got=$(sed -n "s/.*\"name\": \"${pair%%:*}\", \"start\": [^,]*, \"estimate\": \([^,]*\),.*/\1/p" "$tmp/out")
    check "freudenstein example: ${pair%%:*}" near "$got" "${pair#*:}" 1e-12
done
# the same fit through the other engines
for e in generic aot; do
    if [ $e = aot ] && ! have cc; then skip "no cc: fit --engine aot"; continue; fi
    run_mechc fit "$ex/freudenstein.mech" --data "$ex/freudenstein.csv" --json --engine $e
    got=$(sed -n 's/.*"name": "b", "start": [^,]*, "estimate": \([^,]*\),.*/\1/p' "$tmp/out")
    check "freudenstein example, --engine $e: b" near "$got" 2.8 1e-12
done
# examples/coupler_synthesis.mech: the linkage its header names, zero
# residual, and the coupler curve of the result drawn with run --svg.
run_mechc fit "$ex/coupler_synthesis.mech" --data "$ex/coupler_synthesis.csv"
check "coupler_synthesis example: exit 0" status_is 0
for pair in xa:0 ya:0 xd:4 yd:0.5 a:1.2 b:3.5 c:3 px:1.5 py:1; do
    got=$(awk -v n="${pair%%:*}" '$1 == n && NF == 4 { print $3 }' "$tmp/out")
    check "coupler_synthesis example: ${pair%%:*}" near "$got" "${pair#*:}" 1e-9
done
design=$(sed -n 's/^design: --design //p' "$tmp/out")
run_mechc run "$ex/coupler_synthesis.mech" --design "$design" --t0 0.4 --t1 2 --steps 4 \
    --tol 1e-13 --csv "$tmp/curve.csv" --svg "$tmp/curve.svg"
check "coupler_synthesis example: run at the result" status_is 0
check "coupler_synthesis example: P.x at t = 0.8" \
    near "$(csv_value_at 0.8 P.x "$tmp/curve.csv")" 1.1409600883056423 1e-12
check "coupler_synthesis example: P.y at t = 2" \
    near "$(csv_value_at 2 P.y "$tmp/curve.csv")" 2.7574562416530224 1e-12
check "coupler_synthesis example: the SVG" grep -q '</svg>' "$tmp/curve.svg"
run_mechc fit "$ex/stewart_calibration.mech" --data "$ex/stewart_calibration.csv" --json
check "stewart_calibration example: exit 0" status_is 0
check "stewart_calibration example: ok" out_has '"ok": true'

# ---- --design --------------------------------------------------------------
run_mechc eval "$fr" --design zz=1
check "eval --design zz=1: exit 2" status_is 2
check "eval --design zz=1: said" err_has "'zz' is not a design parameter of"
run_mechc eval "$fr" --design a=nan
check "eval --design a=nan: exit 2" status_is 2
check "eval --design a=nan: said" err_has "the value of 'a' must be a finite number, not 'nan'"
run_mechc eval "$fr" --design a
check "eval --design a: exit 2" status_is 2
run_mechc eval "$ex/four_bar.mech" --design a=1
check "eval --design on a file without design parameters: exit 2" status_is 2
check "eval --design on a file without design parameters: said" err_has "has no design parameters"
# one parameter given twice was taken at its last value, silently (the
# outside corpus): refused, whether in one list or two options
run_mechc run "$fr" --design a=1,a=2 --steps 2
check "run --design a=1,a=2: exit 2" status_is 2
check "run --design a=1,a=2: said" err_has "mechc run: error: --design: 'a' is given more than once"
run_mechc eval "$fr" --design a=1 --design b=2,a=1
check "eval --design a=1 --design b=2,a=1: exit 2" status_is 2
check "eval --design a=1 --design b=2,a=1: said" err_has "'a' is given more than once"
run_mechc eval "$fr" --design c=2.25 --design a=1.5 --json
check "eval --design twice: exit 0" status_is 0
check "eval --design twice: p" out_has '"p": [1.5, 3, 2.25]'
run_mechc run "$fr" --design a=1.2,b=2.8,c=2.3 --t0 0.5 --t1 1.5 --steps 2 --tol 1e-13 --csv "$tmp/true.csv"
check "run --design: exit 0" status_is 0
for pair in 0.5:1.4525472019214092 1:1.5118730782920675 1.5:1.7153735894075408; do
    check "run --design: rocker.phi at t = ${pair%%:*}" \
        near "$(csv_value_at "${pair%%:*}" rocker.phi "$tmp/true.csv")" "${pair#*:}" 1e-12
done

# ---- run --sens ------------------------------------------------------------
run_mechc run "$ex/four_bar.mech" --sens
check "run --sens without design parameters: exit 2" status_is 2
check "run --sens without design parameters: said" err_has "the file has no design parameters"
run_mechc run "$fr" --sens --forces
check "run --sens --forces: exit 2" status_is 2
check "run --sens --forces: said" err_has "--sens and --forces"

printf 'design r = 0.5\nbody w x = 0 y = 0.5 phi = 0\ndriver h: w.y = r\nvelocity roll: der(w.x) + r*der(w.phi) = 0\ndriver s: w.phi = t\n' \
    > "$tmp/wheel.mech"
run_mechc run "$tmp/wheel.mech" --sens
check "run --sens with a velocity-level row: exit 2" status_is 2
check "run --sens with a velocity-level row: said" err_has "this one has 1 velocity-level row"

# d(rocker.phi)/d(b) and d(dd(P.y))/d(a) against runs at b +- h, a +- h
run_mechc run "$fr" --sens --steps 4 --tol 1e-13 --csv "$tmp/sens.csv"
check "run --sens: exit 0" status_is 0
check "run --sens: its columns" \
    sh -c "head -1 '$tmp/sens.csv' | grep -q -F 'd(rocker.phi)/d(b),d(rocker.phi)/d(c),d(P.x)/d(a)'"
# --json: the same columns, "sens_columns", a row of "sens" per state
run_mechc run "$fr" --sens --steps 4 --tol 1e-13 --json
check "run --sens --json: exit 0" status_is 0
at=$(sed -n 's/.*"sens_columns": \[\([^]]*\)\].*/\1/p' "$tmp/out" | tr ',' '\n' \
     | grep -n -F '"d(rocker.phi)/d(b)"' | cut -d: -f1)
got=$(tr -d '\n' < "$tmp/out" | sed 's/.*"sens": \[\[//' | awk -F'\\], *\\[' '{ print $2 }' \
      | awk -F, -v c="$at" '{ print $c }' | tr -d ' ')
check "run --sens --json: d(rocker.phi)/d(b) at t = 0.25 as in the CSV" \
    near "$got" "$(csv_value_at 0.25 'd(rocker.phi)/d(b)' "$tmp/sens.csv")" 1e-15
for w in b=3.000001,b=2.999999 a=1.000001,a=0.999999; do
    run_mechc run "$fr" --design "${w%%,*}" --steps 4 --tol 1e-13 --csv "$tmp/plus.csv"
    run_mechc run "$fr" --design "${w#*,}" --steps 4 --tol 1e-13 --csv "$tmp/minus.csv"
    case $w in
        b*) col=rocker.phi sens="d(rocker.phi)/d(b)" ;;
        *) col="dd(P.y)" sens="d(dd(P.y))/d(a)" ;;
    esac
    for t in 0.25 0.75; do
        fd=$(awk -v p="$(csv_value_at $t "$col" "$tmp/plus.csv")" -v m="$(csv_value_at $t "$col" "$tmp/minus.csv")" \
            'BEGIN { printf "%.17g", (p - m) / 2e-6 }')
        check "run --sens: $sens at t = $t" near "$(csv_value_at $t "$sens" "$tmp/sens.csv")" "$fd" 1e-6
    done
done

# ---- gen: the written C of a design file ---------------------------------
run_mechc gen "$fr" -o "$tmp/fr.c"
check "gen of a design file: exit 0" status_is 0
check "gen: p in phi" grep -q -F 'void freudenstein_phi(const freudenstein_real *q, freudenstein_real t, const freudenstein_real *p, freudenstein_real *phi)' "$tmp/fr.c"
check "gen: FREUDENSTEIN_NP" grep -q '^#define FREUDENSTEIN_NP  *3' "$tmp/fr.c"
run_mechc gen "$fr" --design b=2.75
check "gen --design b=2.75: p0" sh -c "grep -A3 'freudenstein_p0\[FREUDENSTEIN_NP\] = {' '$tmp/out' | grep -q -x '    2.75,'"
if [ -n "${MECHC_SKIP_GCC_ONLY:-}" ]; then
    skip "MECHC_SKIP_GCC_ONLY: compiling the generated C"
elif have cc; then
    check "gen: cc -std=c99 -Wall -Wextra -Werror" \
        cc -std=c99 -Wall -Wextra -Werror -c "$tmp/fr.c" -o "$tmp/fr.o"
    run_mechc gen "$fr" --real float -o "$tmp/frf.c"
    check "gen --real float: cc -Werror -Wconversion -Wdouble-promotion" \
        cc -std=c99 -Wall -Wextra -Wpedantic -Werror -Wconversion -Wdouble-promotion -c "$tmp/frf.c" -o "$tmp/frf.o"
    # the file's own phi_p against central differences of its phi in p
    cat > "$tmp/main.c" <<'EOF'
#include <math.h>
#include <stdio.h>
#include <string.h>
void freudenstein_phi(const double *q, double t, const double *p, double *phi);
void freudenstein_phi_p(const double *q, double t, const double *p, double *phi_p);
extern const double freudenstein_p0[3];
int main(void)
{
    double q[9] = {0.4, 0.3, 0.6, 1.8, 1.5, 0.8, 2.9, 1.1, 1.6}, p[3], plus[9], minus[9], dp[27];
    double worst = 0, h = 1e-6;
    memcpy(p, freudenstein_p0, sizeof p);
    p[0] += 0.2, p[2] -= 0.2;
    freudenstein_phi_p(q, 0.3, p, dp);
    for (int j = 0; j < 3; j++) {
        double pj = p[j];
        p[j] = pj + h;
        freudenstein_phi(q, 0.3, p, plus);
        p[j] = pj - h;
        freudenstein_phi(q, 0.3, p, minus);
        p[j] = pj;
        for (int r = 0; r < 9; r++)
            worst = fmax(worst, fabs((plus[r] - minus[r]) / (2 * h) - dp[r * 3 + j]));
    }
    printf("%s %g\n", worst < 1e-8 ? "ok" : "bad", worst);
    return worst < 1e-8 ? 0 : 1;
}
EOF
    if cc -std=c99 -o "$tmp/main" "$tmp/main.c" "$tmp/fr.o" -lm 2> "$tmp/err"; then
        check "gen: the written phi_p is phi's difference in p" sh -c "'$tmp/main' > '$tmp/out'"
    else
        bad "gen: the written file links with a main"
    fi
else
    skip "no cc: compiling the generated C"
fi

# An engine's own error, not a stale one: emitting the aot engine's C once
# recorded "more than N operations" on every success, and that was what a
# missing compiler was reported as.
mkdir "$tmp/cache"
CC=mechc_no_such_cc XDG_CACHE_HOME=$tmp/cache run_mechc eval "$ex/four_bar.mech" --engine aot
check "aot without a compiler: exit 2" status_is 2
check "aot without a compiler: said" err_has "the aot engine needs a C compiler: 'mechc_no_such_cc'"

suite_end
