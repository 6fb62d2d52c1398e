#!/bin/sh
# tests/sim_convergence_cli.sh MECHC - `mechc sim`'s error against exact solutions falls with its tolerance.
#
#   sh tests/sim_convergence_cli.sh build/mechc
#
# IFToMM A01 (simple pendulum, examples/a01_pendulum.mech) and A02 (the N
# four-bar, sh examples/a02_four_bar.sh 2: 15 coordinates, the dense path
# and the sparse one, through 14 flat positions where Phi_q loses two
# ranks) over 20 s with 20 output steps (the integrator's steps then
# follow its tolerance, not the outputs), rk8pd at --rtol = --atol =
# 1e-4, 1e-5, ..., 1e-9: the largest error of P1 (A01: Jacobi elliptic
# functions) and of B0's position and velocity (A02: the one-angle
# equation of the parallelogram branch, sh examples/a02_four_bar.sh
# --error) over the 21 states must fall at least fivefold per decade.
# Before the fix of doc/dynamics.md, "Step control near singular
# positions", A02's rose past 1e-8. Then the defaults on the benchmarks'
# own spans: A01 over 2000 s within 1e-5 at every state, A02 N = 2 with 400
# outputs within 1e-7. A02 N = 40 and the CPU times are bench/dynamics.sh's.
# The last line is "sim_convergence_cli: N passed, M failed".
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin sim_convergence_cli "${1:-build/mechc}"

tols="1e-4 1e-5 1e-6 1e-7 1e-8 1e-9"

# a01_error CSV: the largest |P1 - exact| over the rows (Abramowitz & Stegun
# 16.4: sn by the arithmetic-geometric mean, dn = sqrt(1 - m sn^2); phi from the downward
# vertical, sin(phi/2) = k sn(K - w t | 1/2), P1 = (2k sn dn, 2k^2 sn^2 - 1)).
a01_error() {
    awk -F, '
    function asin_(x) { return atan2(x, sqrt(1 - x * x)) }
    function jacobi(u, m,   a, c, b, n, i, ph, tb) {
        a[0] = 1; b = sqrt(1 - m); c[0] = sqrt(m); n = 0
        while (c[n] > 1e-17 && n < 40) {
            a[n + 1] = (a[n] + b) / 2; c[n + 1] = (a[n] - b) / 2; tb = sqrt(a[n] * b); b = tb; n++
        }
        KM = atan2(0, -1) / (2 * a[n])
        ph = 2 ^ n * a[n] * u
        for (i = n; i > 0; i--)
            ph = (ph + asin_(c[i] / a[i] * sin(ph))) / 2
        SN = sin(ph); DN = sqrt(1 - m * SN * SN)
    }
    BEGIN { m = 0.5; k = sqrt(m); w = sqrt(9.81); jacobi(0, m); K = KM }
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    {
        jacobi(K - w * $1, m)
        d = $(c["P1.x"]) - 2 * k * SN * DN; if (d < 0) d = -d; if (d > worst) worst = d
        d = $(c["P1.y"]) - (2 * k * k * SN * SN - 1); if (d < 0) d = -d; if (d > worst) worst = d
    }
    END { printf "%.3g\n", worst }' "$1"
}

# falls NAME ERRORS...: each error at least 5 times the next (one per tolerance).
falls() {
    name=$1
    shift
    if echo "$*" | awk '{ for (i = 1; i < NF; i++) if (!($i >= 5 * $(i + 1))) exit 1 }'; then
        ok
    else
        bad "$name: the error against the exact solution falls fivefold per decade of --rtol ($tols): $*"
    fi
}

# errors WHICH FILE [OPTION...]: the error at each tolerance, or "x" where sim failed.
errors() {
    which=$1
    file=$2
    shift 2
    for r in $tols; do
        if "$mechc" sim "$file" --t1 20 --steps 20 --rtol "$r" --atol "$r" --csv "$tmp/c.csv" "$@" \
            2> "$tmp/err"; then
            case $which in
                a01) a01_error "$tmp/c.csv" ;;
                *) sh "$ex/a02_four_bar.sh" --error "$which" "$tmp/c.csv" ;;
            esac
        else
            echo x
        fi
    done | tr '\n' ' '
}

falls "a01" $(errors a01 "$ex/a01_pendulum.mech")

sh "$ex/a02_four_bar.sh" 2 "$tmp/a02.mech"
qd=$(sh "$ex/a02_four_bar.sh" --qd 2)
falls "a02, N = 2" $(errors 2 "$tmp/a02.mech" --qd "$qd")
falls "a02, N = 2, --linear sparse" $(errors 2 "$tmp/a02.mech" --qd "$qd" --linear sparse)

# The defaults keep the benchmarks' targets (doc/dynamics.md,
# "Step control near singular positions"): A01 over its 2000 s within 1e-5
# at every one of the 4001 states (1.06e-5 at the old default 1e-10), A02
# N = 2 with its 400 output steps within 1e-7.
# within NAME ERROR LIMIT: ERROR (from the CSV) at most LIMIT
within() {
    if awk -v e="$2" -v l="$3" 'BEGIN { exit !(e != "" && e <= l) }'; then
        ok
    else
        bad "$1: largest error ${2:-(sim failed)} against the exact solution, not within $3"
    fi
}
e=
if "$mechc" sim "$ex/a01_pendulum.mech" --t1 2000 --steps 4000 --csv "$tmp/c.csv" 2> "$tmp/err"; then
    e=$(a01_error "$tmp/c.csv")
fi
within "a01 at the defaults, 2000 s" "$e" 1e-5
e=
if "$mechc" sim "$tmp/a02.mech" --t1 20 --steps 400 --qd "$qd" --csv "$tmp/c.csv" 2> "$tmp/err"; then
    e=$(sh "$ex/a02_four_bar.sh" --error 2 "$tmp/c.csv")
fi
within "a02, N = 2, at the defaults, 400 outputs" "$e" 1e-7

suite_end
